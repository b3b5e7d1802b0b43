//! Properties of the closed-mesh check, the silhouette and the shadow volume over
//! generated closed meshes: boxes welded from separate quads and tetrahedra, under
//! random rigid transforms and scales, alone or overlapping.

use glam::{DMat3, DVec3, Mat4, Vec3, Vec4};
use proptest::prelude::*;
use shadowmap_frustum::{Aabb, Camera, Light, Projection};
use shadowmap_volume::{
    EdgeMesh, OccluderMask, Partition, ProjectiveShadow, ShadowVolume, VolumeError,
    infinite_clip_from_world,
};

/// A triangle soup under construction.
#[derive(Clone, Debug, Default)]
struct Soup {
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
}

impl Soup {
    fn push(&mut self, corners: &[Vec3], tris: &[[u32; 3]]) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(corners);
        self.indices
            .extend(tris.iter().map(|t| t.map(|k| k + base)));
    }

    /// A box as six separate quads (no shared vertices until welded).
    fn push_box(&mut self, frame: &Frame) {
        let c = |x: u8, y: u8, z: u8| {
            frame.apply(DVec3::new(f64::from(x), f64::from(y), f64::from(z)) * 2.0 - 1.0)
        };
        let faces = [
            [c(0, 0, 0), c(0, 0, 1), c(0, 1, 1), c(0, 1, 0)],
            [c(1, 0, 0), c(1, 1, 0), c(1, 1, 1), c(1, 0, 1)],
            [c(0, 0, 0), c(1, 0, 0), c(1, 0, 1), c(0, 0, 1)],
            [c(0, 1, 0), c(0, 1, 1), c(1, 1, 1), c(1, 1, 0)],
            [c(0, 0, 0), c(0, 1, 0), c(1, 1, 0), c(1, 0, 0)],
            [c(0, 0, 1), c(1, 0, 1), c(1, 1, 1), c(0, 1, 1)],
        ];
        for f in faces {
            self.push(&f, &[[0, 1, 2], [0, 2, 3]]);
        }
    }

    /// A tetrahedron with shared corners, faces turned outward.
    fn push_tetrahedron(&mut self, frame: &Frame) {
        let p = [
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(-1.0, -1.0, 1.0),
        ]
        .map(|q| frame.apply(q));
        let mut tris = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
        let centroid = p.iter().map(|v| v.as_dvec3()).sum::<DVec3>() / 4.0;
        for t in &mut tris {
            let [a, b, c] = t.map(|k| p[k as usize].as_dvec3());
            if (b - a).cross(c - a).dot(a - centroid) < 0.0 {
                t.swap(1, 2);
            }
        }
        self.push(&p, &tris);
    }
}

/// A rotation, positive scales and a translation.
#[derive(Clone, Debug)]
struct Frame {
    rotation: DMat3,
    scale: DVec3,
    offset: DVec3,
}

impl Frame {
    fn apply(&self, p: DVec3) -> Vec3 {
        (self.rotation * (p * self.scale) + self.offset).as_vec3()
    }
}

fn frame() -> impl Strategy<Value = Frame> {
    (
        -3.2f64..3.2,
        -1.5f64..1.5,
        -3.2f64..3.2,
        prop::array::uniform3(0.3f64..3.0),
        prop::array::uniform3(-4.0f64..4.0),
    )
        .prop_map(|(a, b, c, s, o)| Frame {
            rotation: DMat3::from_euler(glam::EulerRot::YXZ, a, b, c),
            scale: DVec3::from(s),
            offset: DVec3::from(o),
        })
}

/// One convex caster (box or tetrahedron).
fn convex() -> impl Strategy<Value = Soup> {
    (frame(), any::<bool>()).prop_map(|(f, is_box)| {
        let mut soup = Soup::default();
        if is_box {
            soup.push_box(&f);
        } else {
            soup.push_tetrahedron(&f);
        }
        soup
    })
}

/// One to three casters, possibly overlapping.
fn casters() -> impl Strategy<Value = Soup> {
    prop::collection::vec((frame(), any::<bool>()), 1..4).prop_map(|parts| {
        let mut soup = Soup::default();
        for (f, is_box) in parts {
            if is_box {
                soup.push_box(&f);
            } else {
                soup.push_tetrahedron(&f);
            }
        }
        soup
    })
}

/// A point or directional light well outside the casters' region.
fn light() -> impl Strategy<Value = Light> {
    (
        prop::array::uniform3(-1.0f32..1.0),
        20.0f32..60.0,
        any::<bool>(),
    )
        .prop_filter_map("zero direction", |(d, dist, point)| {
            let dir = Vec3::from(d).try_normalize()?;
            Some(if point {
                Light::Point {
                    position: -dir * dist,
                    range: 1000.0,
                }
            } else {
                Light::Directional { direction: dir }
            })
        })
}

