//! Triangle meshes and the evaluation scenes, built in code and deterministic for a seed.
//!
//! Every triangle of a [`Scene`] both casts and receives shadows. World units are
//! metres, `y` up. The scenes stay under 20k triangles so that the CPU reference
//! rasterizer and the ray caster stay fast.
//!
//! # Example
//!
//! ```
//! use shadowmap_eval::scene::Scene;
//!
//! let city = Scene::city_block(7);
//! assert!(city.mesh.triangle_count() < 20_000);
//! let bounds = city.scene_bounds().unwrap();
//! assert!(bounds.receivers.size().x > 200.0);
//! // Same seed, same scene.
//! assert_eq!(city.mesh.positions, Scene::city_block(7).mesh.positions);
//! ```

use glam::{DVec3, Vec3};
use shadowmap_frustum::{Aabb, SceneBounds};

use crate::EvalError;

/// An indexed triangle mesh in world space (`f64`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles as indices into `positions`.
    pub indices: Vec<[u32; 3]>,
}

impl Mesh {
    /// An empty mesh.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            positions: Vec::new(),
            indices: Vec::new(),
        }
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The corners of triangle `i`.
    ///
    /// # Panics
    /// If `i >= triangle_count()` or the mesh fails [`Mesh::validate`].
    #[must_use]
    pub fn triangle(&self, i: usize) -> [DVec3; 3] {
        self.indices[i].map(|k| self.positions[k as usize])
    }

    /// Every triangle's corners, in index order.
    pub fn triangles(&self) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        self.indices
            .iter()
            .map(|t| t.map(|k| self.positions[k as usize]))
    }

    /// The triangles with `f32` corners, as the depth passes (GPU and CPU) and the
    /// caster subdivisions take them.
    #[must_use]
    pub fn triangles_f32(&self) -> Vec<[glam::Vec3; 3]> {
        self.triangles().map(|t| t.map(DVec3::as_vec3)).collect()
    }

    /// Checks that every position is finite and every index is in range.
    ///
    /// # Errors
    /// [`EvalError::InvalidMesh`] naming the first bad vertex or triangle.
    pub fn validate(&self) -> Result<(), EvalError> {
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(EvalError::InvalidMesh {
                message: format!("vertex {i} is not finite"),
            });
        }
        let n = self.positions.len();
        if let Some(i) = self
            .indices
            .iter()
            .position(|t| t.iter().any(|&k| k as usize >= n))
        {
            return Err(EvalError::InvalidMesh {
                message: format!("triangle {i} indexes past the {n} vertices"),
            });
        }
        Ok(())
    }

    /// Bounds of the vertices that triangles use, rounded outward to `f32`; `None`
    /// for a mesh without triangles or with a non-finite vertex.
    #[must_use]
    pub fn bounds(&self) -> Option<Aabb> {
        let mut min = DVec3::INFINITY;
        let mut max = DVec3::NEG_INFINITY;
        for t in &self.indices {
            for &k in t {
                let p = *self.positions.get(k as usize)?;
                min = min.min(p);
                max = max.max(p);
            }
        }
        if self.indices.is_empty() || !(min.is_finite() && max.is_finite()) {
            return None;
        }
        let aabb = Aabb::new(round_down(min), round_up(max));
        aabb.is_finite().then_some(aabb)
    }

    /// Appends another mesh (its indices shifted past this mesh's vertices).
    pub fn append(&mut self, other: &Mesh) {
        let base = self.base();
        self.positions.extend_from_slice(&other.positions);
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|k| k + base)));
    }

    /// Appends an axis-aligned box (12 triangles).
    pub fn push_box(&mut self, min: DVec3, max: DVec3) {
        let c = |x: bool, y: bool, z: bool| {
            DVec3::new(
                if x { max.x } else { min.x },
                if y { max.y } else { min.y },
                if z { max.z } else { min.z },
            )
        };
        let faces = [
            [
                c(false, false, false),
                c(false, false, true),
                c(false, true, true),
                c(false, true, false),
            ],
            [
                c(true, false, false),
                c(true, true, false),
                c(true, true, true),
                c(true, false, true),
            ],
            [
                c(false, false, false),
                c(true, false, false),
                c(true, false, true),
                c(false, false, true),
            ],
            [
                c(false, true, false),
                c(false, true, true),
                c(true, true, true),
                c(true, true, false),
            ],
            [
                c(false, false, false),
                c(false, true, false),
                c(true, true, false),
                c(true, false, false),
            ],
            [
                c(false, false, true),
                c(true, false, true),
                c(true, true, true),
                c(false, true, true),
            ],
        ];
        for f in faces {
            self.push_quad(f);
        }
    }

    /// Appends a planar quad given by its corners in order (2 triangles).
    pub fn push_quad(&mut self, corners: [DVec3; 4]) {
        let b = self.base();
        self.positions.extend_from_slice(&corners);
        self.indices.push([b, b + 1, b + 2]);
        self.indices.push([b, b + 2, b + 3]);
    }

    /// Appends one triangle.
    pub fn push_triangle(&mut self, corners: [DVec3; 3]) {
        let b = self.base();
        self.positions.extend_from_slice(&corners);
        self.indices.push([b, b + 1, b + 2]);
    }

    /// Appends a quad tessellated into `cells × cells` squares (`2 cells²`
    /// triangles), corners in order `c0, c1, c2, c3`; `cells` of 0 counts as 1.
    pub fn push_grid_quad(&mut self, corners: [DVec3; 4], cells: u32) {
        let n = cells.max(1);
        let [c0, c1, c2, c3] = corners;
        self.push_grid(n, n, |i, j| {
            let (s, t) = (f64::from(i) / f64::from(n), f64::from(j) / f64::from(n));
            let a = c0.lerp(c1, s);
            let b = c3.lerp(c2, s);
            a.lerp(b, t)
        });
    }

    /// Appends a heightfield over `[min.x, max.x] × [min.y, max.y]` (the `x` and `z`
    /// world axes) sampled on `cells × cells` squares: vertex `(x, height(x, z), z)`.
    pub fn push_heightfield(
        &mut self,
        min: (f64, f64),
        max: (f64, f64),
        cells: u32,
        height: impl Fn(f64, f64) -> f64,
    ) {
        let n = cells.max(1);
        self.push_grid(n, n, |i, j| {
            let x = min.0 + (max.0 - min.0) * f64::from(i) / f64::from(n);
            let z = min.1 + (max.1 - min.1) * f64::from(j) / f64::from(n);
            DVec3::new(x, height(x, z), z)
        });
    }

    /// A `(nu + 1) × (nv + 1)` vertex grid with two triangles per cell.
    fn push_grid(&mut self, nu: u32, nv: u32, vertex: impl Fn(u32, u32) -> DVec3) {
        let b = self.base();
        for j in 0..=nv {
            for i in 0..=nu {
                self.positions.push(vertex(i, j));
            }
        }
        let at = |i: u32, j: u32| b + j * (nu + 1) + i;
        for j in 0..nv {
            for i in 0..nu {
                self.indices
                    .push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                self.indices
                    .push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }

    /// Appends a vertical (along `y`) closed cylinder: `segments` sides (at least 3)
    /// and both caps, `4 segments - 4` triangles.
    pub fn push_cylinder(&mut self, base: DVec3, radius: f64, height: f64, segments: u32) {
        self.push_frustum_of_cone(base, radius, radius, height, segments);
    }

    /// Appends a vertical cone with its base disc at `base` and its apex `height`
    /// above: `segments` sides (at least 3) and the base cap.
    pub fn push_cone(&mut self, base: DVec3, radius: f64, height: f64, segments: u32) {
        let n = segments.max(3);
        let b = self.base();
        let apex = base + DVec3::new(0.0, height, 0.0);
        self.positions.push(apex);
        for k in 0..n {
            self.positions.push(base + ring(radius, k, n));
        }
        for k in 0..n {
            let (p, q) = (b + 1 + k, b + 1 + (k + 1) % n);
            self.indices.push([b, q, p]);
        }
        for k in 1..n - 1 {
            self.indices.push([b + 1, b + 1 + k, b + 2 + k]);
        }
    }

    /// Vertical truncated cone (cylinder when both radii are equal), closed.
    fn push_frustum_of_cone(
        &mut self,
        base: DVec3,
        bottom_radius: f64,
        top_radius: f64,
        height: f64,
        segments: u32,
    ) {
        let n = segments.max(3);
        let b = self.base();
        let top = base + DVec3::new(0.0, height, 0.0);
        for k in 0..n {
            self.positions.push(base + ring(bottom_radius, k, n));
        }
        for k in 0..n {
            self.positions.push(top + ring(top_radius, k, n));
        }
        for k in 0..n {
            let k1 = (k + 1) % n;
            self.indices.push([b + k, b + k1, b + n + k1]);
            self.indices.push([b + k, b + n + k1, b + n + k]);
        }
        for k in 1..n - 1 {
            self.indices.push([b, b + k + 1, b + k]);
            self.indices.push([b + n, b + n + k, b + n + k + 1]);
        }
    }

    fn base(&self) -> u32 {
        u32::try_from(self.positions.len()).unwrap_or(u32::MAX)
    }
}

fn ring(radius: f64, k: u32, n: u32) -> DVec3 {
    let a = std::f64::consts::TAU * f64::from(k) / f64::from(n);
    DVec3::new(radius * a.cos(), 0.0, radius * a.sin())
}

fn round_down(p: DVec3) -> Vec3 {
    let v = p.as_vec3();
    Vec3::new(down(v.x, p.x), down(v.y, p.y), down(v.z, p.z))
}

fn round_up(p: DVec3) -> Vec3 {
    -round_down(-p)
}

/// `v` (the nearest `f32` to `exact`) moved one step down if it rounded up.
fn down(v: f32, exact: f64) -> f32 {
    if f64::from(v) <= exact {
        return v;
    }
    // One ulp toward -infinity (`f32::next_down` needs Rust 1.86).
    let bits = v.to_bits();
    if v == 0.0 {
        -f32::from_bits(1)
    } else if v > 0.0 {
        f32::from_bits(bits - 1)
    } else {
        f32::from_bits(bits + 1)
    }
}

/// A named mesh; every triangle casts and receives shadows.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Short name for reports (`city_block`, `fence`, ...).
    pub name: String,
    /// All geometry.
    pub mesh: Mesh,
}

