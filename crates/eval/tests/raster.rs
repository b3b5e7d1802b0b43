//! The reference rasterizer: coverage (top-left rule), depth, clipping, reversed-Z,
//! bias, the projectors, and agreement with the ray caster.

use glam::{DMat4, DVec3, DVec4, Vec3};
use shadowmap_eval::EvalError;
use shadowmap_eval::bvh::Bvh;
use shadowmap_eval::mask::{GBuffer, ShadowMask, ray_traced_mask, shadow_mask};
use shadowmap_eval::raster::{
    ClipVertex, DepthMap, DepthProjector, MatrixProjector, ParaboloidProjector, RasterOptions,
    RtwProjector, rasterize_depth,
};
use shadowmap_eval::scene::Mesh;
use shadowmap_frustum::{
    Camera, CascadeOptions, CascadeSet, CascadeSplits, Light, Projection, ShadowMapping,
    SplitScheme,
};
use shadowmap_paraboloid::{MapOptions, ParaboloidMap};
use shadowmap_rtw::{RtwShadow, WarpMaps};
use shadowmap_warp::{SceneBounds, UniformOptions, uniform_focused};

/// World = clip (w = 1): `x, y` are NDC directly.
fn ndc() -> MatrixProjector {
    MatrixProjector::new(vec![DMat4::IDENTITY], false)
}

/// The NDC point of pixel coordinates `(px, py)` (y down) at depth `z`.
fn at_pixel(px: f64, py: f64, w: u32, h: u32, z: f64) -> DVec3 {
    DVec3::new(
        px / f64::from(w) * 2.0 - 1.0,
        1.0 - py / f64::from(h) * 2.0,
        z,
    )
}

fn covered(map: &DepthMap) -> Vec<bool> {
    map.depth.iter().map(|&d| d != map.clear_value()).collect()
}

fn options(w: u32, h: u32) -> RasterOptions {
    RasterOptions::default().with_size(w, h)
}

#[test]
fn triangle_covers_the_hand_counted_pixels() {
    // Pixel-space right triangles splitting a 4×4 map along the anti-diagonal, which
    // runs through the centres (x + 1/2) + (y + 1/2) = 4.
    let (w, h) = (4, 4);
    let p = |x: f64, y: f64| at_pixel(x, y, w, h, 0.5);
    let mut upper = Mesh::new();
    upper.push_triangle([p(0.0, 0.0), p(4.0, 0.0), p(0.0, 4.0)]);
    let mut lower = Mesh::new();
    lower.push_triangle([p(4.0, 0.0), p(4.0, 4.0), p(0.0, 4.0)]);
    let a = covered(&rasterize_depth(&upper, &ndc(), &options(w, h)).unwrap());
    let b = covered(&rasterize_depth(&lower, &ndc(), &options(w, h)).unwrap());
    // Upper-left: x + y <= 2 strictly inside; the centres on the diagonal belong to
    // the lower triangle, for which the diagonal is a top-left edge.
    let expected_upper: Vec<bool> = (0..16).map(|i| i % 4 + i / 4 <= 2).collect();
    assert_eq!(a, expected_upper);
    assert_eq!(a.iter().filter(|&&c| c).count(), 6);
    assert!(a.iter().zip(&b).all(|(x, y)| x ^ y), "gap or overlap");
    // Either winding gives the same coverage (no culling).
    let mut flipped = Mesh::new();
    flipped.push_triangle([p(0.0, 4.0), p(4.0, 0.0), p(0.0, 0.0)]);
    assert_eq!(
        covered(&rasterize_depth(&flipped, &ndc(), &options(w, h)).unwrap()),
        a
    );
    // A top edge through pixel centres is covered, a bottom one is not.
    let mut band = Mesh::new();
    band.push_quad([p(0.0, 0.5), p(4.0, 0.5), p(4.0, 2.5), p(0.0, 2.5)]);
    let c = covered(&rasterize_depth(&band, &ndc(), &options(w, h)).unwrap());
    let rows: Vec<bool> = (0..4)
        .map(|y| c[y * 4..y * 4 + 4].iter().all(|&v| v))
        .collect();
    assert_eq!(rows, [true, true, false, false]);
    assert_eq!(c.iter().filter(|&&v| v).count(), 8);
}

