//! Light-facing triangles, silhouette edges and the shadow volume's geometry.
//!
//! For a light at `L` (point or spot) or travelling along `d` (directional), a
//! triangle with outward normal `n` and corner `a` faces the light when
//!
//! ```text
//! point, spot:  n . (L - a) > 0          directional:  n . (-d) > 0
//! ```
//!
//! An edge is on the silhouette when one of its two triangles faces the light and
//! the other does not; it is oriented as the light-facing triangle runs along it.
//! Points are extruded to infinity as homogeneous points with `w = 0`:
//!
//! ```text
//! point, spot:  p_inf = (p - L, 0)       directional:  p_inf = (d, 0)
//! ```
//!
//! The volume (Crow, *Shadow algorithms for computer graphics*, SIGGRAPH 1977; caps
//! and the infinite far plane after Everitt and Kilgard, *Practical and Robust
//! Stenciled Shadow Volumes for Hardware-Accelerated Rendering*, 2002) is closed and
//! outward-facing (counter-clockwise seen from outside):
//!
//! ```text
//! sides      per silhouette edge a -> b:  (a, a_inf, b_inf), (a, b_inf, b)
//!            (directional: the first triangle has no area and only (a, d_inf, b) is kept)
//! front cap  the light-facing triangles, as they are
//! back cap   the other triangles projected to infinity (point and spot lights; a
//!            directional light's volume closes in the single point d_inf)
//! ```
//!
//! Z-pass (the stencil counts volume faces in front of the visible surface) needs
//! the sides only and a camera outside every volume; z-fail (Carmack's reverse:
//! counts faces behind the surface) needs the caps as well and is right wherever
//! the camera is.

use alloc::vec::Vec;

use glam::{DVec3, Vec4};
use shadowmap_frustum::Light;

use crate::{EdgeMesh, VolumeError};

/// Where the light is, as the extrusion sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Source {
    /// Unit direction the light travels.
    Direction(DVec3),
    /// Position of a point or spot light (the cone does not limit visibility).
    Position(DVec3),
}

impl Source {
    fn new(light: &Light) -> Result<Self, VolumeError> {
        light.validate().map_err(VolumeError::InvalidLight)?;
        Ok(match *light {
            Light::Directional { direction } => Self::Direction(direction.as_dvec3().normalize()),
            Light::Spot { position, .. } | Light::Point { position, .. } => {
                Self::Position(position.as_dvec3())
            }
        })
    }

    fn faces(&self, corners: [DVec3; 3]) -> bool {
        let [a, b, c] = corners;
        let n = (b - a).cross(c - a);
        match *self {
            Self::Direction(d) => n.dot(-d) > 0.0,
            Self::Position(l) => n.dot(l - a) > 0.0,
        }
    }

    fn at_infinity(&self, p: DVec3) -> Vec4 {
        match *self {
            Self::Direction(d) => d.extend(0.0).as_vec4(),
            Self::Position(l) => (p - l).extend(0.0).as_vec4(),
        }
    }
}

/// The shadow volume of one closed mesh for one light, with its working buffers:
/// [`ShadowVolume::update`] clears and refills them, so a volume kept from frame to
/// frame allocates only while its buffers grow.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShadowVolume {
    /// Per triangle of the mesh: does it face the light?
    pub facing: Vec<bool>,
    /// Silhouette edges as welded vertex indices, oriented as their light-facing
    /// triangle runs along them.
    pub silhouette: Vec<[u32; 2]>,
    /// Triangle list (three homogeneous world-space vertices per triangle): the
    /// sides first ([`ShadowVolume::side_vertices`] of them), then the front cap,
    /// then the back cap.
    pub vertices: Vec<Vec4>,
    /// Number of leading entries of `vertices` that are the sides.
    pub side_vertices: usize,
}

impl ShadowVolume {
    /// Empty buffers.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            facing: Vec::new(),
            silhouette: Vec::new(),
            vertices: Vec::new(),
            side_vertices: 0,
        }
    }

    /// The side triangles: all a z-pass needs.
    #[must_use]
    pub fn sides(&self) -> &[Vec4] {
        &self.vertices[..self.side_vertices]
    }

    /// Sides and both caps: the closed volume a z-fail pass needs.
    #[must_use]
    pub fn closed(&self) -> &[Vec4] {
        &self.vertices
    }

    /// Recomputes facing, silhouette and geometry of `mesh` for `light`.
    ///
    /// # Errors
    /// [`VolumeError::InvalidLight`] for a light that fails validation (the
    /// buffers are left empty).
    pub fn update(&mut self, mesh: &EdgeMesh, light: &Light) -> Result<(), VolumeError> {
        self.facing.clear();
        self.silhouette.clear();
        self.vertices.clear();
        self.side_vertices = 0;
        let source = Source::new(light)?;
        self.facing.extend(
            mesh.triangles
                .iter()
                .map(|t| source.faces(t.map(|k| mesh.positions[k as usize]))),
        );
        silhouette_edges(mesh, &self.facing, &mut self.silhouette);
        let at = |k: u32| mesh.positions[k as usize];
        for &[a, b] in &self.silhouette {
            let (pa, pb) = (at(a), at(b));
            let (ia, ib) = (source.at_infinity(pa), source.at_infinity(pb));
            let (fa, fb) = (pa.extend(1.0).as_vec4(), pb.extend(1.0).as_vec4());
            if matches!(source, Source::Position(_)) {
                self.vertices.extend([fa, ia, ib]);
            }
            self.vertices.extend([fa, ib, fb]);
        }
        self.side_vertices = self.vertices.len();
        for (tri, &lit) in mesh.triangles.iter().zip(&self.facing) {
            if lit {
                self.vertices
                    .extend(tri.map(|k| at(k).extend(1.0).as_vec4()));
            }
        }
        if matches!(source, Source::Position(_)) {
            for (tri, &lit) in mesh.triangles.iter().zip(&self.facing) {
                if !lit {
                    self.vertices.extend(tri.map(|k| source.at_infinity(at(k))));
                }
            }
        }
        Ok(())
    }
}

/// Appends the silhouette edges of `mesh` for the per-triangle `facing` flags
/// (oriented as the light-facing triangle runs along them) to `out`. Flags past
/// the end of `facing` count as not facing.
pub fn silhouette_edges(mesh: &EdgeMesh, facing: &[bool], out: &mut Vec<[u32; 2]>) {
    let lit = |t: u32| facing.get(t as usize).copied().unwrap_or(false);
    for e in &mesh.edges {
        let [a, b] = e.vertices;
        match (lit(e.triangles[0]), lit(e.triangles[1])) {
            (true, false) => out.push([a, b]),
            (false, true) => out.push([b, a]),
            _ => {}
        }
    }
}