impl Scene {
    /// A scene from a mesh.
    #[must_use]
    pub fn new(name: impl Into<String>, mesh: Mesh) -> Self {
        Self {
            name: name.into(),
            mesh,
        }
    }

    /// Bounds of all geometry (see [`Mesh::bounds`]).
    #[must_use]
    pub fn bounds(&self) -> Option<Aabb> {
        self.mesh.bounds()
    }

    /// Receiver and caster bounds for the fits: both the whole scene, since every
    /// triangle casts and receives.
    #[must_use]
    pub fn scene_bounds(&self) -> Option<SceneBounds> {
        let b = self.bounds()?;
        Some(SceneBounds {
            receivers: b,
            casters: b,
        })
    }

    /// A city block about 200 m across on a 2 km ground plane: buildings of varied
    /// heights (4–60 m) on an 8 × 8 lot grid with streets between, and thin street
    /// poles (radius 0.12 m, 5–8 m tall) along the streets. About 5k triangles.
    #[must_use]
    pub fn city_block(seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed ^ 0xC17B_10C4);
        let mut mesh = Mesh::new();
        push_ground(&mut mesh, 1000.0, 16);
        let lot = 25.0;
        let street = 6.0;
        let origin = -4.0 * lot;
        for j in 0..8 {
            for i in 0..8 {
                let x0 = origin + f64::from(i) * lot + street * 0.5;
                let z0 = origin + f64::from(j) * lot + street * 0.5;
                let size = lot - street;
                // One to three buildings per lot, some tall.
                let count = 1 + rng.below(3);
                let w = size / count as f64;
                for k in 0..count {
                    let h = if rng.unit() < 0.15 {
                        rng.range(35.0, 60.0)
                    } else {
                        rng.range(4.0, 25.0)
                    };
                    let inset = rng.range(0.3, 1.5);
                    let xa = x0 + w * k as f64 + inset;
                    let xb = x0 + w * (k + 1) as f64 - inset;
                    mesh.push_box(
                        DVec3::new(xa, 0.0, z0 + inset),
                        DVec3::new(xb, h, z0 + size - inset),
                    );
                }
            }
        }
        // Poles at street crossings and midway along the streets.
        for j in 0..=8 {
            for i in 0..=8 {
                for (dx, dz) in [(0.0, 0.0), (lot * 0.5, 0.0)] {
                    let x = origin + f64::from(i) * lot + dx + rng.range(-0.5, 0.5);
                    let z = origin + f64::from(j) * lot + dz + rng.range(-0.5, 0.5);
                    let h = rng.range(5.0, 8.0);
                    mesh.push_cylinder(DVec3::new(x, 0.0, z), 0.12, h, 6);
                }
            }
        }
        Self::new("city_block", mesh)
    }

    /// The fence of IPSM's figure 2: thin vertical slats (5 cm wide, 1.8 m tall, 15 cm
    /// apart) and two horizontal wires (2 cm) on a 40 m long fence standing 3 m in
    /// front of a 4 m high wall, on a 2 km ground plane. Light grazing the fence
    /// throws long, thin shadows on the ground and the wall: the hard case for
    /// aliasing. About 3.9k triangles.
    #[must_use]
    pub fn fence() -> Self {
        let mut mesh = Mesh::new();
        push_ground(&mut mesh, 1000.0, 16);
        let (x0, x1) = (-20.0, 20.0);
        let wall_z = -3.0;
        mesh.push_box(
            DVec3::new(x0 - 5.0, 0.0, wall_z - 0.3),
            DVec3::new(x1 + 5.0, 4.0, wall_z),
        );
        let slat = 0.05;
        let gap = 0.15;
        let count = ((x1 - x0) / gap) as u32;
        for k in 0..count {
            let x = x0 + f64::from(k) * gap;
            mesh.push_box(DVec3::new(x, 0.0, -0.02), DVec3::new(x + slat, 1.8, 0.02));
        }
        for y in [0.6, 1.5] {
            mesh.push_box(DVec3::new(x0, y, 0.03), DVec3::new(x1, y + 0.02, 0.05));
        }
        // Fence posts every 4 m.
        for k in 0..=10 {
            let x = x0 + f64::from(k) * 4.0;
            mesh.push_box(
                DVec3::new(x - 0.05, 0.0, 0.05),
                DVec3::new(x + 0.05, 2.0, 0.15),
            );
        }
        Self::new("fence", mesh)
    }

    /// Rolling terrain 1 km across (a 64 × 64 heightfield, ±25 m) with 280 trees:
    /// hexagonal trunks and conical canopies. About 19k triangles.
    #[must_use]
    pub fn terrain_with_trees(seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed ^ 0x7E44_A1B5);
        let waves: Vec<(f64, f64, f64, f64)> = (0..6)
            .map(|k| {
                let freq = 0.004 * f64::from(1 << k.min(3)) * rng.range(0.8, 1.2);
                let angle = rng.range(0.0, std::f64::consts::TAU);
                let amp = 18.0 / f64::from(1 + k * k);
                (
                    freq * angle.cos(),
                    freq * angle.sin(),
                    amp,
                    rng.range(0.0, std::f64::consts::TAU),
                )
            })
            .collect();
        let height = move |x: f64, z: f64| -> f64 {
            waves
                .iter()
                .map(|&(fx, fz, a, phase)| a * (fx * x + fz * z + phase).sin())
                .sum()
        };
        let mut mesh = Mesh::new();
        mesh.push_heightfield((-500.0, -500.0), (500.0, 500.0), 64, &height);
        for _ in 0..280 {
            let x = rng.range(-450.0, 450.0);
            let z = rng.range(-450.0, 450.0);
            // Sink the trunk below the surface so no gap shows on slopes.
            let y = height(x, z) - 0.5;
            let trunk_h = rng.range(2.0, 5.0);
            let trunk_r = rng.range(0.15, 0.4);
            mesh.push_cylinder(DVec3::new(x, y, z), trunk_r, trunk_h + 0.5, 6);
            let canopy_r = rng.range(1.5, 4.0);
            let canopy_h = rng.range(4.0, 12.0);
            mesh.push_cone(DVec3::new(x, y + trunk_h, z), canopy_r, canopy_h, 10);
        }
        Self::new("terrain_with_trees", mesh)
    }

    /// A room 10 m × 3 m × 8 m (x, y, z; floor at `y = 0`, centred on the origin in
    /// `x` and `z`) with a 2 m × 1.5 m opening in the ceiling and a window in the
    /// `+x` wall, furnished with a table (top and four legs), a shelf, two chairs and
    /// a column. Meant for a point light inside, e.g. at `(0, 2.5, 0)`; all
    /// surfaces are double-sided for the rasterizer. About 400 triangles.
    #[must_use]
    pub fn indoor_room() -> Self {
        let mut mesh = Mesh::new();
        let (hx, h, hz) = (5.0, 3.0, 4.0);
        let v = DVec3::new;
        // Floor, slightly larger than the room so walls sit on it.
        mesh.push_grid_quad(
            [
                v(-hx, 0.0, -hz),
                v(hx, 0.0, -hz),
                v(hx, 0.0, hz),
                v(-hx, 0.0, hz),
            ],
            4,
        );
        // Ceiling with a hole over x in [1, 3], z in [-0.75, 0.75].
        let (ox0, ox1, oz0, oz1) = (1.0, 3.0, -0.75, 0.75);
        for [xa, xb, za, zb] in [
            [-hx, ox0, -hz, hz],
            [ox1, hx, -hz, hz],
            [ox0, ox1, -hz, oz0],
            [ox0, ox1, oz1, hz],
        ] {
            mesh.push_quad([v(xa, h, za), v(xa, h, zb), v(xb, h, zb), v(xb, h, za)]);
        }
        // Walls: -x, -z, +z solid; +x with a window over z in [-1, 1], y in [1, 2].
        mesh.push_grid_quad(
            [
                v(-hx, 0.0, -hz),
                v(-hx, 0.0, hz),
                v(-hx, h, hz),
                v(-hx, h, -hz),
            ],
            2,
        );
        mesh.push_grid_quad(
            [
                v(-hx, 0.0, -hz),
                v(-hx, h, -hz),
                v(hx, h, -hz),
                v(hx, 0.0, -hz),
            ],
            2,
        );
        mesh.push_grid_quad(
            [v(-hx, 0.0, hz), v(hx, 0.0, hz), v(hx, h, hz), v(-hx, h, hz)],
            2,
        );
        let (wz0, wz1, wy0, wy1) = (-1.0, 1.0, 1.0, 2.0);
        for [ya, yb, za, zb] in [
            [0.0, h, -hz, wz0],
            [0.0, h, wz1, hz],
            [0.0, wy0, wz0, wz1],
            [wy1, h, wz0, wz1],
        ] {
            mesh.push_quad([v(hx, ya, za), v(hx, ya, zb), v(hx, yb, zb), v(hx, yb, za)]);
        }
        // Table.
        mesh.push_box(v(-1.5, 0.72, -0.8), v(0.5, 0.78, 0.4));
        for (x, z) in [(-1.45, -0.75), (0.45, -0.75), (-1.45, 0.35), (0.45, 0.35)] {
            mesh.push_box(v(x - 0.03, 0.0, z - 0.03), v(x + 0.03, 0.72, z + 0.03));
        }
        // Chairs: seat, back, legs.
        for (x, z, back) in [(-0.5, 0.9, 1.0), (-1.0, -1.3, -1.0)] {
            mesh.push_box(v(x - 0.22, 0.44, z - 0.22), v(x + 0.22, 0.48, z + 0.22));
            let bz = z + back * 0.2;
            mesh.push_box(v(x - 0.22, 0.48, bz - 0.02), v(x + 0.22, 0.95, bz + 0.02));
            for (dx, dz) in [(-0.2, -0.2), (0.2, -0.2), (0.2, 0.2), (-0.2, 0.2)] {
                mesh.push_box(
                    v(x + dx - 0.02, 0.0, z + dz - 0.02),
                    v(x + dx + 0.02, 0.44, z + dz + 0.02),
                );
            }
        }
        // Shelf against the -z wall: two sides and four boards.
        mesh.push_box(v(-4.0, 0.0, -4.0), v(-3.95, 2.0, -3.6));
        mesh.push_box(v(-2.55, 0.0, -4.0), v(-2.5, 2.0, -3.6));
        for k in 0..4 {
            let y = 0.1 + 0.6 * f64::from(k);
            mesh.push_box(v(-3.95, y, -4.0), v(-2.55, y + 0.03, -3.6));
        }
        // A column.
        mesh.push_cylinder(v(2.5, 0.0, 2.0), 0.25, h, 12);
        Self::new("indoor_room", mesh)
    }
}

/// A flat ground square of half-size `half` at `y = 0`, `cells × cells` quads.
fn push_ground(mesh: &mut Mesh, half: f64, cells: u32) {
    let v = DVec3::new;
    mesh.push_grid_quad(
        [
            v(-half, 0.0, -half),
            v(half, 0.0, -half),
            v(half, 0.0, half),
            v(-half, 0.0, half),
        ],
        cells,
    );
}

/// SplitMix64: small, fast, good enough for scene layout, no dependency.
#[derive(Clone, Debug)]
pub(crate) struct SplitMix64(u64);

impl SplitMix64 {
    pub(crate) const fn new(seed: u64) -> Self {
        Self(seed)
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[lo, hi)`.
    pub(crate) fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }
}