/// `(b - a) x (p - a)` on integers (pixel coordinates times 256).
fn cross(a: (i64, i64), b: (i64, i64), p: (i64, i64)) -> i64 {
    (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
}

#[test]
fn quad_split_in_two_never_double_covers_or_leaves_a_gap() {
    let (w, h) = (16, 16);
    let offsets = [
        0.0,
        1.0 / 256.0,
        0.25,
        0.5,
        0.5 + 1.0 / 256.0,
        0.75,
        255.0 / 256.0,
    ];
    let shapes: [[(f64, f64); 4]; 3] = [
        [(2.0, 3.0), (13.0, 2.0), (12.0, 14.0), (1.0, 12.0)],
        [(2.0, 2.0), (12.0, 2.0), (12.0, 12.0), (2.0, 12.0)],
        [(0.0, 7.0), (8.0, 0.0), (15.0, 8.0), (7.0, 15.0)],
    ];
    let mut shared_edge_centres = 0;
    for shape in shapes {
        for &ox in &offsets {
            for &oy in &offsets {
                let q = shape.map(|(x, y)| (x + ox, y + oy));
                let world = q.map(|(x, y)| at_pixel(x, y, w, h, 0.5));
                let mut first = Mesh::new();
                first.push_triangle([world[0], world[1], world[2]]);
                let mut second = Mesh::new();
                second.push_triangle([world[0], world[2], world[3]]);
                let a = covered(&rasterize_depth(&first, &ndc(), &options(w, h)).unwrap());
                let b = covered(&rasterize_depth(&second, &ndc(), &options(w, h)).unwrap());
                let fixed =
                    q.map(|(x, y)| ((x * 256.0).round() as i64, (y * 256.0).round() as i64));
                for y in 0..h as i64 {
                    for x in 0..w as i64 {
                        let i = (y * i64::from(w) + x) as usize;
                        assert!(
                            !(a[i] && b[i]),
                            "double cover at ({x}, {y}), offset ({ox}, {oy})"
                        );
                        let c = (x * 256 + 128, y * 256 + 128);
                        // Clockwise on screen: inside where every cross product is > 0.
                        let e: Vec<i64> = (0..4)
                            .map(|k| cross(fixed[k], fixed[(k + 1) % 4], c))
                            .collect();
                        if e.iter().all(|&v| v > 0) {
                            assert!(a[i] || b[i], "gap at ({x}, {y}), offset ({ox}, {oy})");
                            if cross(fixed[0], fixed[2], c) == 0 {
                                shared_edge_centres += 1;
                            }
                        } else if e.iter().any(|&v| v < 0) {
                            assert!(!(a[i] || b[i]), "outside pixel ({x}, {y}) covered");
                        }
                    }
                }
            }
        }
    }
    // The diagonal did pass through pixel centres (the tie the fill rule decides).
    assert!(shared_edge_centres > 20, "{shared_edge_centres}");
}

#[test]
fn depth_is_the_plane_through_the_vertices() {
    let (w, h) = (64, 48);
    // Vertices on the subpixel grid, so snapping moves nothing.
    let v = [
        at_pixel(3.25, 2.5, w, h, 0.1),
        at_pixel(60.0, 10.75, w, h, 0.9),
        at_pixel(20.5, 45.0, w, h, 0.4),
    ];
    let mut mesh = Mesh::new();
    mesh.push_triangle(v);
    let map = rasterize_depth(&mesh, &ndc(), &options(w, h)).unwrap();
    // z = a x + b y + c in NDC.
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let plane = |x: f64, y: f64| v[0].z - (n.x * (x - v[0].x) + n.y * (y - v[0].y)) / n.z;
    let mut count = 0;
    for y in 0..h {
        for x in 0..w {
            let d = map.get(0, x, y);
            if d != map.clear_value() {
                let c = at_pixel(f64::from(x) + 0.5, f64::from(y) + 0.5, w, h, 0.0);
                let expected = plane(c.x, c.y);
                assert!(
                    (f64::from(d) - expected).abs() < 1e-7,
                    "({x}, {y}): {d} vs {expected}"
                );
                count += 1;
            }
        }
    }
    // Area of the triangle: 1134.8 pixels.
    assert!((1100..1170).contains(&count), "{count}");
}

/// A projector with a user clip distance equal to the NDC `y`.
struct ClipAboveAxis;

impl DepthProjector for ClipAboveAxis {
    fn layers(&self) -> u32 {
        1
    }
    fn reversed_z(&self) -> bool {
        false
    }
    fn project_vertex(&self, _layer: u32, world: DVec3) -> Option<ClipVertex> {
        Some(ClipVertex::new(world.extend(1.0), world.y))
    }
}

fn full_screen(z_left: f64, z_right: f64) -> Mesh {
    let mut m = Mesh::new();
    m.push_quad([
        DVec3::new(-1.0, -1.0, z_left),
        DVec3::new(1.0, -1.0, z_right),
        DVec3::new(1.0, 1.0, z_right),
        DVec3::new(-1.0, 1.0, z_left),
    ]);
    m
}

fn covered_columns(map: &DepthMap) -> Vec<u32> {
    (0..map.width)
        .filter(|&x| (0..map.height).all(|y| map.get(0, x, y) != map.clear_value()))
        .collect()
}

#[test]
fn clipping_keeps_exactly_the_inside_part() {
    let (w, h) = (8, 8);
    // z = x: the left half has z < 0 and is clipped away.
    let map = rasterize_depth(&full_screen(-1.0, 1.0), &ndc(), &options(w, h)).unwrap();
    assert_eq!(covered_columns(&map), [4, 5, 6, 7]);
    assert!((map.get(0, 4, 0) - 0.125).abs() < 1e-7);
    let cov = covered(&map).iter().filter(|&&c| c).count();
    assert_eq!(cov, 32);
    // z = x + 1/2: z < 0 left of x = -1/2, z > w right of x = 1/2.
    let map = rasterize_depth(&full_screen(-0.5, 1.5), &ndc(), &options(w, h)).unwrap();
    assert_eq!(covered_columns(&map), [2, 3, 4, 5]);
    assert_eq!(covered(&map).iter().filter(|&&c| c).count(), 32);
    // clip_distance = y keeps the top half (rows 0..4, v < 1/2).
    let map = rasterize_depth(&full_screen(0.5, 0.5), &ClipAboveAxis, &options(w, h)).unwrap();
    let rows: Vec<u32> = (0..h)
        .filter(|&y| (0..w).all(|x| map.get(0, x, y) == 0.5))
        .collect();
    assert_eq!(rows, [0, 1, 2, 3]);
    assert_eq!(covered(&map).iter().filter(|&&c| c).count(), 32);
    // Perspective: a ground plane crossing the near plane (w -> 0 behind the eye)
    // is cut at the near plane, never wraps around.
    let clip_from_world = shadowmap_frustum::projection::perspective(1.2, 1.0, 0.5, 50.0, false);
    let mut ground = Mesh::new();
    ground.push_quad([
        DVec3::new(-100.0, -1.0, 100.0),
        DVec3::new(100.0, -1.0, 100.0),
        DVec3::new(100.0, -1.0, -100.0),
        DVec3::new(-100.0, -1.0, -100.0),
    ]);
    let projector = MatrixProjector::new(vec![clip_from_world], false);
    let map = rasterize_depth(&ground, &projector, &options(w, h)).unwrap();
    // Below the horizon every pixel sees the ground; above it none.
    let c = covered(&map);
    assert!(
        c[..32].iter().all(|&v| !v) && c[32..].iter().all(|&v| v),
        "{c:?}"
    );
}

#[test]
fn reversed_z_flips_the_clear_value_and_the_test() {
    let mut mesh = full_screen(0.3, 0.3);
    mesh.append(&full_screen(0.6, 0.6));
    let standard = rasterize_depth(&mesh, &ndc(), &options(4, 4)).unwrap();
    assert!(standard.depth.iter().all(|&d| d == 0.3f32));
    assert_eq!(standard.clear_value(), 1.0);
    let reversed = MatrixProjector::new(vec![DMat4::IDENTITY], true);
    let map = rasterize_depth(&mesh, &reversed, &options(4, 4)).unwrap();
    assert!(map.depth.iter().all(|&d| d == 0.6f32));
    assert_eq!(map.clear_value(), 0.0);
    let empty = rasterize_depth(&Mesh::new(), &reversed, &options(4, 4)).unwrap();
    assert!(empty.depth.iter().all(|&d| d == 0.0));
    // The shadow test flips with it: a bias moves toward the light either way.
    let s = |depth: f64| shadowmap_frustum::ShadowSample {
        uv: glam::DVec2::splat(0.5),
        depth,
        layer: 0,
    };
    assert_eq!(standard.is_lit(&s(0.3), 0.0), Some(true));
    assert_eq!(standard.is_lit(&s(0.31), 0.0), Some(false));
    assert_eq!(standard.is_lit(&s(0.31), 0.02), Some(true));
    assert_eq!(map.is_lit(&s(0.6), 0.0), Some(true));
    assert_eq!(map.is_lit(&s(0.59), 0.0), Some(false));
    assert_eq!(map.is_lit(&s(0.59), 0.02), Some(true));
    assert_eq!(map.is_lit(&s(f64::NAN), 0.0), None);
    let outside = shadowmap_frustum::ShadowSample {
        uv: glam::DVec2::new(1.01, 0.5),
        depth: 0.5,
        layer: 0,
    };
    assert_eq!(map.lookup(&outside), None);
    assert_eq!(
        map.lookup(&shadowmap_frustum::ShadowSample { layer: 1, ..s(0.5) }),
        None
    );
}

#[test]
fn slope_scaled_bias_is_vulkans() {
    // z = x_ndc / 2 + 1/2 over 8 pixels: dz/dx = 1/8 per pixel.
    let mesh = full_screen(0.0, 1.0);
    let plain = rasterize_depth(&mesh, &ndc(), &options(8, 1)).unwrap();
    let biased = rasterize_depth(&mesh, &ndc(), &options(8, 1).with_depth_bias(0.0, 2.0)).unwrap();
    for x in 0..6 {
        let d = f64::from(biased.get(0, x, 0)) - f64::from(plain.get(0, x, 0));
        assert!((d - 0.25).abs() < 1e-6, "{d}");
    }
    // Clamped to [0, 1].
    assert_eq!(biased.get(0, 7, 0), 1.0);
    // Constant bias in units of r = 2^(e - 23), e the exponent of the largest depth.
    let flat = full_screen(0.3, 0.3);
    let biased = rasterize_depth(&flat, &ndc(), &options(2, 2).with_depth_bias(4.0, 0.0)).unwrap();
    let r = 2f64.powi(-2 - 23);
    assert_eq!(biased.get(0, 0, 0), (0.3 + 4.0 * r) as f32);
    assert!(biased.get(0, 0, 0) > f32::from_bits(0.3f32.to_bits() + 1));
}

#[test]
fn bad_options_are_refused() {
    let mesh = full_screen(0.5, 0.5);
    for o in [
        options(0, 4),
        options(4, 0),
        options(40_000, 4),
        options(4, 4).with_subpixel_bits(0),
        options(4, 4).with_subpixel_bits(17),
        options(16384, 16384).with_subpixel_bits(16),
        options(4, 4).with_depth_bias(f64::NAN, 0.0),
    ] {
        assert!(
            matches!(
                rasterize_depth(&mesh, &ndc(), &o),
                Err(EvalError::InvalidRasterSize { .. })
            ),
            "{o:?}"
        );
    }
    let none = MatrixProjector::new(vec![], false);
    assert!(rasterize_depth(&mesh, &none, &options(4, 4)).is_err());
    let mut bad = Mesh::new();
    bad.indices.push([0, 1, 2]);
    assert!(matches!(
        rasterize_depth(&bad, &ndc(), &options(4, 4)),
        Err(EvalError::InvalidMesh { .. })
    ));
    // Non-finite projections drop triangles instead of poisoning the map.
    let nan = MatrixProjector::new(vec![DMat4::from_diagonal(DVec4::splat(f64::NAN))], false);
    let map = rasterize_depth(&mesh, &nan, &options(4, 4)).unwrap();
    assert!(map.depth.iter().all(|&d| d == 1.0));
}

/// A ground square of half-size `half`, 8 × 8 cells.
fn ground(half: f64) -> Mesh {
    let mut m = Mesh::new();
    m.push_grid_quad(
        [
            DVec3::new(-half, 0.0, -half),
            DVec3::new(half, 0.0, -half),
            DVec3::new(half, 0.0, half),
            DVec3::new(-half, 0.0, half),
        ],
        8,
    );
    m
}

fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(0.0, 12.0, 22.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 4.0 / 3.0, 0.5, 80.0),
    )
    .unwrap()
}

