//! Tests of the error prediction.
use glam::{Mat4, Vec3};

use super::*;
use crate::{LightDirection, Projection, ShadowTransform};

fn camera() -> Camera {
    Camera::look_to(
        Vec3::new(0.0, 10.0, 0.0),
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 1.0, 200.0),
    )
    .unwrap()
}

/// An overhead orthographic map of `[-a, a]²` in x, z.
fn overhead(a: f32) -> ShadowTransform {
    let clip_from_world = Mat4::from_cols(
        glam::Vec4::new(1.0 / a, 0.0, 0.0, 0.0),
        glam::Vec4::new(0.0, 0.0, -0.001, 0.0),
        glam::Vec4::new(0.0, -1.0 / a, 0.0, 0.0),
        glam::Vec4::new(0.0, 0.0, 0.5, 1.0),
    );
    ShadowTransform::new(
        Mat4::IDENTITY,
        clip_from_world,
        false,
        LightDirection::Directional(Vec3::NEG_Y),
    )
}

fn ground() -> Aabb {
    Aabb::new(Vec3::new(-200.0, 0.0, -210.0), Vec3::new(200.0, 30.0, 10.0))
}

#[test]
fn faces_the_light_does_not_face_are_left_out() {
    // From inside the box the rays leave through the floor (lit from above), the
    // far wall and the ceiling (not lit).
    let map = overhead(400.0);
    let predict = |options: PredictOptions| {
        predict_error(&camera(), &ground(), &map, 1024, &options)
            .unwrap()
            .unwrap()
    };
    let all = predict(PredictOptions::default());
    let lit = predict(PredictOptions::default().with_light_direction(Vec3::NEG_Y));
    assert!(
        lit.rays > 0 && lit.rays < all.rays,
        "{} of {}",
        lit.rays,
        all.rays
    );
    // Lit from below, only the ceiling counts.
    let below = predict(PredictOptions::default().with_light_direction(Vec3::Y));
    assert!(below.rays > 0 && below.rays < all.rays);
    // A zero direction is no light: every ray.
    let none = predict(PredictOptions::default().with_light_direction(Vec3::ZERO));
    assert_eq!(none, all);
}

#[test]
fn a_positional_light_lights_the_faces_that_face_it() {
    let map = overhead(400.0);
    let predict = |options: PredictOptions| {
        predict_error(&camera(), &ground(), &map, 1024, &options)
            .unwrap()
            .unwrap()
    };
    // Far above the box a light position acts as a light straight down, far below
    // as one straight up.
    let down = predict(PredictOptions::default().with_light_direction(Vec3::NEG_Y));
    let high = Vec3::new(0.0, 1.0e6, -100.0);
    assert_eq!(
        predict(PredictOptions::default().with_light_position(high)),
        down
    );
    let up = predict(PredictOptions::default().with_light_direction(Vec3::Y));
    let low = Vec3::new(0.0, -1.0e6, -100.0);
    assert_eq!(
        predict(PredictOptions::default().with_light_position(low)),
        up
    );
    // The position wins over a direction.
    let both = PredictOptions::default()
        .with_light_direction(Vec3::Y)
        .with_light_position(high);
    assert_eq!(predict(both), down);
    // Between the floor and the ceiling it lights both (and the far wall).
    let inside =
        predict(PredictOptions::default().with_light_position(Vec3::new(0.0, 20.0, -100.0)));
    assert!(
        inside.rays > down.rays && inside.rays > up.rays,
        "{inside:?}"
    );
    // A non-finite position is none.
    let nan = PredictOptions::default().with_light_position(Vec3::NAN);
    assert_eq!(nan.light_position, None);
}

