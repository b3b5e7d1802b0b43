//! Welding, the closed-mesh check and edge adjacency.
//!
//! Vertices at bitwise-equal positions are one vertex (`-0.0` equals `0.0`), so a box
//! built from six separate quads is as closed as one with shared corners. Every
//! directed edge `a -> b` of a triangle is then paired with an edge `b -> a` of
//! another triangle; a mesh is *closed* when every edge finds a partner. An edge
//! shared by `2k` triangles (two boxes touching along an edge) is paired `k` times;
//! the stencil count of the volumes stays exact because every pair contributes the
//! same signed crossing whichever way the pairs are drawn. Triangles with two equal
//! (welded) corners have no area and are dropped.

use alloc::vec::Vec;
use core::cmp::Ordering;

use glam::{DVec3, Vec3};

use crate::VolumeError;

/// One edge of a closed mesh with its two triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    /// Welded vertex indices, in the order `triangles[0]` runs along the edge
    /// (`triangles[1]` runs `vertices[1] -> vertices[0]`).
    pub vertices: [u32; 2],
    /// Indices into [`EdgeMesh::triangles`].
    pub triangles: [u32; 2],
}

/// A closed triangle mesh with its edge adjacency, built once per mesh and reused
/// for every light and frame.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeMesh {
    /// Welded vertex positions (`f64` copies of the `f32` input).
    pub positions: Vec<DVec3>,
    /// Triangles as welded vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Every edge once, with its two triangles.
    pub edges: Vec<Edge>,
}

/// A mesh split into closed parts (shadow casters) and the rest.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Partition {
    /// Triangles (input indices) of the connected parts whose every edge is paired.
    pub closed: Vec<[u32; 3]>,
    /// Triangles of the parts with an open edge: they can receive shadows but cast
    /// no volume.
    pub open: Vec<[u32; 3]>,
    /// The first open edge found, as [`VolumeError::OpenEdge`] reports it.
    pub first_open_edge: Option<VolumeError>,
}

/// A directed edge of one triangle, keyed by its welded, sorted endpoints.
#[derive(Clone, Copy, Debug)]
struct HalfEdge {
    lo: u32,
    hi: u32,
    /// `true` when the triangle runs `hi -> lo`.
    reversed: bool,
    triangle: u32,
}

impl HalfEdge {
    fn key(&self) -> (u32, u32) {
        (self.lo, self.hi)
    }
}

/// Welded vertices: `canon[i]` is the welded index of input vertex `i`.
struct Welded {
    positions: Vec<DVec3>,
    canon: Vec<u32>,
}

fn bits(p: Vec3) -> [u32; 3] {
    // `+ 0.0` turns -0.0 into 0.0 so both weld.
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

fn check_input(positions: &[Vec3], indices: &[[u32; 3]]) -> Result<(), VolumeError> {
    if u32::try_from(positions.len()).is_err() || u32::try_from(indices.len()).is_err() {
        return Err(VolumeError::TooLarge);
    }
    if let Some(vertex) = positions.iter().position(|p| !p.is_finite()) {
        return Err(VolumeError::NonFinite { vertex });
    }
    let n = positions.len();
    if let Some(triangle) = indices
        .iter()
        .position(|t| t.iter().any(|&k| k as usize >= n))
    {
        return Err(VolumeError::IndexOutOfRange { triangle });
    }
    Ok(())
}

fn weld(positions: &[Vec3]) -> Welded {
    let mut order: Vec<u32> = (0..positions.len() as u32).collect();
    order.sort_unstable_by_key(|&i| bits(positions[i as usize]));
    let mut canon = alloc::vec![0u32; positions.len()];
    let mut welded = Vec::new();
    let mut last: Option<[u32; 3]> = None;
    for &i in &order {
        let key = bits(positions[i as usize]);
        if last != Some(key) {
            welded.push(positions[i as usize].as_dvec3());
            last = Some(key);
        }
        canon[i as usize] = (welded.len() - 1) as u32;
    }
    Welded {
        positions: welded,
        canon,
    }
}

/// The half-edges of the non-degenerate welded triangles, sorted by key, then
/// direction, then triangle.
fn half_edges(triangles: &[[u32; 3]]) -> Vec<HalfEdge> {
    let mut out = Vec::with_capacity(triangles.len() * 3);
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            out.push(HalfEdge {
                lo: a.min(b),
                hi: a.max(b),
                reversed: a > b,
                triangle: t as u32,
            });
        }
    }
    out.sort_unstable_by(|x, y| {
        x.key()
            .cmp(&y.key())
            .then(x.reversed.cmp(&y.reversed))
            .then(x.triangle.cmp(&y.triangle))
    });
    out
}

/// Welded triangles without the degenerate ones, and each one's input index.
fn welded_triangles(welded: &Welded, indices: &[[u32; 3]]) -> (Vec<[u32; 3]>, Vec<u32>) {
    let mut tris = Vec::with_capacity(indices.len());
    let mut source = Vec::with_capacity(indices.len());
    for (i, t) in indices.iter().enumerate() {
        let w = t.map(|k| welded.canon[k as usize]);
        if w[0] != w[1] && w[1] != w[2] && w[2] != w[0] {
            tris.push(w);
            source.push(i as u32);
        }
    }
    (tris, source)
}