const LIGHT: Vec3 = Vec3::new(0.4, -1.0, 0.3);

fn focus(mesh: &Mesh) -> SceneBounds {
    let b = mesh.bounds().unwrap();
    SceneBounds::new(b, b)
}

#[test]
fn shadow_transform_round_trip_on_a_ground_plane() {
    let mesh = ground(60.0);
    let t = uniform_focused(&camera(), LIGHT, &focus(&mesh), &UniformOptions::new()).unwrap();
    let projector = MatrixProjector::from(&t);
    let biased = options(1024, 1024).with_depth_bias(2.0, 1.0);
    let map = rasterize_depth(&mesh, &projector, &biased).unwrap();
    let raw = rasterize_depth(&mesh, &projector, &options(1024, 1024)).unwrap();
    let (mut covered, mut lit, mut acne) = (0, 0, 0);
    for i in 0..80 {
        for j in 0..80 {
            let p = DVec3::new(-40.0 + f64::from(i), 0.0, -40.0 + f64::from(j) * 0.8);
            let Some(sample) = t.map_point(p) else {
                continue;
            };
            let Some(l) = map.is_lit(&sample, 1e-7) else {
                continue;
            };
            covered += 1;
            lit += usize::from(l);
            acne += usize::from(raw.is_lit(&sample, 0.0) == Some(false));
        }
    }
    assert!(covered > 1000, "{covered}");
    assert_eq!(lit, covered, "biased map shadows its own receiver");
    // Without bias about half the samples lie behind their texel's centre.
    assert!(acne > covered / 5, "acne {acne} of {covered}");
}

