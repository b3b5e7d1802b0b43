//! A bounding volume hierarchy over a mesh's triangles for exact ray casting in `f64`.
//!
//! Built top-down with a binned surface-area heuristic (16 bins over triangle
//! centroids, leaves of at most 4 triangles); traversed nearest child first. The
//! triangle test is the watertight one of Woop, Benthin and Wald (JCGT 2013): a ray
//! through an edge or vertex shared by two triangles hits at least one of them, so
//! shadow rays never leak through the seams of a mesh. Box tests are widened by a few
//! ulps (Ize 2013) so that rounding never culls a box the ray touches.
//!
//! # Example
//!
//! ```
//! use glam::DVec3;
//! use shadowmap_eval::bvh::Bvh;
//! use shadowmap_eval::scene::Mesh;
//!
//! let mut mesh = Mesh::new();
//! mesh.push_box(DVec3::splat(-1.0), DVec3::splat(1.0));
//! let bvh = Bvh::build(&mesh)?;
//! let hit = bvh.intersect(DVec3::new(0.0, 5.0, 0.0), DVec3::NEG_Y, 0.0, f64::INFINITY).unwrap();
//! assert!((hit.t - 4.0).abs() < 1e-12);
//! assert_eq!(hit.normal, DVec3::Y); // facing the ray's origin
//! assert!(bvh.occluded(DVec3::new(0.0, 5.0, 0.0), DVec3::NEG_Y, 0.0, 10.0));
//! # Ok::<(), shadowmap_eval::EvalError>(())
//! ```

use glam::DVec3;

use crate::EvalError;
use crate::scene::Mesh;

/// Where a ray hit the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter: the hit is `origin + t * dir`.
    pub t: f64,
    /// Index of the triangle in the mesh.
    pub triangle: usize,
    /// World position of the hit.
    pub position: DVec3,
    /// Unit geometric normal of the triangle, turned toward the ray's origin side.
    pub normal: DVec3,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Leaf: first triangle in `order`; inner: index of the second child (the first
    /// child follows its parent).
    start: u32,
    /// Triangles in a leaf, 0 for an inner node.
    count: u32,
}

/// A BVH over a mesh's triangles; it owns a copy of the triangles' corners.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangle corners in leaf order.
    triangles: Vec<[DVec3; 3]>,
    /// Mesh triangle index of each entry of `triangles`.
    order: Vec<u32>,
}

const BINS: usize = 16;
const MAX_LEAF: usize = 4;
/// Depth of the traversal stack; the build never exceeds it (see `build_node`).
const STACK: usize = 128;

#[derive(Clone, Copy)]
struct Bounds {
    min: DVec3,
    max: DVec3,
}

