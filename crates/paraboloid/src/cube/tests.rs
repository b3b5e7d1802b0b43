//! Tests of the cube maps; [`street`] is shared with the tiled cube map's tests.

use glam::Vec4;
use shadowmap_frustum::Projection;

use super::*;

/// A street under a lamp ahead of the eye (five faces kept); shared with the
/// tiled cube map's tests.
pub(crate) fn street() -> (Camera, Light, SceneBounds) {
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, -0.2, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.5, 300.0),
    )
    .unwrap();
    let light = Light::Point {
        position: Vec3::new(5.0, 6.0, -30.0),
        range: 200.0,
    };
    let ground = Aabb::new(Vec3::new(-150.0, 0.0, -320.0), Vec3::new(150.0, 1.0, 20.0));
    let scene = SceneBounds::new(ground, Aabb::new(ground.min, ground.max + 30.0 * Vec3::Y));
    (camera, light, scene)
}

/// The depth pass (the `f32` clip matrix, divided by `w`) puts a point where the
/// lookup does, for both depth conventions.
#[test]
fn clip_matrix_agrees_with_the_lookup() {
    let (camera, light, scene) = street();
    let orientations = [
        CubeOrientation::WorldAxes,
        CubeOrientation::TowardReceivers,
        CubeOrientation::CornerUp,
    ];
    let cases = [false, true]
        .into_iter()
        .flat_map(|reversed| orientations.map(|o| (reversed, o)));
    for (reversed, orientation) in cases {
        let options = CubeOptions::default()
            .with_reversed_z(reversed)
            .with_orientation(orientation);
        let cube = CubeMap::fit(&light, &camera, None, &scene, &options).unwrap();
        let turned = cube.orientation() != Quat::IDENTITY;
        assert_eq!(turned, orientation != CubeOrientation::WorldAxes);
        let mut checked = 0;
        for x in [-40.0, -5.0, 0.0, 7.0, 30.0] {
            for z in [-200.0, -60.0, -31.0, -29.0, -10.0] {
                let p = Vec3::new(x, 0.5, z);
                let Some(s) = cube.map_point(p.as_dvec3()) else {
                    continue;
                };
                let face = &cube.faces[s.layer as usize];
                let c = face.clip_from_world * Vec4::new(p.x, p.y, p.z, 1.0);
                let ndc = c.truncate() / c.w;
                let uv = DVec2::new(0.5 + 0.5 * f64::from(ndc.x), 0.5 - 0.5 * f64::from(ndc.y));
                assert!(
                    (uv - s.uv).abs().max_element() < 1e-5,
                    "{p}: {uv} {:?}",
                    s.uv
                );
                assert!(
                    (f64::from(ndc.z) - s.depth).abs() < 1e-5,
                    "{p}: {} {}",
                    ndc.z,
                    s.depth
                );
                checked += 1;
            }
        }
        assert!(checked >= 20, "{checked}");
    }
}

/// Receivers ahead of a lamp along a diagonal of the world axes fall across two
/// world-axis side faces; turned toward them, across one: the turned cube keeps
/// fewer faces, each side face looking along the diagonal or across it, and
/// predicted on the receivers' box, its error is the smaller one.
#[test]
fn a_cube_turned_toward_the_receivers_holds_them_in_fewer_faces() {
    let diagonal = Vec3::new(1.0, 0.0, -1.0).normalize();
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        diagonal + Vec3::new(0.0, -0.3, 0.0),
        Vec3::Y,
        Projection::perspective(0.8, 1.5, 0.5, 80.0),
    )
    .unwrap();
    let light = Light::Point {
        position: Vec3::new(-3.0, 5.0, 3.0),
        range: 200.0,
    };
    let ground = Aabb::new(Vec3::new(-100.0, 0.0, -100.0), Vec3::new(100.0, 0.5, 100.0));
    let scene = SceneBounds::new(ground, ground);
    let fit = |orientation| {
        let options = CubeOptions::default().with_orientation(orientation);
        CubeMap::fit(&light, &camera, None, &scene, &options).unwrap()
    };
    let (world, turned) = (
        fit(CubeOrientation::WorldAxes),
        fit(CubeOrientation::TowardReceivers),
    );
    assert!(turned.layers() < world.layers(), "{world:?}\n{turned:?}");
    let side = turned
        .faces
        .iter()
        .find(|f| !matches!(f.face, CubeFaceId::PosY | CubeFaceId::NegY))
        .unwrap();
    let forward = side.orientation * side.face.forward();
    assert!(forward.dot(diagonal).abs() > 0.99 || forward.dot(diagonal).abs() < 0.01);
    assert_eq!(fit(CubeOrientation::Predicted), turned);
}

/// Focused windows lie in the face and the unfocused map keeps the same faces;
/// the up face, seeing nothing visible, is skipped by both.
#[test]
fn focused_windows_are_inside_the_same_faces() {
    let (camera, light, scene) = street();
    let focused = CubeMap::fit(&light, &camera, None, &scene, &CubeOptions::default()).unwrap();
    let options = CubeOptions::default().with_focused(false);
    let full = CubeMap::fit(&light, &camera, None, &scene, &options).unwrap();
    let ids = |c: &CubeMap| c.faces.iter().map(|f| f.face).collect::<Vec<_>>();
    assert_eq!(ids(&focused), ids(&full));
    assert_eq!(focused.layer_of(CubeFaceId::PosY), None);
    for (f, u) in focused.faces.iter().zip(&full.faces) {
        assert!(f.tan_min.cmpge(u.tan_min - 1e-4).all() && f.tan_max.cmple(u.tan_max + 1e-4).all());
        assert!(f.near >= u.near && f.far <= u.far);
    }
    // The face looking away from the view (+Z, behind the camera) sees less.
    let area = |f: &CubeFace| (f.tan_max - f.tan_min).element_product();
    assert!(focused.faces.iter().any(|f| area(f) < 2.0));
}