/// Scale at which `w = 0` points are placed for the crossing counts.
const FAR: f64 = 1e6;

fn light_origin(light: &Light) -> DVec3 {
    match *light {
        Light::Directional { .. } => DVec3::ZERO,
        Light::Spot { position, .. } | Light::Point { position, .. } => position.as_dvec3(),
    }
}

/// A homogeneous volume vertex as a finite point (points at infinity at distance
/// `FAR` from the light, or from the origin for a directional light).
fn finite(v: Vec4, origin: DVec3) -> DVec3 {
    let v = v.as_dvec4();
    if v.w == 0.0 {
        origin + v.truncate().normalize() * FAR
    } else {
        v.truncate() / v.w
    }
}

/// Where segment `p -> q` crosses triangle `t` (strictly inside both): `Some(+1)`
/// entering (the triangle faces `p`), `Some(-1)` leaving.
fn crossing(p: DVec3, q: DVec3, t: [DVec3; 3]) -> Option<i32> {
    let d = q - p;
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = p - t[0];
    let u = s.dot(h) / det;
    let qv = s.cross(e1);
    let v = d.dot(qv) / det;
    let t_hit = e2.dot(qv) / det;
    (u > 0.0 && v > 0.0 && u + v < 1.0 && t_hit > 0.0 && t_hit < 1.0)
        .then(|| if e1.cross(e2).dot(d) < 0.0 { 1 } else { -1 })
}

/// Signed crossings of the volume triangles `tris` along `p -> q`.
fn crossings(tris: &[Vec4], origin: DVec3, p: DVec3, q: DVec3) -> i32 {
    tris.chunks_exact(3)
        .filter_map(|t| crossing(p, q, [t[0], t[1], t[2]].map(|v| finite(v, origin))))
        .sum()
}

/// Ground truth: does the segment from `p` toward the light hit a caster triangle?
fn ray_shadowed(soup: &Soup, light: &Light, p: DVec3) -> bool {
    let target = match *light {
        Light::Directional { direction } => p - direction.as_dvec3().normalize() * FAR,
        Light::Spot { position, .. } | Light::Point { position, .. } => position.as_dvec3(),
    };
    segment_hits(soup, p, target)
}

/// Does segment `a -> b` cross a caster triangle?
fn segment_hits(soup: &Soup, a: DVec3, b: DVec3) -> bool {
    soup.indices.iter().any(|t| {
        let c = t.map(|k| soup.positions[k as usize].as_dvec3());
        crossing(a, b, c).is_some()
    })
}