impl Bounds {
    const EMPTY: Self = Self {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    fn grow(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    fn merge(&mut self, b: &Self) {
        self.min = self.min.min(b.min);
        self.max = self.max.max(b.max);
    }

    fn half_area(&self) -> f64 {
        let d = (self.max - self.min).max(DVec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

struct Prim {
    bounds: Bounds,
    centroid: DVec3,
    index: u32,
}

impl Bvh {
    /// Builds the hierarchy. Degenerate (zero-area) triangles are kept; they are
    /// never hit.
    ///
    /// # Errors
    /// [`EvalError::InvalidMesh`] for a mesh failing [`Mesh::validate`] or with more
    /// than `u32::MAX` triangles.
    pub fn build(mesh: &Mesh) -> Result<Self, EvalError> {
        mesh.validate()?;
        if u32::try_from(mesh.triangle_count()).is_err() {
            return Err(EvalError::InvalidMesh {
                message: "more than u32::MAX triangles".into(),
            });
        }
        let mut prims: Vec<Prim> = mesh
            .triangles()
            .enumerate()
            .map(|(i, t)| {
                let mut bounds = Bounds::EMPTY;
                t.iter().for_each(|&p| bounds.grow(p));
                Prim {
                    bounds,
                    centroid: (t[0] + t[1] + t[2]) / 3.0,
                    index: i as u32,
                }
            })
            .collect();
        let mut nodes = Vec::with_capacity(2 * prims.len().max(1));
        if !prims.is_empty() {
            build_node(&mut prims, 0, &mut nodes, 0);
        }
        let order: Vec<u32> = prims.iter().map(|p| p.index).collect();
        let triangles = order.iter().map(|&i| mesh.triangle(i as usize)).collect();
        Ok(Self {
            nodes,
            triangles,
            order,
        })
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The nearest hit with `t_min < t < t_max`, `None` if none (or for a zero or
    /// non-finite direction, or NaN bounds). `dir` need not be unit length; `t` is in
    /// its units.
    #[must_use]
    pub fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
        let ray = Ray::new(origin, dir, t_min, t_max)?;
        let mut best: Option<(f64, usize)> = None;
        let mut t_far = t_max;
        self.traverse(&ray, |i, tri| {
            if let Some(t) = ray.triangle(tri, t_far) {
                t_far = t;
                best = Some((t, i));
            }
            (false, t_far)
        });
        let (t, i) = best?;
        let [a, b, c] = self.triangles[i];
        let mut normal = (b - a).cross(c - a).normalize_or_zero();
        if normal.dot(dir) > 0.0 {
            normal = -normal;
        }
        Some(Hit {
            t,
            triangle: self.order[i] as usize,
            position: origin + dir * t,
            normal,
        })
    }

    /// Whether any triangle is hit with `t_min < t < t_max` (stops at the first).
    #[must_use]
    pub fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        let Some(ray) = Ray::new(origin, dir, t_min, t_max) else {
            return false;
        };
        let mut found = false;
        self.traverse(&ray, |_, tri| {
            found = ray.triangle(tri, t_max).is_some();
            (found, t_max)
        });
        found
    }

    /// Visits the leaves' triangles the ray may hit, nearest child first. `visit`
    /// returns (stop, current far bound).
    fn traverse(&self, ray: &Ray, mut visit: impl FnMut(usize, &[DVec3; 3]) -> (bool, f64)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut top = 1;
        let mut t_far = ray.t_max;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if ray.slab(node.min, node.max, t_far).is_none() {
                continue;
            }
            if node.count > 0 {
                let start = node.start as usize;
                for i in start..start + node.count as usize {
                    let (stop, far) = visit(i, &self.triangles[i]);
                    if stop {
                        return;
                    }
                    t_far = far;
                }
                continue;
            }
            let first = stack[top] + 1;
            let second = node.start;
            let d1 = self.nodes[first as usize].entry(ray, t_far);
            let d2 = self.nodes[second as usize].entry(ray, t_far);
            // Push the farther child first so the nearer is popped next.
            let (near, far, dn, df) = if d1 <= d2 {
                (first, second, d1, d2)
            } else {
                (second, first, d2, d1)
            };
            if df.is_finite() && top < STACK {
                stack[top] = far;
                top += 1;
            }
            if dn.is_finite() && top < STACK {
                stack[top] = near;
                top += 1;
            }
        }
    }
}

impl Node {
    /// Entry distance of the ray into the node's box, infinite on a miss.
    fn entry(&self, ray: &Ray, t_far: f64) -> f64 {
        ray.slab(self.min, self.max, t_far).unwrap_or(f64::INFINITY)
    }
}

/// Splits `prims` recursively, appending nodes depth first.
fn build_node(prims: &mut [Prim], first: usize, nodes: &mut Vec<Node>, depth: usize) -> usize {
    let mut bounds = Bounds::EMPTY;
    let mut centroids = Bounds::EMPTY;
    for p in prims.iter() {
        bounds.merge(&p.bounds);
        centroids.grow(p.centroid);
    }
    let id = nodes.len();
    nodes.push(Node {
        min: bounds.min,
        max: bounds.max,
        start: first as u32,
        count: prims.len() as u32,
    });
    // The traversal stack holds at most one entry per level plus one.
    if prims.len() <= MAX_LEAF || depth + 2 >= STACK {
        return id;
    }
    let mid = match sah_split(prims, &bounds, &centroids) {
        Some(mid) => mid,
        None => {
            if prims.len() <= 4 * MAX_LEAF {
                return id;
            }
            // All centroids coincide or SAH prefers a leaf that is too large: median.
            let axis = (centroids.max - centroids.min).max_position();
            prims.sort_unstable_by(|a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
            prims.len() / 2
        }
    };
    let (left, right) = prims.split_at_mut(mid);
    build_node(left, first, nodes, depth + 1);
    let second = build_node(right, first + mid, nodes, depth + 1);
    nodes[id].start = second as u32;
    nodes[id].count = 0;
    id
}

/// Binned SAH: partitions `prims` and returns the split point, or `None` when a leaf
/// is cheaper (or the centroids do not spread).
fn sah_split(prims: &mut [Prim], bounds: &Bounds, centroids: &Bounds) -> Option<usize> {
    let extent = centroids.max - centroids.min;
    let axis = extent.max_position();
    if !(extent[axis] > 0.0) {
        return None;
    }
    let lo = centroids.min[axis];
    let scale = BINS as f64 / extent[axis];
    let bin_of = |p: &Prim| (((p.centroid[axis] - lo) * scale) as usize).min(BINS - 1);
    let mut bins = [(Bounds::EMPTY, 0usize); BINS];
    for p in prims.iter() {
        let b = &mut bins[bin_of(p)];
        b.0.merge(&p.bounds);
        b.1 += 1;
    }
    // Sweep from the right, then from the left, to cost each of the BINS-1 planes.
    let mut right_cost = [0.0; BINS];
    let mut acc = Bounds::EMPTY;
    let mut count = 0;
    for i in (1..BINS).rev() {
        acc.merge(&bins[i].0);
        count += bins[i].1;
        right_cost[i] = acc.half_area() * count as f64;
    }
    let mut acc = Bounds::EMPTY;
    let mut count = 0;
    let mut best = (f64::INFINITY, 0);
    for i in 0..BINS - 1 {
        acc.merge(&bins[i].0);
        count += bins[i].1;
        if count == 0 || count == prims.len() {
            continue;
        }
        let cost = acc.half_area() * count as f64 + right_cost[i + 1];
        if cost < best.0 {
            best = (cost, i);
        }
    }
    let leaf_cost = bounds.half_area() * prims.len() as f64;
    // Traversal costs about one triangle test per child.
    let split_cost = 0.5 * bounds.half_area() + best.0;
    if !(best.0.is_finite()) || (prims.len() <= MAX_LEAF * 4 && split_cost >= leaf_cost) {
        return None;
    }
    // Partition in place: bins 0..=best.1 to the left.
    let mut mid = 0;
    for i in 0..prims.len() {
        if bin_of(&prims[i]) <= best.1 {
            prims.swap(i, mid);
            mid += 1;
        }
    }
    (mid > 0 && mid < prims.len()).then_some(mid)
}

/// A ray prepared for slab and watertight triangle tests.
struct Ray {
    origin: DVec3,
    inv_dir: DVec3,
    t_min: f64,
    t_max: f64,
    /// Watertight test: the axis along which the ray is longest, and the other two.
    kx: usize,
    ky: usize,
    kz: usize,
    shear: DVec3,
}

/// `1 + 2 gamma(3)`: widens box exits so rounding never misses a touched box.
const SLAB_WIDEN: f64 = 1.0 + 2.0 * (3.0 * f64::EPSILON * 0.5) / (1.0 - 3.0 * f64::EPSILON * 0.5);

impl Ray {
    fn new(origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Self> {
        if !(origin.is_finite() && dir.is_finite() && dir != DVec3::ZERO)
            || t_min.is_nan()
            || t_max.is_nan()
            || !(t_min < t_max)
        {
            return None;
        }
        let kz = dir.abs().max_position();
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        // Keep the winding of the sheared triangles.
        if dir[kz] < 0.0 {
            core::mem::swap(&mut kx, &mut ky);
        }
        let shear = DVec3::new(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
        Some(Self {
            origin,
            inv_dir: dir.recip(),
            t_min,
            t_max,
            kx,
            ky,
            kz,
            shear,
        })
    }

    /// Entry distance into a box if the ray crosses it within `(t_min, t_far)`.
    fn slab(&self, min: DVec3, max: DVec3, t_far: f64) -> Option<f64> {
        let t0 = (min - self.origin) * self.inv_dir;
        let t1 = (max - self.origin) * self.inv_dir;
        // `f64::min`/`max` skip the NaN of 0 * inf (origin on a slab of a flat box).
        let near = t0.min(t1);
        let far = t0.max(t1);
        let enter = near.x.max(near.y).max(near.z).max(self.t_min);
        let exit = far.x.min(far.y).min(far.z).min(t_far) * SLAB_WIDEN;
        (enter <= exit).then_some(enter)
    }

    /// Watertight ray–triangle test (Woop et al. 2013); `t` if in `(t_min, t_far)`.
    fn triangle(&self, tri: &[DVec3; 3], t_far: f64) -> Option<f64> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let a = tri[0] - self.origin;
        let b = tri[1] - self.origin;
        let c = tri[2] - self.origin;
        let (sx, sy, sz) = (self.shear.x, self.shear.y, self.shear.z);
        let ax = a[kx] - sx * a[kz];
        let ay = a[ky] - sy * a[kz];
        let bx = b[kx] - sx * b[kz];
        let by = b[ky] - sy * b[kz];
        let cx = c[kx] - sx * c[kz];
        let cy = c[ky] - sy * c[kz];
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || det.is_nan() {
            return None;
        }
        let t_scaled = u * sz * a[kz] + v * sz * b[kz] + w * sz * c[kz];
        let t = t_scaled / det;
        (t > self.t_min && t < t_far && t.is_finite()).then_some(t)
    }
}
