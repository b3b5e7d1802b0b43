//! Scenes, mesh helpers and the BVH ray caster (against brute force).

use glam::{DVec3, Vec3};
use proptest::prelude::*;
use shadowmap_eval::EvalError;
use shadowmap_eval::bvh::Bvh;
use shadowmap_eval::scene::{Mesh, Scene};

fn all_scenes() -> Vec<Scene> {
    vec![
        Scene::city_block(1),
        Scene::fence(),
        Scene::terrain_with_trees(1),
        Scene::indoor_room(),
    ]
}

#[test]
fn scenes_are_moderate_valid_and_sized_as_documented() {
    let sizes = [
        ("city_block", 2000.0),
        ("fence", 2000.0),
        ("terrain_with_trees", 1000.0),
        ("indoor_room", 10.0),
    ];
    for (scene, (name, extent)) in all_scenes().iter().zip(sizes) {
        assert_eq!(scene.name, name);
        let n = scene.mesh.triangle_count();
        assert!((100..=20_000).contains(&n), "{name}: {n} triangles");
        scene.mesh.validate().unwrap();
        let b = scene.bounds().unwrap();
        let size = b.size();
        assert!(
            (size.x - extent).abs() <= 1e-3 * extent,
            "{name}: x extent {}",
            size.x
        );
        let sb = scene.scene_bounds().unwrap();
        assert_eq!(sb.receivers, b);
        assert_eq!(sb.casters, b);
        // No degenerate triangles: every one has area.
        assert!(
            scene
                .mesh
                .triangles()
                .all(|[a, b, c]| (b - a).cross(c - a).length() > 1e-9),
            "{name}"
        );
    }
}

#[test]
fn scenes_are_deterministic_for_a_seed() {
    assert_eq!(Scene::city_block(5), Scene::city_block(5));
    assert_ne!(Scene::city_block(5).mesh, Scene::city_block(6).mesh);
    assert_eq!(Scene::terrain_with_trees(9), Scene::terrain_with_trees(9));
    assert_ne!(
        Scene::terrain_with_trees(9).mesh,
        Scene::terrain_with_trees(10).mesh
    );
}

#[test]
fn city_has_tall_buildings_and_thin_poles() {
    let city = Scene::city_block(3);
    let b = city.bounds().unwrap();
    assert!(b.max.y > 35.0 && b.max.y <= 60.0, "tallest {}", b.max.y);
    assert_eq!(b.min.y, 0.0);
    // The pole at the central crossing: vertical rays over a 1.2 m square find its
    // top (5-8 m) on a few percent of the square (radius 0.12 m), the street elsewhere.
    let bvh = Bvh::build(&city.mesh).unwrap();
    let heights: Vec<f64> = (0..24 * 24)
        .filter_map(|i| {
            let x = -0.6 + 0.05 * f64::from(i % 24);
            let z = -0.6 + 0.05 * f64::from(i / 24);
            bvh.intersect(DVec3::new(x, 100.0, z), DVec3::NEG_Y, 0.0, 200.0)
        })
        .map(|h| h.position.y)
        .collect();
    assert_eq!(heights.len(), 24 * 24);
    let on_pole = heights
        .iter()
        .filter(|&&y| (5.0..=8.0).contains(&y))
        .count();
    assert!((1..=40).contains(&on_pole), "{on_pole} rays hit the pole");
    assert_eq!(
        heights.iter().filter(|&&y| y == 0.0).count(),
        24 * 24 - on_pole
    );
}

#[test]
fn room_is_closed_except_for_its_openings() {
    let room = Scene::indoor_room();
    let bvh = Bvh::build(&room.mesh).unwrap();
    let light = DVec3::new(0.0, 2.5, 0.0);
    // Through the ceiling opening and the window the light escapes; elsewhere not.
    assert!(!bvh.occluded(light, DVec3::new(2.0, 3.0, 0.0) - light, 0.0, 10.0));
    assert!(!bvh.occluded(light, DVec3::new(5.0, 1.5, 0.0) - light, 0.0, 10.0));
    assert!(bvh.occluded(light, DVec3::new(-2.0, 3.0, 0.0) - light, 0.0, 10.0));
    assert!(bvh.occluded(light, DVec3::new(5.0, 1.5, 3.0) - light, 0.0, 10.0));
    assert!(bvh.occluded(light, DVec3::NEG_Y, 0.0, 10.0));
}