/// Equal sides make a column of layers; sides by need give the face toward the
/// eye's near ground (the light's `+Z` face, the camera being behind it along
/// `+Z`) the most texels; both stay within the budget, their tiles apart, and a
/// sample lands in its face's tile of the atlas.
#[test]
fn faces_share_the_budget() {
    let (camera, light, scene) = street();
    let budget = 512 * 512;
    let equal = CubeOptions::default()
        .with_texel_budget(budget)
        .with_sizes(FaceSizes::Equal);
    let cube = CubeMap::fit(&light, &camera, None, &scene, &equal).unwrap();
    assert!(cube.has_equal_faces());
    let [side, _] = cube.faces[0].size;
    assert_eq!(cube.atlas, [side, side * cube.layers()]);
    let by_need = equal.with_sizes(FaceSizes::ByNeed);
    let cube = CubeMap::fit(&light, &camera, None, &scene, &by_need).unwrap();
    assert!(!cube.has_equal_faces());
    assert!(
        cube.texels() <= budget && cube.texels() > budget / 2,
        "{}",
        cube.texels()
    );
    assert!(cube.faces.iter().all(|f| f.size[0] == f.size[1]));
    let largest = cube.faces.iter().max_by_key(|f| f.size[0]).unwrap();
    assert_eq!(largest.face, CubeFaceId::PosZ, "{:?}", cube.faces);
    let p = DVec3::new(1.0, 0.5, -10.0);
    let s = cube.map_point(p).unwrap();
    let a = cube.atlas_sample(s).unwrap();
    let f = &cube.faces[s.layer as usize];
    let pair = |p: [u32; 2]| DVec2::new(f64::from(p[0]), f64::from(p[1]));
    let texel = a.uv * pair(cube.atlas);
    let lo = pair(f.offset);
    assert!(texel.cmpge(lo).all() && texel.cmple(lo + pair(f.size)).all());
    assert_eq!((a.layer, a.depth), (0, s.depth));
}

/// A face drawn into the corner of a layer of the largest face's side lands
/// where its own `uv`, scaled by its share of the layer, says: the corner
/// clip matrix and the scaled lookup agree, and the face keeps its texels.
#[test]
fn faces_drawn_into_layer_corners_keep_their_uv() {
    let (camera, light, scene) = street();
    let by_need = CubeOptions::default().with_sizes(FaceSizes::ByNeed);
    let cube = CubeMap::fit(&light, &camera, None, &scene, &by_need).unwrap();
    let side = cube.largest_side();
    for f in &cube.faces {
        let texels = f.uv_scale_in_layer(side).as_dvec2() * f64::from(side);
        let size = DVec2::new(f64::from(f.size[0]), f64::from(f.size[1]));
        assert!(
            (texels - size).abs().max_element() < 1e-3,
            "{texels} {size}"
        );
    }
    let mut checked = 0;
    for x in [-40.0, -5.0, 0.0, 7.0, 30.0] {
        for z in [-200.0, -60.0, -31.0, -29.0, -10.0] {
            let p = DVec3::new(x, 0.5, z);
            let Some(s) = cube.map_point(p) else {
                continue;
            };
            let face = &cube.faces[s.layer as usize];
            let c = face.clip_from_world_in_layer(side).as_dmat4() * p.extend(1.0);
            let ndc = c.truncate() / c.w;
            let uv = DVec2::new(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
            let scaled = s.uv * face.uv_scale_in_layer(side).as_dvec2();
            assert!(
                (uv - scaled).abs().max_element() < 1e-5,
                "{p}: {uv} {scaled}"
            );
            checked += 1;
        }
    }
    assert!(checked >= 20, "{checked}");
}

#[test]
fn bad_input_is_a_typed_error() {
    let (camera, light, scene) = street();
    let o = CubeOptions::default();
    let sun = Light::Directional {
        direction: Vec3::NEG_Y,
    };
    assert_eq!(
        CubeMap::fit(&sun, &camera, None, &scene, &o),
        Err(ParaboloidError::UnsupportedLight)
    );
    let nan = Light::Point {
        position: Vec3::NAN,
        range: 10.0,
    };
    assert_eq!(
        CubeMap::fit(&nan, &camera, None, &scene, &o),
        Err(ParaboloidError::NonFinite)
    );
    for bad in [o.with_near(0.0), o.with_texel_budget(0)] {
        assert_eq!(
            CubeMap::fit(&light, &camera, None, &scene, &bad),
            Err(ParaboloidError::InvalidOptions)
        );
    }
    let short = Light::Point {
        position: Vec3::new(0.0, 100.0, 300.0),
        range: 1.0,
    };
    assert_eq!(
        CubeMap::fit(&short, &camera, None, &scene, &o),
        Err(ParaboloidError::Frustum(FrustumError::SliceOutsideScene))
    );
    let tiny = Light::Point {
        position: Vec3::ZERO,
        range: 0.01,
    };
    assert!(matches!(
        CubeMap::fit(&tiny, &camera, None, &scene, &o),
        Err(ParaboloidError::InvalidDepthRange { .. })
    ));
}
