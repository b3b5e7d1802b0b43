use glam::{DMat4, DVec2, DVec3, Mat4, Vec3, Vec4};

use crate::math;

/// Texture coordinates from WebGPU clip coordinates: `u = x/2 + 1/2`, `v = 1/2 - y/2`
/// (texture `v` grows downward), depth unchanged.
pub const UV_FROM_CLIP: Mat4 = Mat4::from_cols(
    Vec4::new(0.5, 0.0, 0.0, 0.0),
    Vec4::new(0.0, -0.5, 0.0, 0.0),
    Vec4::new(0.0, 0.0, 1.0, 0.0),
    Vec4::new(0.5, 0.5, 0.0, 1.0),
);

/// Where a world point lands in a shadow map: texture coordinates, depth and layer.
///
/// `f64` so that the evaluation harness can take accurate Jacobians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSample {
    /// Texture coordinates, `[0, 1]²` inside the map, `v` down.
    pub uv: DVec2,
    /// Depth stored in the map, `[0, 1]` inside the depth range (reversed if the
    /// technique uses reversed-Z).
    pub depth: f64,
    /// Array layer (cascade index, paraboloid side); 0 for single maps.
    pub layer: u32,
}

/// The one trait worth having: a technique maps a world point to where it is stored
/// in the shadow map, so the evaluation harness and the backend treat every
/// technique alike.
pub trait ShadowMapping {
    /// The sample for a world point, `None` where the technique does not cover it
    /// (behind a perspective light, beyond the last cascade, ...).
    fn map_point(&self, world: DVec3) -> Option<ShadowSample>;
}

/// Which way is "toward the light" for depth bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightDirection {
    /// A directional light; the vector is the (unit) direction the light travels.
    Directional(Vec3),
    /// A positional light at this world position.
    Position(Vec3),
}

/// The matrices of a matrix-based shadow technique (uniform, one cascade, spot,
/// LiSPSM, XPSM, TSM).
///
/// `clip_from_world` renders the depth pass; `uv_from_world` is
/// [`UV_FROM_CLIP`] times it, for the lookup (divide by `w` for perspective
/// techniques).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowTransform {
    /// The light's frame: light looks down `-Z`.
    pub light_from_world: Mat4,
    /// Depth pass, WebGPU clip space.
    pub clip_from_world: Mat4,
    /// Lookup, texture space (`uv`, depth, `w`).
    pub uv_from_world: Mat4,
    /// Whether depth runs 1 (near) to 0 (far).
    pub reversed_z: bool,
    /// Where the light is, for bias.
    pub light: LightDirection,
}

impl ShadowTransform {
    /// The transform for a depth-pass matrix; computes `uv_from_world`.
    #[must_use]
    pub fn new(
        light_from_world: Mat4,
        clip_from_world: Mat4,
        reversed_z: bool,
        light: LightDirection,
    ) -> Self {
        Self {
            light_from_world,
            clip_from_world,
            uv_from_world: UV_FROM_CLIP * clip_from_world,
            reversed_z,
            light,
        }
    }

    /// Texture coordinates and depth of a world point (`None` behind a perspective
    /// light, where `w <= 0`).
    #[must_use]
    pub fn project(&self, world: Vec3) -> Option<ShadowSample> {
        project_dmat(&self.uv_from_world.as_dmat4(), world.as_dvec3())
    }

    /// The unit direction toward the light at `world`.
    #[must_use]
    pub fn toward_light(&self, world: Vec3) -> Vec3 {
        match self.light {
            LightDirection::Directional(d) => -d.normalize_or_zero(),
            LightDirection::Position(p) => (p - world).normalize_or_zero(),
        }
    }

    /// The change in stored depth when `world` moves `world_bias` units toward the
    /// light (negative for standard depth, positive for reversed-Z), evaluated through
    /// the full projective mapping, so it is exact for warped techniques too.
    #[must_use]
    pub fn depth_bias(&self, world: Vec3, world_bias: f32) -> Option<f32> {
        let m = self.uv_from_world.as_dmat4();
        let p = world.as_dvec3();
        let moved = p + self.toward_light(world).as_dvec3() * f64::from(world_bias);
        let a = project_dmat(&m, p)?;
        let b = project_dmat(&m, moved)?;
        let bias = (b.depth - a.depth) as f32;
        bias.is_finite().then_some(bias)
    }