#[test]
fn a_finer_map_predicts_a_proportionally_smaller_error() {
    let (c, g, map) = (camera(), ground(), overhead(250.0));
    let o = PredictOptions::default();
    let coarse = predict_error(&c, &g, &map, 512, &o).unwrap().unwrap();
    let fine = predict_error(&c, &g, &map, 2048, &o).unwrap().unwrap();
    assert!(coarse.rays > 50, "{coarse:?}");
    assert!((coarse.percentile / fine.percentile - 4.0).abs() < 1e-6);
    assert!(coarse.max >= coarse.percentile);
    // A map four times larger in world units has four times larger texels.
    let wide = predict_error(&c, &g, &overhead(1000.0), 2048, &o)
        .unwrap()
        .unwrap();
    assert!((wide.percentile / fine.percentile - 4.0).abs() < 1e-3);
}

#[test]
fn the_ground_under_an_overhead_map_has_the_textbook_error() {
    // A level pinhole camera 10 m above the ground: a pixel at view depth z is
    // 2 z tan(30°) / 1080 wide, and an overhead map of 500 m over 2048 texels has
    // 2048 / 500 texels per metre, so m >= 1080 / (2 z tan 30°) / (2048 / 500),
    // with equality for the width of the pixel (the foreshortened height is longer).
    // The largest m is at the lowest row of rays, the nearest ground.
    let (c, g, map) = (camera(), ground(), overhead(250.0));
    let o = PredictOptions::default().with_percentile(1.0);
    let p = predict_error(&c, &g, &map, 2048, &o).unwrap().unwrap();
    assert_eq!(p.percentile, p.max);
    let tan = 30f64.to_radians().tan();
    let lowest = ((8.0 / 9.0) * tan).atan();
    let z = 10.0 / lowest.tan();
    let across = 1080.0 / (2.0 * z * tan) / (2048.0 / 500.0);
    assert!(
        p.max >= 0.999 * across && p.max <= 1.5 * across,
        "{} vs {across}",
        p.max
    );
}

#[test]
fn nothing_met_or_bad_input_is_reported() {
    let (c, map) = (camera(), overhead(250.0));
    let away = Aabb::new(Vec3::splat(1000.0), Vec3::splat(1001.0));
    let o = PredictOptions::default();
    assert_eq!(predict_error(&c, &away, &map, 1024, &o), Ok(None));
    let inverted = Aabb::new(Vec3::ONE, Vec3::ZERO);
    assert_eq!(
        predict_error(&c, &inverted, &map, 1024, &o),
        Err(FrustumError::EmptyBounds)
    );
    assert_eq!(
        predict_error(&c, &ground(), &map, 0, &o),
        Err(FrustumError::InvalidResolution)
    );
    for bad in [
        o.with_grid(0, 4),
        o.with_grid(64, 64),
        o.with_percentile(0.0),
        o.with_percentile(f64::NAN),
        o.with_viewport_height(0),
    ] {
        assert_eq!(
            predict_error(&c, &ground(), &map, 1024, &bad),
            Err(FrustumError::InvalidResolution)
        );
    }
}

/// A wrapped map's differentials where a wrapper covers all five points (as it
/// maps them one by one: the wrapped map's own, where it covers them).
fn differentials_where(
    map: &ShadowTransform,
    centre: glam::DVec3,
    around: &[glam::DVec3; 4],
    covers: impl Fn(&glam::DVec3) -> bool,
) -> Option<[glam::DVec2; 2]> {
    let covered = core::iter::once(&centre).chain(around).all(covers);
    covered
        .then(|| map.uv_differentials(centre, around))
        .flatten()
}

/// A mapping that covers only points nearer than `depth` in front of the camera.
struct NearOnly(ShadowTransform, f64);

impl ShadowMapping for NearOnly {
    fn map_point(&self, world: glam::DVec3) -> Option<crate::ShadowSample> {
        (-world.z < self.1)
            .then(|| self.0.map_point(world))
            .flatten()
    }

    fn uv_differentials(
        &self,
        centre: glam::DVec3,
        around: &[glam::DVec3; 4],
    ) -> Option<[glam::DVec2; 2]> {
        differentials_where(&self.0, centre, around, |p| -p.z < self.1)
    }
}