/// Whether the ray from `p` toward the light hits the box.
fn box_shadows(p: DVec3, min: DVec3, max: DVec3) -> bool {
    let d = -LIGHT.as_dvec3();
    let t0 = (min - p) / d;
    let t1 = (max - p) / d;
    let enter = t0.min(t1).max_element();
    let exit = t0.max(t1).min_element();
    enter <= exit && exit > 0.0
}

#[test]
fn a_box_above_the_ground_shadows_the_expected_region() {
    let (bmin, bmax) = (DVec3::new(-2.0, 3.0, -2.0), DVec3::new(2.0, 4.0, 2.0));
    let mut mesh = ground(60.0);
    mesh.push_box(bmin, bmax);
    let t = uniform_focused(&camera(), LIGHT, &focus(&mesh), &UniformOptions::new()).unwrap();
    let map = rasterize_depth(
        &mesh,
        &MatrixProjector::from(&t),
        &options(1024, 1024).with_depth_bias(2.0, 1.0),
    )
    .unwrap();
    let (mut shadowed, mut checked) = (0, 0);
    for i in 0..200 {
        for j in 0..200 {
            let p = DVec3::new(-5.0 + 0.1 * f64::from(i), 0.0, -5.0 + 0.1 * f64::from(j));
            let texel = f64::from(t.texel_world_size(p.as_vec3(), 1024).unwrap());
            let expected = box_shadows(p, bmin, bmax);
            // Skip points within two texels of the shadow's edge.
            let near_edge = (0..8).any(|k| {
                let a = f64::from(k) * std::f64::consts::FRAC_PI_4;
                let q = p + DVec3::new(a.cos(), 0.0, a.sin()) * 2.0 * texel;
                box_shadows(q, bmin, bmax) != expected
            });
            if near_edge {
                continue;
            }
            let lit = map.is_lit(&t.map_point(p).unwrap(), 1e-7).unwrap();
            assert_eq!(lit, !expected, "at {p}");
            checked += 1;
            shadowed += usize::from(expected);
        }
    }
    assert!(
        checked > 35_000 && shadowed > 1000,
        "{checked} checked, {shadowed} shadowed"
    );
}