fn volume(soup: &Soup, light: &Light) -> (EdgeMesh, ShadowVolume) {
    let mesh = EdgeMesh::new(&soup.positions, &soup.indices).expect("closed");
    let mut v = ShadowVolume::new();
    v.update(&mesh, light).expect("valid light");
    (mesh, v)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Generated casters are closed; every edge pairs two triangles.
    #[test]
    fn generated_meshes_are_closed(soup in casters()) {
        let mesh = EdgeMesh::new(&soup.positions, &soup.indices).unwrap();
        prop_assert_eq!(mesh.edges.len() * 2, mesh.triangle_count() * 3);
        for e in &mesh.edges {
            let [a, b] = e.vertices;
            let t0 = mesh.triangles[e.triangles[0] as usize];
            let t1 = mesh.triangles[e.triangles[1] as usize];
            let runs = |t: [u32; 3], x: u32, y: u32| (0..3).any(|k| t[k] == x && t[(k + 1) % 3] == y);
            prop_assert!(runs(t0, a, b) && runs(t1, b, a));
        }
    }

    /// Dropping a triangle or flipping its winding is reported with an edge of it.
    #[test]
    fn open_or_flipped_meshes_are_refused(soup in casters(), pick in any::<prop::sample::Index>(), flip in any::<bool>()) {
        let mut broken = soup.clone();
        let i = pick.index(broken.indices.len());
        let removed = broken.indices[i];
        if flip {
            broken.indices[i].swap(1, 2);
        } else {
            broken.indices.remove(i);
        }
        match EdgeMesh::new(&broken.positions, &broken.indices) {
            Err(VolumeError::OpenEdge { from, to, .. }) => {
                let corners = removed.map(|k| soup.positions[k as usize]);
                prop_assert!(corners.contains(&from) && corners.contains(&to));
            }
            other => prop_assert!(false, "expected an open edge, got {:?}", other),
        }
    }

    /// The silhouette is a set of closed loops: every vertex has as many silhouette
    /// edges leaving it as arriving.
    #[test]
    fn silhouette_is_closed_loops(soup in casters(), light in light()) {
        let (mesh, v) = volume(&soup, &light);
        let mut degree = vec![0i32; mesh.positions.len()];
        for &[a, b] in &v.silhouette {
            degree[a as usize] += 1;
            degree[b as usize] -= 1;
        }
        prop_assert!(degree.iter().all(|&d| d == 0));
        prop_assert!(!v.silhouette.is_empty());
    }

    /// The closed volume's winding number at a point (signed crossings out to far
    /// away) is nonzero exactly where the shadow ray toward the light hits a caster;
    /// from an eye outside every volume, the sides alone (z-pass) count the same.
    #[test]
    fn volume_contains_exactly_the_shadowed_points(
        soup in casters(),
        light in light(),
        p in prop::array::uniform3(-8.0f64..8.0),
        dirs in prop::array::uniform2(prop::array::uniform3(-1.0f64..1.0)),
    ) {
        let (_, v) = volume(&soup, &light);
        let origin = light_origin(&light);
        let p = DVec3::from(p);
        let [d0, d1] = dirs.map(|d| DVec3::from(d).try_normalize());
        let (d0, d1) = (d0.unwrap_or(DVec3::Y), d1.unwrap_or(DVec3::X));
        prop_assume!(d0.cross(d1).length() > 0.1);
        let winding = [d0, d1].map(|d| -crossings(v.closed(), origin, p, p + d * 1e3));
        // A ray grazing an edge can double count: skip points the two rays disagree on.
        prop_assume!(winding[0] == winding[1]);
        prop_assert_eq!(winding[0] != 0, ray_shadowed(&soup, &light, p));
        prop_assert!(winding[0] >= 0);
        // An eye on the light's side, 100 units out and outside every volume, sees
        // p (when no caster hides it) through the sides only.
        let eye = match light {
            Light::Directional { direction } => -direction.as_dvec3() * 100.0,
            _ => origin * (100.0 / origin.length()),
        };
        if !segment_hits(&soup, eye, p) {
            let z_pass = crossings(v.sides(), origin, eye, p);
            prop_assert_eq!(z_pass, winding[0]);
        }
    }

    /// A point straight behind a convex caster, seen from the light, is in its volume.
    #[test]
    fn point_behind_a_convex_caster_is_shadowed(soup in convex(), light in light(), beyond in 0.5f64..20.0) {
        let (_, v) = volume(&soup, &light);
        let origin = light_origin(&light);
        let inside = soup.positions.iter().map(|p| p.as_dvec3()).sum::<DVec3>()
            / soup.positions.len() as f64;
        let away = match light {
            Light::Directional { direction } => direction.as_dvec3().normalize(),
            _ => (inside - origin).normalize(),
        };
        let p = inside + away * (10.0 + beyond);
        prop_assert!(ray_shadowed(&soup, &light, p));
        // Counted along two rays: one that grazes a volume edge can miss or double a
        // crossing, and two rarely both do.
        let winding = [DVec3::new(0.31, 0.83, -0.46), DVec3::new(-0.72, 0.29, 0.63)]
            .map(|d| -crossings(v.closed(), origin, p, p + d * 1e3));
        prop_assert!(winding.iter().any(|w| *w > 0), "windings {:?}", winding);
    }
}

#[test]
fn partition_separates_open_ground_from_closed_boxes() {
    let mut soup = Soup::default();
    soup.push(
        &[
            Vec3::new(-10.0, 0.0, -10.0),
            Vec3::new(-10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, -10.0),
        ],
        &[[0, 1, 2], [0, 2, 3]],
    );
    for x in [-3.0, 3.0] {
        soup.push_box(&Frame {
            rotation: DMat3::IDENTITY,
            scale: DVec3::ONE,
            offset: DVec3::new(x, 1.0, 0.0),
        });
    }
    let part = Partition::new(&soup.positions, &soup.indices).unwrap();
    assert_eq!(part.closed.len(), 24);
    assert_eq!(part.open, soup.indices[..2].to_vec());
    assert!(matches!(
        part.first_open_edge,
        Some(VolumeError::OpenEdge {
            triangle: 0 | 1,
            ..
        })
    ));
    assert!(EdgeMesh::new(&soup.positions, &part.closed).is_ok());
}

#[test]
fn bad_input_is_a_typed_error() {
    let p = [Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 0.0)];
    assert_eq!(
        EdgeMesh::new(&p, &[[0, 1, 2]]),
        Err(VolumeError::NonFinite { vertex: 2 })
    );
    assert_eq!(
        EdgeMesh::new(&p[..2], &[[0, 1, 5]]),
        Err(VolumeError::IndexOutOfRange { triangle: 0 })
    );
    let mesh = EdgeMesh::new(&[], &[]).unwrap();
    let mut v = ShadowVolume::new();
    let bad = Light::Directional {
        direction: Vec3::ZERO,
    };
    assert!(matches!(
        v.update(&mesh, &bad),
        Err(VolumeError::InvalidLight(_))
    ));
}

