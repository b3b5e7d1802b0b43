//! Property tests of `shadowmap-frustum`, 1,000 cases each, driven by the same
//! generators as the fuzz targets (`shadowmap_testgen`).

use glam::{DQuat, DVec3, Mat4, Quat, Vec3};
use proptest::prelude::*;
use shadowmap_frustum::{
    Camera, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, ConvexBody, SceneBounds,
    ShadowMapping, SplitScheme, ValidCamera, uv_differentials_by_points,
};
use shadowmap_testgen::{
    GenResult, arbitrary::Unstructured, camera, frustum as cases, in_range, light_direction,
    log_uniform, strategy, unit_vec3,
};

/// A valid cascade request: camera, light, splits and options.
#[derive(Clone, Debug)]
struct FitCase {
    camera: Camera,
    light: Vec3,
    lambda: f32,
    count: usize,
    overlap: f32,
    options: CascadeOptions,
    /// Barycentric-ish weights picking interior points of each slice.
    weights: [[f32; 8]; 4],
}

fn fit_case(u: &mut Unstructured<'_>) -> GenResult<FitCase> {
    let camera = camera(u)?;
    let light = light_direction(u, &camera)?;
    let fit = if u.arbitrary()? {
        CascadeFit::Tight
    } else {
        CascadeFit::Stable
    };
    let options = CascadeOptions::default()
        .with_resolution(1 << u.int_in_range(3u32..=13)?)
        .with_fit(fit)
        .with_reversed_z(u.arbitrary()?)
        .with_up_hint(unit_vec3(u)?);
    let mut weights = [[0.0; 8]; 4];
    for row in &mut weights {
        for w in row.iter_mut() {
            *w = in_range(u, 0.0, 1.0)?;
        }
    }
    Ok(FitCase {
        camera,
        light,
        lambda: in_range(u, 0.0, 1.0)?,
        count: usize::from(u.int_in_range(1u8..=8)?),
        overlap: in_range(u, 0.0, 0.5)?,
        options,
        weights,
    })
}

/// Per-axis tolerance (u, v, depth) for points of magnitude up to `coord` mapped
/// through an `f32` matrix: the rounding of an `f32` coordinate, scaled by how many
/// map units one world unit is along that axis (the matrix row's norm), plus a small
/// floor.
fn f32_tolerance(m: &Mat4, coord: f64) -> [f64; 3] {
    let m = m.as_dmat4();
    core::array::from_fn(|r| {
        let row = DVec3::new(m.x_axis[r], m.y_axis[r], m.z_axis[r]);
        1e-4 + 16.0 * f64::from(f32::EPSILON) * coord * row.length()
    })
}

/// `1 +` the largest slope of a camera's side edges to its view axis (how far a
/// point on a side moves sideways per unit it moves along the axis: 0 for an
/// orthographic camera), from its frustum's near and far corners.
fn side_slope(camera: &Camera) -> f64 {
    let corners = camera.frustum().unwrap().corners.map(Vec3::as_dvec3);
    let forward = camera.forward().as_dvec3().normalize();
    let slope = (0..4)
        .map(|k| {
            let edge = corners[k + 4] - corners[k];
            let along = edge.dot(forward);
            (edge - forward * along).length() / along.abs()
        })
        .fold(0.0, f64::max);
    1.0 + slope
}