/// Calls `group` with each run of half-edges that share endpoints.
fn for_each_group(edges: &[HalfEdge], mut group: impl FnMut(&[HalfEdge])) {
    let mut start = 0;
    while start < edges.len() {
        let key = edges[start].key();
        let len = edges[start..]
            .iter()
            .position(|e| e.key() != key)
            .unwrap_or(edges.len() - start);
        group(&edges[start..start + len]);
        start += len;
    }
}

/// The unpaired half-edge of a group whose two directions differ in count.
fn unpaired(group: &[HalfEdge]) -> Option<HalfEdge> {
    let forward = group.iter().filter(|e| !e.reversed).count();
    match forward.cmp(&(group.len() - forward)) {
        Ordering::Equal => None,
        Ordering::Greater => Some(group[0]),
        Ordering::Less => group.last().copied(),
    }
}

fn open_edge(welded: &Welded, source: &[u32], e: HalfEdge) -> VolumeError {
    let (a, b) = if e.reversed {
        (e.hi, e.lo)
    } else {
        (e.lo, e.hi)
    };
    VolumeError::OpenEdge {
        from: welded.positions[a as usize].as_vec3(),
        to: welded.positions[b as usize].as_vec3(),
        triangle: source[e.triangle as usize] as usize,
    }
}

impl EdgeMesh {
    /// Welds the vertices, checks that the mesh is closed and pairs every edge.
    ///
    /// # Errors
    /// [`VolumeError::NonFinite`], [`VolumeError::IndexOutOfRange`],
    /// [`VolumeError::TooLarge`] for bad input; [`VolumeError::OpenEdge`] naming the
    /// first edge (in welded-vertex order) without a partner.
    pub fn new(positions: &[Vec3], indices: &[[u32; 3]]) -> Result<Self, VolumeError> {
        check_input(positions, indices)?;
        let welded = weld(positions);
        let (triangles, source) = welded_triangles(&welded, indices);
        let halves = half_edges(&triangles);
        let mut edges = Vec::with_capacity(halves.len() / 2);
        let mut error = None;
        for_each_group(&halves, |group| {
            if error.is_some() {
                return;
            }
            if let Some(e) = unpaired(group) {
                error = Some(open_edge(&welded, &source, e));
                return;
            }
            let half = group.len() / 2;
            for (f, r) in group[..half].iter().zip(&group[half..]) {
                edges.push(Edge {
                    vertices: [f.lo, f.hi],
                    triangles: [f.triangle, r.triangle],
                });
            }
        });
        if let Some(e) = error {
            return Err(e);
        }
        Ok(Self {
            positions: welded.positions,
            triangles,
            edges,
        })
    }

    /// Number of (non-degenerate) triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The corners of triangle `t`, `None` past the end.
    #[must_use]
    pub fn triangle(&self, t: usize) -> Option<[DVec3; 3]> {
        let tri = self.triangles.get(t)?;
        Some(tri.map(|k| self.positions[k as usize]))
    }
}

/// Union-find over triangles.
struct Components(Vec<u32>);

impl Components {
    fn find(&mut self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            let up = self.0[self.0[i as usize] as usize];
            self.0[i as usize] = up;
            i = up;
        }
        i
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb) as usize] = ra.min(rb);
        }
    }
}

impl Partition {
    /// Splits a mesh (a whole scene, say) into its closed parts, which cast shadow
    /// volumes, and the parts with an open edge (a ground plane, single-sided walls),
    /// which only receive. Parts are connected through shared (welded) edges; a part
    /// is closed when every edge it touches is paired. Degenerate triangles go with
    /// neither list.
    ///
    /// # Errors
    /// [`VolumeError::NonFinite`], [`VolumeError::IndexOutOfRange`],
    /// [`VolumeError::TooLarge`]; open parts are not an error but are reported in
    /// [`Partition::first_open_edge`].
    pub fn new(positions: &[Vec3], indices: &[[u32; 3]]) -> Result<Self, VolumeError> {
        check_input(positions, indices)?;
        let welded = weld(positions);
        let (triangles, source) = welded_triangles(&welded, indices);
        let halves = half_edges(&triangles);
        let mut parts = Components((0..triangles.len() as u32).collect());
        let mut open_seeds = Vec::new();
        let mut first_open_edge = None;
        for_each_group(&halves, |group| {
            for e in &group[1..] {
                parts.union(group[0].triangle, e.triangle);
            }
            if let Some(e) = unpaired(group) {
                open_seeds.push(e.triangle);
                first_open_edge.get_or_insert_with(|| open_edge(&welded, &source, e));
            }
        });
        let mut open_root = alloc::vec![false; triangles.len()];
        for t in open_seeds {
            let r = parts.find(t);
            open_root[r as usize] = true;
        }
        let mut out = Self {
            first_open_edge,
            ..Self::default()
        };
        for (t, &src) in source.iter().enumerate() {
            let r = parts.find(t as u32);
            let tri = indices[src as usize];
            if open_root[r as usize] {
                out.open.push(tri);
            } else {
                out.closed.push(tri);
            }
        }
        Ok(out)
    }
}