#[test]
fn candidates_are_compared_on_the_rays_all_of_them_cover() {
    let (c, g, map) = (camera(), ground(), overhead(250.0));
    let near = NearOnly(map, 40.0);
    let o = PredictOptions::default();
    let mut out = [None; 2];
    predict_errors(&c, &g, &[(&map, 1024), (&near, 1024)], &o, &mut out).unwrap();
    let (all, near_only) = (out[0].unwrap(), out[1].unwrap());
    // The same rays, the same mapping there: the same prediction.
    assert_eq!(all, near_only);
    let alone = predict_error(&c, &g, &map, 1024, &o).unwrap().unwrap();
    assert!(all.rays < alone.rays, "{all:?} vs {alone:?}");
    // No shared ray: each on its own rays.
    let nowhere = NearOnly(map, 0.0);
    predict_errors(&c, &g, &[(&map, 1024), (&nowhere, 1024)], &o, &mut out).unwrap();
    assert_eq!(out, [Some(alone), None]);
    // Too many candidates, or an output of another length.
    let many = [(&map as &dyn ShadowMapping, 1024u32); MAX_PREDICT_CANDIDATES + 1];
    let mut nine = [None; MAX_PREDICT_CANDIDATES + 1];
    assert_eq!(
        predict_errors(&c, &g, &many, &o, &mut nine),
        Err(FrustumError::InvalidResolution)
    );
    assert_eq!(
        predict_errors(&c, &g, &[(&map, 1024)], &o, &mut out),
        Err(FrustumError::InvalidResolution)
    );
}

/// A mapping that covers only view depths in `[near, far]` (the camera of
/// `camera()` looks down `-Z` from `z = 0`).
struct DepthOnly(ShadowTransform, f64, f64);

impl ShadowMapping for DepthOnly {
    fn map_point(&self, world: glam::DVec3) -> Option<crate::ShadowSample> {
        (-world.z >= self.1 && -world.z <= self.2)
            .then(|| self.0.map_point(world))
            .flatten()
    }

    fn uv_differentials(
        &self,
        centre: glam::DVec3,
        around: &[glam::DVec3; 4],
    ) -> Option<[glam::DVec2; 2]> {
        differentials_where(&self.0, centre, around, |p| {
            -p.z >= self.1 && -p.z <= self.2
        })
    }
}

#[test]
fn points_stay_within_the_depth_bounds() {
    let (c, g, map) = (camera(), ground(), overhead(250.0));
    let slab = DepthOnly(map, 20.0, 40.0);
    let o = PredictOptions::default().with_light_direction(Vec3::NEG_Y);
    let mut out = [None; 2];
    // Without bounds most rays meet the box outside the slab.
    predict_errors(&c, &g, &[(&map, 1024), (&slab, 1024)], &o, &mut out).unwrap();
    let unbounded = out[0].unwrap();
    // With them, every point lies in it: the slab covers every ray the map does.
    let bounded = o.with_depth_range(20.0, 40.0);
    predict_errors(&c, &g, &[(&map, 1024), (&slab, 1024)], &bounded, &mut out).unwrap();
    let (all, inside) = (out[0].unwrap(), out[1].unwrap());
    assert_eq!(all, inside);
    assert!(all.rays > unbounded.rays, "{all:?} vs {unbounded:?}");
    // Invalid bounds are none.
    assert_eq!(o.with_depth_range(40.0, 20.0).depth_range, None);
    assert_eq!(o.with_depth_range(0.0, 20.0).depth_range, None);
    assert_eq!(o.with_depth_range(f32::NAN, 20.0).depth_range, None);
    // Bounds beyond the far plane leave no ray.
    let beyond = o.with_depth_range(250.0, 300.0);
    assert_eq!(predict_error(&c, &ground(), &map, 1024, &beyond), Ok(None));
}