#[test]
fn infinite_projection_keeps_points_at_infinity() {
    let camera = Camera::look_at(
        Vec3::new(0.0, 2.0, 10.0),
        Vec3::ZERO,
        Vec3::Y,
        Projection::perspective(1.0, 1.5, 0.5, 50.0),
    )
    .unwrap();
    let m: Mat4 = infinite_clip_from_world(&camera).unwrap();
    // A direction in front of the eye lands exactly on the far plane (depth 0).
    let inf = m * (camera.forward() + Vec3::new(0.1, 0.0, 0.0)).extend(0.0);
    assert_eq!(inf.z, 0.0);
    assert!(inf.w > 0.0);
    // The near plane is at depth 1 (reversed-Z).
    let near = m * (camera.eye() + camera.forward() * 0.5).extend(1.0);
    assert!((near.z / near.w - 1.0).abs() < 1e-5);
    let ortho = Camera {
        projection: Projection::Orthographic {
            left: -1.0,
            right: 1.0,
            bottom: -1.0,
            top: 1.0,
            near: 0.0,
            far: 10.0,
        },
        ..camera
    };
    assert_eq!(
        infinite_clip_from_world(&ortho),
        Err(VolumeError::UnsupportedProjection)
    );
}

#[test]
fn projective_shadow_frames_the_occluders() {
    let occluders = Aabb::new(Vec3::new(-1.0, 1.0, -2.0), Vec3::new(3.0, 4.0, 1.0));
    for light in [
        Light::Directional {
            direction: Vec3::new(0.3, -1.0, 0.2),
        },
        Light::Point {
            position: Vec3::new(1.0, 20.0, 0.0),
            range: 100.0,
        },
    ] {
        let s = ProjectiveShadow::new(&light, &occluders).unwrap();
        for c in occluders.corners() {
            let uv = s.uv(c).unwrap();
            assert!(
                (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y),
                "{uv}"
            );
        }
    }
    let point = Light::Point {
        position: Vec3::new(1.0, 20.0, 0.0),
        range: 100.0,
    };
    let s = ProjectiveShadow::new(&point, &occluders).unwrap();
    // Behind the light: no mask lookup.
    assert_eq!(s.uv(Vec3::new(1.0, 40.0, 0.0)), None);
    // Inside the occluders' sphere: refused.
    let inside = Light::Point {
        position: occluders.center(),
        range: 100.0,
    };
    assert_eq!(
        ProjectiveShadow::new(&inside, &occluders),
        Err(VolumeError::InvalidOccluders)
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// A ground point straight down-light of a convex occluder's centre is in its
    /// projective shadow; one outside the occluder's shadow cylinder or cone, or
    /// behind a point light, is not.
    #[test]
    fn projective_mask_shadows_points_behind_occluders(soup in convex(), light in light()) {
        let bounds = Aabb::from_points(&soup.positions).unwrap();
        let shadow = ProjectiveShadow::new(&light, &bounds).unwrap();
        let mask = OccluderMask::render(&shadow, &soup.positions, &soup.indices, 256).unwrap();
        let centre = soup.positions.iter().map(|p| p.as_dvec3()).sum::<DVec3>()
            / soup.positions.len() as f64;
        let origin = light_origin(&light);
        let away = match light {
            Light::Directional { direction } => direction.as_dvec3().normalize(),
            _ => (centre - origin).normalize(),
        };
        prop_assert!(mask.shadows(&shadow, (centre + away * 30.0).as_vec3()));
        // Sideways, well past the bounds: outside the mask's shadow.
        let side = away.any_orthonormal_vector();
        let radius = f64::from(bounds.size().length());
        let beside = centre + side * (radius + 1.0) * 3.0 + away * 2.0;
        prop_assert!(!mask.shadows(&shadow, beside.as_vec3()));
        if let Light::Point { position, .. } = light {
            let behind = position.as_dvec3() - away * 5.0;
            prop_assert!(!mask.shadows(&shadow, behind.as_vec3()));
        }
    }
}

#[test]
fn occluder_mask_rejects_bad_input() {
    let occluders = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let light = Light::Directional {
        direction: Vec3::NEG_Y,
    };
    let s = ProjectiveShadow::new(&light, &occluders).unwrap();
    let p = [Vec3::ZERO, Vec3::X, Vec3::Z];
    assert_eq!(
        OccluderMask::render(&s, &p, &[[0, 1, 2]], 0),
        Err(VolumeError::InvalidOccluders)
    );
    assert_eq!(
        OccluderMask::render(&s, &p, &[[0, 1, 3]], 8),
        Err(VolumeError::IndexOutOfRange { triangle: 0 })
    );
    let m = OccluderMask::render(&s, &p, &[[0, 1, 2]], 8).unwrap();
    assert!(m.occluded.iter().any(|&o| o) && !m.occluded.iter().all(|&o| o));
}