    /// World size of one texel at `world` for a map of `resolution²` texels: the
    /// largest extent of the texel's footprint, `1 / (resolution * s_min)` with
    /// `s_min` the smaller singular value of the 2x3 Jacobian `d uv / d world`. Use it
    /// for normal-offset bias. `None` where the mapping is degenerate.
    #[must_use]
    pub fn texel_world_size(&self, world: Vec3, resolution: u32) -> Option<f32> {
        let s = uv_jacobian_singular_values(&self.uv_from_world.as_dmat4(), world.as_dvec3())?;
        let size = 1.0 / (f64::from(resolution) * s.1);
        (size.is_finite() && size > 0.0).then_some(size as f32)
    }
}

impl ShadowMapping for ShadowTransform {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        project_dmat(&self.uv_from_world.as_dmat4(), world)
    }
}

/// Whether an `f32` matrix is finite and invertible with rows that `f32` can tell
/// apart, for world coordinates of magnitude up to `world_scale`: a nonzero
/// determinant, and no two rows of `m * diag(s, s, s, 1)` (s = `world_scale`) within
/// `1e-6` rad of parallel. That is the failure `f32` rounding produces, e.g. a depth
/// row equal to the `w` row for a tiny near plane far from the origin; scaling by the
/// world's magnitude keeps the test independent of the world's units.
pub fn is_invertible(m: &Mat4, world_scale: f32) -> bool {
    let a = m.to_cols_array();
    if !a.iter().all(|x| x.is_finite()) {
        return false;
    }
    let d = a.map(f64::from);
    let s = f64::from(world_scale.abs()).max(f64::MIN_POSITIVE);
    // Row `r` of the column-major matrix is `d[r], d[4 + r], d[8 + r], d[12 + r]`.
    let rows: [glam::DVec4; 4] =
        core::array::from_fn(|r| glam::DVec4::new(d[r] * s, d[4 + r] * s, d[8 + r] * s, d[12 + r]));
    let norms = rows.map(glam::DVec4::length_squared);
    if norms.contains(&0.0) {
        return false;
    }
    for i in 0..4 {
        for j in i + 1..4 {
            let dot = rows[i].dot(rows[j]);
            // sin² of the angle between the rows.
            if 1.0 - dot * dot / (norms[i] * norms[j]) < 1e-12 {
                return false;
            }
        }
    }
    let det = DMat4::from_cols_array(&d).determinant();
    det != 0.0 && det.is_finite()
}

pub(crate) fn project_dmat(uv_from_world: &DMat4, p: DVec3) -> Option<ShadowSample> {
    let h = *uv_from_world * p.extend(1.0);
    if !(h.w > 0.0 && h.is_finite()) {
        return None;
    }
    Some(ShadowSample {
        uv: DVec2::new(h.x / h.w, h.y / h.w),
        depth: h.z / h.w,
        layer: 0,
    })
}

/// Singular values `(s_max, s_min)` of `d(uv)/d(world)` for a projective map.
pub(crate) fn uv_jacobian_singular_values(m: &DMat4, p: DVec3) -> Option<(f64, f64)> {
    let h = *m * p.extend(1.0);
    if !(h.w > 0.0 && h.is_finite()) {
        return None;
    }
    let row = |r: usize| DVec3::new(m.x_axis[r], m.y_axis[r], m.z_axis[r]);
    let (rx, ry, rw) = (row(0), row(1), row(3));
    let w2 = h.w * h.w;
    let du = (rx * h.w - rw * h.x) / w2;
    let dv = (ry * h.w - rw * h.y) / w2;
    // Eigenvalues of J J^T (2x2, symmetric).
    let (a, b, c) = (du.dot(du), du.dot(dv), dv.dot(dv));
    let mean = 0.5 * (a + c);
    let disc = math::sqrt((0.25 * (a - c) * (a - c) + b * b).max(0.0));
    let (l1, l2) = (mean + disc, (mean - disc).max(0.0));
    let (s1, s2) = (math::sqrt(l1), math::sqrt(l2));
    (s1.is_finite() && s2 > 0.0).then_some((s1, s2))
}