#[test]
fn cascade_set_gives_one_layer_per_cascade() {
    let mesh = ground(60.0);
    let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 3, 0.5, 80.0).unwrap();
    let set = CascadeSet::fit(&camera(), LIGHT, &splits, &CascadeOptions::default()).unwrap();
    let projector = MatrixProjector::from(&set);
    assert_eq!(projector.layers(), 3);
    let map = rasterize_depth(&mesh, &projector, &options(64, 64)).unwrap();
    for (k, c) in set.cascades.iter().enumerate() {
        let single = rasterize_depth(
            &mesh,
            &MatrixProjector::from(&c.transform),
            &options(64, 64),
        )
        .unwrap();
        assert_eq!(&map.depth[k * 4096..(k + 1) * 4096], &single.depth[..]);
        assert!(single.depth.iter().any(|&d| d < 1.0));
    }
}

#[test]
fn paraboloid_projector_splits_hemispheres_into_layers() {
    let map =
        ParaboloidMap::dual(Vec3::ZERO, Vec3::NEG_Y, 0.1, 20.0, &MapOptions::default()).unwrap();
    let projector = ParaboloidProjector::from(&map);
    assert_eq!(projector.layers(), 2);
    // A small triangle below the light (front side) and one above (back side).
    let tri = |c: DVec3| {
        [
            c + DVec3::new(-0.2, 0.0, -0.2),
            c + DVec3::new(0.2, 0.0, -0.2),
            c + DVec3::new(0.0, 0.0, 0.25),
        ]
    };
    let below = DVec3::new(1.0, -3.0, 0.5);
    let above = DVec3::new(-0.5, 4.0, 1.0);
    let mut mesh = Mesh::new();
    mesh.push_triangle(tri(below));
    mesh.push_triangle(tri(above));
    let depth = rasterize_depth(&mesh, &projector, &options(256, 256)).unwrap();
    for (c, layer, other) in [(below, 0, 1), (above, 1, 0)] {
        let s = map.map_point(c).unwrap();
        assert_eq!(s.layer, layer);
        let stored = f64::from(depth.lookup(&s).unwrap());
        assert!((stored - s.depth).abs() < 1e-3, "{stored} vs {}", s.depth);
        let elsewhere = shadowmap_frustum::ShadowSample { layer: other, ..s };
        assert_eq!(depth.lookup(&elsewhere), Some(1.0));
    }
    // A big wall through the light's plane is clipped at the hemisphere: each layer
    // gets its half, nothing wraps to the rim of the other side.
    // Tessellated: a paraboloid's depth is not linear over big triangles.
    let mut wall = Mesh::new();
    wall.push_grid_quad(
        [
            DVec3::new(-5.0, -5.0, -3.0),
            DVec3::new(5.0, -5.0, -3.0),
            DVec3::new(5.0, 5.0, -3.0),
            DVec3::new(-5.0, 5.0, -3.0),
        ],
        32,
    );
    let depth = rasterize_depth(&wall, &projector, &options(128, 128)).unwrap();
    for layer in 0..2 {
        let n = (0..128 * 128)
            .filter(|&i| depth.depth[layer * 128 * 128 + i] < 1.0)
            .count();
        assert!(n > 500, "layer {layer}: {n}");
    }
    let s = map.map_point(DVec3::new(0.0, -2.0, -3.0)).unwrap();
    assert!((f64::from(depth.lookup(&s).unwrap()) - s.depth).abs() < 0.01);
}