#[test]
fn mesh_helpers_build_what_they_say() {
    let mut m = Mesh::new();
    m.push_box(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0));
    assert_eq!(m.triangle_count(), 12);
    let area: f64 = m
        .triangles()
        .map(|[a, b, c]| 0.5 * (b - a).cross(c - a).length())
        .sum();
    assert!((area - 2.0 * (2.0 + 6.0 + 3.0)).abs() < 1e-12);
    let mut c = Mesh::new();
    c.push_cylinder(DVec3::ZERO, 1.0, 2.0, 8);
    assert_eq!(c.triangle_count(), 4 * 8 - 4);
    c.push_cone(DVec3::ZERO, 1.0, 2.0, 8);
    assert_eq!(c.triangle_count(), 28 + 8 + 6);
    let mut g = Mesh::new();
    g.push_heightfield((0.0, 0.0), (4.0, 4.0), 4, |x, z| x + z);
    assert_eq!(g.triangle_count(), 32);
    assert_eq!(g.bounds().unwrap().max, Vec3::new(4.0, 8.0, 4.0));
    m.append(&g);
    assert_eq!(m.triangle_count(), 44);
    m.validate().unwrap();
    assert_eq!(m.triangle(12), g.triangle(0));
    assert!(Mesh::new().bounds().is_none());
}

#[test]
fn invalid_meshes_are_refused() {
    let mut m = Mesh::new();
    m.push_triangle([DVec3::ZERO, DVec3::X, DVec3::Y]);
    m.indices.push([0, 1, 3]);
    assert!(matches!(Bvh::build(&m), Err(EvalError::InvalidMesh { .. })));
    let mut m = Mesh::new();
    m.push_triangle([DVec3::ZERO, DVec3::X, DVec3::new(f64::NAN, 0.0, 0.0)]);
    assert!(matches!(m.validate(), Err(EvalError::InvalidMesh { .. })));
    assert!(m.bounds().is_none());
}

/// Möller–Trumbore, independent of the BVH's watertight test.
fn brute_force(mesh: &Mesh, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<(f64, usize)> {
    let mut best: Option<(f64, usize)> = None;
    for (i, [a, b, c]) in mesh.triangles().enumerate() {
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-300 {
            continue;
        }
        let s = o - a;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        let t = e2.dot(q) / det;
        let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > t_min && t < t_max;
        if inside && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, i));
        }
    }
    best
}

fn vec3(r: f64) -> impl Strategy<Value = DVec3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    #[test]
    fn bvh_agrees_with_brute_force(
        tris in prop::collection::vec((vec3(10.0), vec3(2.0), vec3(2.0)), 1..60),
        rays in prop::collection::vec((vec3(15.0), vec3(1.0), 0.0..5.0f64, 5.0..40.0f64), 16),
    ) {
        let mut mesh = Mesh::new();
        for (c, a, b) in &tris {
            mesh.push_triangle([*c, *c + *a, *c + *b]);
        }
        let bvh = Bvh::build(&mesh).unwrap();
        for (o, d, t_min, t_max) in rays {
            // Aim half the rays at a triangle so hits are common.
            let d = if t_min < 2.5 { mesh.triangle(0)[0] + d * 0.1 - o } else { d };
            let expected = brute_force(&mesh, o, d, t_min, t_max);
            let hit = bvh.intersect(o, d, t_min, t_max);
            match (expected, hit) {
                (None, None) => {}
                (Some((t, _)), Some(h)) => {
                    prop_assert!((t - h.t).abs() <= 1e-9 * (1.0 + t), "t {} vs {}", t, h.t);
                    let [a, b, c] = mesh.triangle(h.triangle);
                    let n = (b - a).cross(c - a);
                    // The hit lies on its triangle's plane, normal faces the origin.
                    prop_assert!(n.dot(h.position - a).abs() <= 1e-9 * n.length() * (1.0 + h.position.length()));
                    prop_assert!(h.normal.dot(d) <= 0.0);
                    prop_assert!((h.normal.length() - 1.0).abs() < 1e-12);
                }
                (e, h) => {
                    // Only grazing hits on an edge may differ between the two tests.
                    let t = e.map(|x| x.0).or(h.map(|x| x.t)).unwrap();
                    let p = o + d * t;
                    let near_edge = mesh.triangles().any(|[a, b, c]| {
                        [(a, b), (b, c), (c, a)].iter().any(|&(u, v)| {
                            let s = ((p - u).dot(v - u) / (v - u).length_squared()).clamp(0.0, 1.0);
                            (u + (v - u) * s - p).length() < 1e-7 * (1.0 + p.length())
                        })
                    });
                    prop_assert!(near_edge, "brute {:?} bvh {:?}", e, h);
                }
            }
            prop_assert_eq!(bvh.occluded(o, d, t_min, t_max), hit.is_some());
        }
    }
}