/// The cascades of a generated case over the camera's whole depth range.
fn fitted_set(case: &FitCase) -> CascadeSet {
    let (near, far) = case.camera.depth_range().unwrap();
    let splits = CascadeSplits::new(
        &SplitScheme::Practical {
            lambda: case.lambda,
        },
        case.count,
        near,
        far,
    )
    .unwrap()
    .with_overlap(case.overlap)
    .unwrap();
    CascadeSet::fit(&case.camera, case.light, &splits, &case.options).unwrap()
}

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// Every point of a slice (corners and interior points) maps inside its cascade's
    /// `[0, 1]² x [0, 1]`, for tight and stable fits, either depth convention.
    #[test]
    fn slice_points_map_inside_their_cascade(case in strategy(fit_case)) {
        let set = fitted_set(&case);
        for (i, cascade) in set.cascades.iter().enumerate() {
            let (a, b) = cascade.view_depth;
            let slice = case.camera.slice(a, b).unwrap();
            let mut points: Vec<Vec3> = slice.corners.to_vec();
            for w in &case.weights {
                let sum: f32 = w.iter().sum();
                let w = if sum > 1e-3 { *w } else { [1.0; 8] };
                let sum: f32 = w.iter().sum();
                points.push(slice.corners.iter().zip(w).fold(Vec3::ZERO, |s, (c, w)| s + *c * (w / sum)));
            }
            let coord = points.iter().map(|p| f64::from(p.abs().max_element())).fold(0.0, f64::max);
            let [tu, tv, tz] = f32_tolerance(&cascade.transform.uv_from_world, coord);
            for p in &points {
                let s = cascade.transform.project(*p).unwrap();
                prop_assert!(s.uv.x >= -tu && s.uv.x <= 1.0 + tu, "cascade {i}: u = {} (tol {tu})", s.uv.x);
                prop_assert!(s.uv.y >= -tv && s.uv.y <= 1.0 + tv, "cascade {i}: v = {} (tol {tv})", s.uv.y);
                prop_assert!(s.depth >= -tz && s.depth <= 1.0 + tz, "cascade {i}: depth = {} (tol {tz})", s.depth);
            }
        }
    }

    /// The cascades' and a cascade's transform's texture-coordinate differentials
    /// (the derivative at the centre, one division) are the central differences of
    /// the points mapped one by one, to the square of the step over the distance,
    /// and refused where those are (a transform's: behind its projection); the
    /// cascades' are those of the cascade that stores the centre, also where the
    /// points around it cross into another (which the points mapped one by one
    /// refuse), and refused only beyond the last cascade.
    #[test]
    fn uv_differentials_are_the_central_differences(case in strategy(fit_case)) {
        let set = fitted_set(&case);
        let (near, far) = case.camera.depth_range().unwrap();
        let whole = case.camera.slice(near, far).unwrap();
        let reach = f64::from(whole.corners[4].distance(whole.corners[6]));
        for w in &case.weights {
            let sum: f32 = w.iter().sum::<f32>().max(1e-3);
            let centre = whole.corners.iter().zip(w).fold(Vec3::ZERO, |s, (c, w)| s + *c * (w / sum)).as_dvec3();
            // Steps from a thousandth of the frustum's far diagonal (within a
            // cascade) to a tenth (across boundaries).
            for step in [1e-3, 1e-1].map(|f| reach * f) {
                let around = [DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::NEG_Y].map(|d| centre + d * step);
                let t = &set.cascades[0].transform;
                let stored = set.select_by_depth(centre.as_vec3()).is_some();
                prop_assert_eq!(set.uv_differentials(centre, &around).is_some(), stored);
                for (fast, slow, refused_alike) in [
                    (set.uv_differentials(centre, &around), uv_differentials_by_points(&set, centre, &around), false),
                    (t.uv_differentials(centre, &around), uv_differentials_by_points(t, centre, &around), true),
                ] {
                    if refused_alike {
                        prop_assert_eq!(fast.is_some(), slow.is_some());
                    }
                    let (Some(fast), Some(slow)) = (fast, slow) else { continue };
                    // An orthographic map is affine: the derivative is the difference,
                    // to the rounding of the points' uv, which is that of the terms of
                    // the matrix product (far larger than uv far from the origin).
                    let rounding = set
                        .cascades
                        .iter()
                        .map(|c| {
                            let m = c.transform.uv_from_world.as_dmat4();
                            let abs = glam::DMat4::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs(), m.w_axis.abs());
                            let terms = abs * centre.abs().extend(1.0);
                            terms.x.max(terms.y) / terms.w.max(f64::MIN_POSITIVE)
                        })
                        .fold(0.0, f64::max)
                        * 16.0
                        * f64::EPSILON;
                    for (f, s) in fast.iter().zip(&slow) {
                        prop_assert!((*f - *s).length() <= 1e-9 * s.length() + rounding, "{} vs {}", f, s);
                    }
                }
            }
        }
    }

    /// A checked camera's slice corners without the planes are the slice's corners
    /// (`ValidCamera::slice_corners`, which the IPSM plan reads), and refuse the
    /// same depth pairs.
    #[test]
    fn slice_corners_are_the_slice_corners(
        (camera, a, b) in strategy(|u| Ok((camera(u)?, in_range(u, 0.0, 1.0)?, in_range(u, 0.0, 1.0)?)))
    ) {
        let Ok(valid) = ValidCamera::new(&camera) else { return Ok(()) };
        let (near, far) = valid.depth_range();
        let depth = |t: f32| near + (far - near) * t;
        let (n, f) = (depth(a.min(b)), depth(a.max(b)));
        match (valid.slice(n, f), valid.slice_corners(n, f)) {
            (Ok(slice), Ok(corners)) => prop_assert_eq!(slice.corners, corners),
            (Err(e), Err(c)) => prop_assert_eq!(e, c),
            (slice, corners) => prop_assert!(false, "{:?} vs {:?}", slice, corners),
        }
    }

    /// Split depths are monotone from near to far; lambda 0 is exactly the uniform
    /// scheme and lambda 1 exactly the logarithmic one.
    #[test]
    fn split_depths_monotone_and_schemes_agree(
        (near, far, count) in strategy(|u| {
            let (n, f) = shadowmap_testgen::depth_range(u)?;
            Ok((n, f, usize::from(u.int_in_range(1u8..=8)?)))
        })
    ) {
        let Ok(uniform) = CascadeSplits::new(&SplitScheme::Uniform, count, near, far) else {
            // Only a range too thin for `count` distinct f32 depths may be refused.
            prop_assert!(f64::from(far - near) / f64::from(far) < 1e-3);
            return Ok(());
        };
        let log = CascadeSplits::new(&SplitScheme::Logarithmic, count, near, far).unwrap();
        let p0 = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.0 }, count, near, far).unwrap();
        let p1 = CascadeSplits::new(&SplitScheme::Practical { lambda: 1.0 }, count, near, far).unwrap();
        for s in [&uniform, &log, &p0, &p1] {
            let d = s.depths();
            prop_assert_eq!(d[0], near);
            prop_assert_eq!(d[count], far);
            prop_assert!(d.windows(2).all(|w| w[0] < w[1]), "{:?}", d);
        }
        prop_assert_eq!(uniform.depths(), p0.depths());
        prop_assert_eq!(log.depths(), p1.depths());
    }

    /// Stable cascades: translating the camera moves every cascade by whole texels
    /// (sub-texel phase of a fixed world point below 1e-3 texel), and rotating it
    /// leaves every cascade's size unchanged.
    #[test]
    fn stable_cascades_move_by_whole_texels_and_keep_size(
        (case, translation, rotation) in strategy(|u| {
            let case = fit_case(u)?;
            let t = unit_vec3(u)? * log_uniform(u, 1e-3, 1e2)?;
            let axis = unit_vec3(u)?;
            let angle = in_range(u, -3.1, 3.1)?;
            Ok((case, t, Quat::from_axis_angle(axis, angle)))
        })
    ) {
        let options = case.options.with_fit(CascadeFit::Stable);
        let (near, far) = case.camera.depth_range().unwrap();
        let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: case.lambda }, case.count, near, far).unwrap();
        let fit = |camera: &Camera| CascadeSet::fit(camera, case.light, &splits, &options).unwrap();
        let base = fit(&case.camera);

        let moved_camera = Camera {
            world_from_view: Mat4::from_translation(translation) * case.camera.world_from_view,
            ..case.camera
        };
        let turned_camera = Camera {
            world_from_view: case.camera.world_from_view * Mat4::from_quat(rotation),
            ..case.camera
        };
        // Moving a tiny frustum far from the origin can leave f32 precision: that is
        // a typed error, tested elsewhere.
        prop_assume!(moved_camera.validate().is_ok() && turned_camera.validate().is_ok());
        let moved = fit(&moved_camera);
        let turned = fit(&turned_camera);
        let res = f64::from(options.resolution);
        for i in 0..base.cascades.len() {
            let (a, b) = (&base.cascades[i], &moved.cascades[i]);
            prop_assert_eq!(a.texel_world_size, turned.cascades[i].texel_world_size);
            prop_assert_eq!(a.texel_world_size, b.texel_world_size);
            // A fixed world point near the cascade.
            let p = a.transform.light_from_world.inverse().transform_point3(Vec3::ZERO) + case.camera.eye();
            let pa = a.transform.uv_from_world.as_dmat4().transform_point3(p.as_dvec3()) * res;
            let pb = b.transform.uv_from_world.as_dmat4().transform_point3(p.as_dvec3()) * res;
            let shift = pb - pa;
            let phase = (shift.x - shift.x.round()).abs().max((shift.y - shift.y.round()).abs());
            prop_assert!(phase < 1e-3, "cascade {}: shift {:?} texels, phase {}", i, shift, phase);
        }
    }

    /// The convex body of frustum ∩ box: its vertices lie inside both, and every box
    /// corner inside the frustum (and every frustum corner inside the box) is a vertex.
    #[test]
    fn convex_body_vertices_inside_both_and_complete(case in strategy(cases::body_case)) {
        cases::check_convex_body(&case);
        let frustum = case.camera.frustum().unwrap();
        let body = ConvexBody::from_frustum_aabb(&frustum, &case.aabb).unwrap();
        let scale = frustum.aabb().union(&case.aabb).max.abs()
            .max(frustum.aabb().union(&case.aabb).min.abs()).max_element();
        let tol = 1e-4 * scale;
        let is_vertex = |p: Vec3| body.vertices().iter().any(|v| (*v - p).abs().max_element() <= tol);
        let planes = frustum.planes;
        for corner in case.aabb.corners() {
            // Strictly inside (by more than the tolerance): must be a vertex.
            if planes.iter().all(|pl| pl.signed_distance(corner) > 2.0 * tol) {
                prop_assert!(is_vertex(corner), "box corner {} missing from {:?}", corner, body.vertices());
            }
        }
        for corner in frustum.corners {
            let shrunk = shadowmap_frustum::Aabb::new(case.aabb.min + 2.0 * tol, case.aabb.max - 2.0 * tol);
            if shrunk.is_valid() && shrunk.contains(corner) {
                prop_assert!(is_vertex(corner), "frustum corner {} missing", corner);
            }
        }
    }

    /// The contract the fuzz targets check, on the same generators.
    #[test]
    fn fuzz_contracts_hold(
        camera_case in strategy(cases::camera_case_raw),
        split_case in strategy(cases::split_case_raw),
        cascade_case in strategy(cases::cascade_case_raw),
        body_case in strategy(cases::body_case_raw),
        spot_case in strategy(cases::spot_case_raw),
        bounds_case in strategy(cases::depth_bounds_case_raw),
        frame_case in strategy(cases::light_frame_case_raw),
    ) {
        cases::check_camera(&camera_case);
        cases::check_splits(&split_case);
        cases::check_cascades(&cascade_case);
        cases::check_convex_body(&body_case);
        cases::check_spot(&spot_case);
        cases::check_depth_bounds(&bounds_case);
        cases::check_light_frame(&frame_case);
    }

    /// Scene-dependent fit: receivers in the slice map inside the map, and casters
    /// between the light and the cascade's footprint are inside the depth range.
    #[test]
    fn scene_fit_keeps_receivers_and_casters(
        (case, receivers, caster_lift) in strategy(|u| {
            let case = fit_case(u)?;
            let frustum = case.camera.frustum().unwrap();
            let c = frustum.centroid();
            let size = frustum.aabb().size().max_element();
            let half = Vec3::new(
                size * log_uniform(u, 1e-2, 1.0)?,
                size * log_uniform(u, 1e-2, 1.0)?,
                size * log_uniform(u, 1e-2, 1.0)?,
            );
            Ok((case, shadowmap_frustum::Aabb::from_center_half_extents(c, half), log_uniform(u, 1e-2, 10.0)? * size))
        })
    ) {
        // Casters: the receivers plus a copy lifted toward the light.
        let lifted = shadowmap_frustum::Aabb::new(receivers.min - case.light.normalize() * caster_lift, receivers.max - case.light.normalize() * caster_lift);
        let casters = receivers.union(&lifted);
        let options = case.options.with_fit(CascadeFit::Tight).with_scene(Some(SceneBounds { receivers, casters }));
        let (near, far) = case.camera.depth_range().unwrap();
        let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: case.lambda }, case.count, near, far).unwrap();
        let set = CascadeSet::fit(&case.camera, case.light, &splits, &options).unwrap();
        for cascade in &set.cascades {
            if cascade.receivers_missed {
                continue;
            }
            let (a, b) = cascade.view_depth;
            // A slice far thinner than it is wide can have no volume in f32 (typed error).
            let Ok(slice) = case.camera.slice(a, b) else { continue };
            let Ok(body) = ConvexBody::from_frustum_aabb(&slice, &receivers) else { continue };
            let coord = f64::from(casters.max.abs().max(casters.min.abs()).max_element());
            // Body vertices carry the f32 rounding of the frustum corners too, and
            // where the slice is wide and shallow its sides nearly face the eye: a
            // vertex where one meets a box face, placed within the body's plane
            // tolerance (a few f32 steps of the coordinates), moves along it by that
            // times the sides' slope (a 179.8° wide view: 700 times).
            let [tu, tv, tz] = f32_tolerance(
                &cascade.transform.uv_from_world,
                8.0 * coord * side_slope(&case.camera),
            );
            let eye = case.camera.eye().as_dvec3();
            let forward = case.camera.forward().as_dvec3().normalize();
            for v in body.vertices() {
                // The body of the slice's f32 corners keeps vertices within its plane
                // tolerance outside the slice: those beyond its near or far plane lie
                // in a neighbouring slice, whose cascade the view depth selects there
                // (where a split lies within rounding of a receiver face facing the
                // eye, the body holds the whole face; with a 179.8° wide view, a
                // vertex 0.2 to the side of the slice, 0.6% of its map).
                let depth = (v.as_dvec3() - eye).dot(forward);
                if depth < f64::from(a) || depth > f64::from(b) {
                    continue;
                }
                let s = cascade.transform.project(*v).unwrap();
                prop_assert!(s.uv.x >= -tu && s.uv.x <= 1.0 + tu && s.uv.y >= -tv && s.uv.y <= 1.0 + tv, "{:?}", s);
                prop_assert!(s.depth >= -tz && s.depth <= 1.0 + tz, "{:?}", s);
                // The caster point straight toward the light from this receiver point.
                let toward = -case.light.normalize();
                let caster_point = *v + toward * caster_lift;
                if casters.contains(caster_point) {
                    let c = cascade.transform.project(caster_point).unwrap();
                    prop_assert!(c.depth >= -tz && c.depth <= 1.0 + tz, "caster clipped: depth {}", c.depth);
                }
            }
        }
    }
}

#[test]
fn rotation_quat_helpers_are_consistent() {
    // Guards the test's own rotation convention: a camera turned by q about its own
    // eye keeps its eye.
    let cam = Camera::look_to(
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::NEG_Z,
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 1.0, 0.1, 10.0),
    )
    .unwrap();
    let q = DQuat::from_rotation_y(0.3).as_quat();
    let turned = cam.world_from_view * Mat4::from_quat(q);
    assert!((turned.w_axis.truncate() - cam.eye()).length() < 1e-6);
    let _ = DVec3::ZERO;
}