#[test]
fn rtw_with_identity_warps_renders_the_base_map() {
    let mesh = {
        let mut m = ground(60.0);
        m.push_box(DVec3::new(-2.0, 0.0, -2.0), DVec3::new(2.0, 3.0, 2.0));
        m
    };
    let t = uniform_focused(&camera(), LIGHT, &focus(&mesh), &UniformOptions::new()).unwrap();
    let warps = WarpMaps::new(64, 64).unwrap();
    let shadow = RtwShadow {
        base: t,
        warps: &warps,
    };
    let rtw = rasterize_depth(&mesh, &RtwProjector::from(shadow), &options(128, 128)).unwrap();
    let base = rasterize_depth(&mesh, &MatrixProjector::from(&t), &options(128, 128)).unwrap();
    let same = rtw
        .depth
        .iter()
        .zip(&base.depth)
        .filter(|(a, b)| (**a - **b).abs() < 1e-6)
        .count();
    // Identity warps up to rounding of the snapped vertices.
    assert!(same >= 128 * 128 - 8, "{same}");
}

/// Whether a visible point lies within `radius` (world units, measured across the
/// light's rays) of a shadow boundary: some point of its surface plane whose light ray
/// passes within `radius` of its own has the other exact (ray-traced) answer. Points
/// on surfaces nearly parallel to the light count as on a boundary.
fn near_shadow_boundary(bvh: &Bvh, surface: &shadowmap_eval::mask::Surface, radius: f64) -> bool {
    let to_light = -LIGHT.as_dvec3().normalize();
    let n = surface.normal;
    if n.dot(to_light).abs() < 0.05 {
        return true;
    }
    let lit = |p: DVec3| !bvh.occluded(p + n * 1e-4, to_light, 0.0, f64::INFINITY);
    let here = lit(surface.position);
    let right = to_light.any_orthonormal_vector();
    let up = to_light.cross(right);
    (0..16).any(|k| {
        let a = f64::from(k) * std::f64::consts::TAU / 16.0;
        let o = (right * a.cos() + up * a.sin()) * radius;
        // Slide along the light ray back onto the surface plane.
        let q = surface.position + o - to_light * (n.dot(o) / n.dot(to_light));
        lit(q) != here
    })
}