#[test]
fn rays_through_shared_edges_and_vertices_hit() {
    // A fan of 8 triangles around the origin in the z = 0 plane, and a quad split
    // along its diagonal.
    let mut mesh = Mesh::new();
    let n = 8;
    for k in 0..n {
        let a = std::f64::consts::TAU * f64::from(k) / f64::from(n);
        let b = std::f64::consts::TAU * f64::from(k + 1) / f64::from(n);
        mesh.push_triangle([
            DVec3::ZERO,
            DVec3::new(a.cos(), a.sin(), 0.0),
            DVec3::new(b.cos(), b.sin(), 0.0),
        ]);
    }
    let bvh = Bvh::build(&mesh).unwrap();
    // Through the shared centre vertex, from many directions.
    for i in 0..50 {
        let f = f64::from(i) * 0.37;
        let o = DVec3::new(f.cos() * 0.3, f.sin() * 0.3, 1.0 + 0.1 * f);
        assert!(bvh.intersect(o, -o, 0.0, 10.0).is_some(), "vertex ray {i}");
    }
    // Through points on the shared spokes.
    for k in 0..n {
        let a = std::f64::consts::TAU * f64::from(k) / f64::from(n);
        for s in [0.1, 1.0 / 3.0, 0.5, std::f64::consts::FRAC_1_SQRT_2, 0.99] {
            let p = DVec3::new(a.cos() * s, a.sin() * s, 0.0);
            for o in [DVec3::new(0.1, 0.2, 3.0), DVec3::new(-0.7, 0.3, -2.0)] {
                assert!(bvh.occluded(o, p - o, 0.0, 2.0), "edge {k} at {s}");
                let h = bvh.intersect(o, p - o, 0.0, 2.0).unwrap();
                assert!((h.t - 1.0).abs() < 1e-12);
            }
        }
    }
    let mut quad = Mesh::new();
    quad.push_quad([
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(3.0, 0.0, 0.0),
        DVec3::new(3.0, 0.0, 7.0),
        DVec3::new(0.0, 0.0, 7.0),
    ]);
    let bvh = Bvh::build(&quad).unwrap();
    for i in 1..100 {
        let s = f64::from(i) / 100.0;
        let p = DVec3::new(3.0 * s, 0.0, 7.0 * s);
        let o = p + DVec3::new(0.3, 1.0, -0.1) * (1.0 + s);
        assert!(bvh.occluded(o, p - o, 0.0, 1.5), "diagonal at {s}");
    }
}

#[test]
fn ray_interval_and_bad_rays() {
    let mut mesh = Mesh::new();
    mesh.push_box(DVec3::splat(-1.0), DVec3::splat(1.0));
    let bvh = Bvh::build(&mesh).unwrap();
    let o = DVec3::new(0.0, 0.0, 5.0);
    assert_eq!(bvh.intersect(o, DVec3::NEG_Z, 0.0, 10.0).unwrap().t, 4.0);
    // The far face when the near one is excluded.
    assert_eq!(bvh.intersect(o, DVec3::NEG_Z, 4.5, 10.0).unwrap().t, 6.0);
    assert!(!bvh.occluded(o, DVec3::NEG_Z, 0.0, 3.9));
    assert!(!bvh.occluded(o, DVec3::NEG_Z, 6.1, 9.0));
    assert!(bvh.intersect(o, DVec3::ZERO, 0.0, 10.0).is_none());
    assert!(
        bvh.intersect(o, DVec3::new(f64::NAN, 0.0, 0.0), 0.0, 10.0)
            .is_none()
    );
    assert!(bvh.intersect(o, DVec3::NEG_Z, 5.0, 1.0).is_none());
    assert!(!bvh.occluded(DVec3::splat(f64::INFINITY), DVec3::NEG_Z, 0.0, 1.0));
    // Axis-aligned ray skimming a face plane from inside the box's slab.
    assert!(
        bvh.intersect(DVec3::new(1.0, 0.0, 5.0), DVec3::NEG_Z, 0.0, 10.0)
            .is_some()
    );
    let empty = Bvh::build(&Mesh::new()).unwrap();
    assert!(empty.intersect(o, DVec3::NEG_Z, 0.0, 10.0).is_none());
}

#[test]
fn bvh_on_a_scene_matches_brute_force() {
    let scene = Scene::city_block(2);
    let bvh = Bvh::build(&scene.mesh).unwrap();
    assert_eq!(bvh.triangle_count(), scene.mesh.triangle_count());
    let mut hits = 0;
    for i in 0..200 {
        let f = f64::from(i);
        let o = DVec3::new(-150.0 + 1.5 * f, 30.0 + (f * 0.7).sin() * 20.0, 120.0);
        let d = DVec3::new((f * 0.31).sin() * 0.3, -0.35, -1.0);
        let e = brute_force(&scene.mesh, o, d, 0.0, f64::INFINITY);
        let h = bvh.intersect(o, d, 0.0, f64::INFINITY);
        assert_eq!(e.map(|x| x.1), h.map(|x| x.triangle), "ray {i}");
        hits += usize::from(h.is_some());
    }
    assert!(hits > 150);
}