/// With a map far finer than the image, the reference
/// rasterizer and the ray caster agree exactly on every pixel whose visible point is
/// not within about one texel of a shadow boundary (there the texel grid itself, a
/// half-texel away from the exact ray, legitimately flips the answer). The excluded
/// fraction is bounded by 5 %.
#[test]
fn rasterizer_and_ray_caster_agree_with_a_fine_map() {
    let mut mesh = ground(60.0);
    mesh.push_box(DVec3::new(-2.0, 0.0, -2.0), DVec3::new(2.0, 3.0, 2.0));
    mesh.push_cylinder(DVec3::new(5.0, 0.0, 1.0), 0.15, 6.0, 8);
    let bvh = Bvh::build(&mesh).unwrap();
    let camera = camera();
    let t = uniform_focused(&camera, LIGHT, &focus(&mesh), &UniformOptions::new()).unwrap();
    let resolution = 4096;
    let map = rasterize_depth(
        &mesh,
        &MatrixProjector::from(&t),
        &options(resolution, resolution).with_depth_bias(2.0, 1.0),
    )
    .unwrap();
    let (w, h) = (64, 48);
    let light = Light::Directional { direction: LIGHT };
    let gbuffer = GBuffer::trace(&bvh, &camera, w, h).unwrap();
    let truth = ShadowMask::ray_traced(&gbuffer, &bvh, &light).unwrap();
    let mapped = ShadowMask::from_map(&gbuffer, &t, &map, 1e-7);
    assert_eq!(truth, ray_traced_mask(&bvh, &camera, w, h, &light).unwrap());
    assert_eq!(
        mapped,
        shadow_mask(&bvh, &camera, w, h, &t, &map, 1e-7).unwrap()
    );
    let (mut compared, mut excluded, mut shadowed) = (0, 0, 0);
    for (i, s) in gbuffer.surfaces.iter().enumerate() {
        let Some(s) = s else { continue };
        // An orthographic map: one texel is the same size everywhere.
        let texel = f64::from(
            t.texel_world_size(s.position.as_vec3(), resolution)
                .unwrap(),
        );
        if near_shadow_boundary(&bvh, s, 1.5 * texel) {
            excluded += 1;
            continue;
        }
        assert_eq!(mapped.lit[i], truth.lit[i], "pixel {i} at {}", s.position);
        compared += 1;
        shadowed += usize::from(truth.lit[i] == Some(false));
    }
    let visible = gbuffer.visible_count();
    assert_eq!(mapped.count(None), w as usize * h as usize - visible);
    assert!(visible > w as usize * h as usize / 2, "{visible}");
    assert!(shadowed > 50, "{shadowed} shadowed pixels");
    assert!(excluded * 20 < visible, "excluded {excluded} of {visible}");
    assert!(compared > 0);
    eprintln!("compared {compared}, excluded {excluded} of {visible} visible, {shadowed} shadowed");
    // Over all visible pixels, the masks differ only on excluded ones.
    let c = mapped.compare(&truth);
    assert_eq!(c.compared, visible);
    assert!(c.misclassified() <= excluded);
}

#[test]
fn unlit_geometry_outside_the_map_is_unclassified() {
    let mesh = ground(60.0);
    let bvh = Bvh::build(&mesh).unwrap();
    // A map covering only x, z in [-10, 10] of the ground (top view).
    let clip_from_world = DMat4::from_cols(
        DVec4::new(0.1, 0.0, 0.0, 0.0),
        DVec4::new(0.0, 0.0, -0.01, 0.0),
        DVec4::new(0.0, -0.1, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 0.5, 1.0),
    );
    let t = shadowmap_frustum::ShadowTransform::new(
        glam::Mat4::IDENTITY,
        clip_from_world.as_mat4(),
        false,
        shadowmap_frustum::LightDirection::Directional(Vec3::NEG_Y),
    );
    let map = rasterize_depth(&mesh, &MatrixProjector::from(&t), &options(32, 32)).unwrap();
    let mask = shadow_mask(&bvh, &camera(), 32, 24, &t, &map, 1e-6).unwrap();
    let classified = mask.count(Some(true)) + mask.count(Some(false));
    assert!(
        classified > 0 && mask.count(None) > classified,
        "{classified}"
    );
    assert_eq!(mask.count(Some(false)), 0);
}
