//! Generators and checks for `shadowmap-frustum` (fuzz targets and property tests).
//!
//! Each `*_raw` generator pairs with a `check_*` function that asserts the builder's
//! contract on any input: it returns `Ok` with finite, non-singular output, or a typed
//! error; it never panics.

use arbitrary::Unstructured;
use glam::{DVec2, DVec3, Mat4, Vec3};
use shadowmap_frustum::{
    Aabb, Camera, Cascade, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, CascadeState,
    ConvexBody, DepthBounds, Frustum, Light, SPOT_ROUNDING_BUDGET, SceneBounds, ShadowMapping,
    ShadowSample, ShadowTransform, SplitScheme, SpotShadow, ValidCamera,
    directional_light_from_world, fit_spot,
};

/// The crate these generators build values of. `shadowmap-frustum`'s own unit tests
/// compile a second copy of it, so they name the generators' types through this path
/// to convert them.
pub use shadowmap_frustum as built;

use crate::{
    GenResult, aabb, aabb_raw, any_f32, any_vec3, camera, camera_raw, depth_range_raw, in_range,
    light_direction, log_uniform, split_scheme_raw, unit_vec3,
};

/// Asserts a matrix is finite and invertible.
pub fn assert_invertible(m: &Mat4, what: &str) {
    assert!(m.is_finite(), "{what} is not finite: {m:?}");
    let det = m.as_dmat4().determinant();
    assert!(det != 0.0 && det.is_finite(), "{what} is singular: {m:?}");
}

/// Input of [`check_camera`].
#[derive(Clone, Debug)]
pub struct CameraCase {
    /// Any camera.
    pub camera: Camera,
    /// A requested slice, fractions of the depth range (may be anything).
    pub slice: (f32, f32),
}

/// Any camera and slice request.
pub fn camera_case_raw(u: &mut Unstructured<'_>) -> GenResult<CameraCase> {
    Ok(CameraCase {
        camera: camera_raw(u)?,
        slice: depth_range_raw(u)?,
    })
}

/// Camera validation, frustum and slices: valid cameras give finite frusta whose
/// corners are inside their own planes and an invertible `clip_from_world`.
pub fn check_camera(case: &CameraCase) {
    let Ok(()) = case.camera.validate() else {
        // Validation covers the frustum and the projection: one of them must refuse.
        assert!(case.camera.frustum().is_err() || case.camera.clip_from_world().is_err());
        return;
    };
    let frustum = case.camera.frustum().expect("valid camera has a frustum");
    check_frustum(&frustum);
    let clip = case
        .camera
        .clip_from_world()
        .expect("valid camera has a projection");
    assert_invertible(&clip, "clip_from_world");
    let (near, far) = case.camera.depth_range().expect("valid camera has a range");
    assert!(near.is_finite() && far.is_finite() && far > near);
    let (a, b) = case.slice;
    if let Ok(slice) = case.camera.slice(a, b) {
        check_frustum(&slice);
        assert!(a < b, "slice accepted an inverted range {a} {b}");
    }
}

fn check_frustum(f: &Frustum) {
    assert!(f.corners.iter().all(|c| c.is_finite()), "{f:?}");
    assert!(
        f.planes
            .iter()
            .all(|p| p.normal.is_finite() && p.d.is_finite()),
        "{f:?}"
    );
    let scale = f
        .aabb()
        .size()
        .max_element()
        .max(f.aabb().max.abs().max_element());
    for c in &f.corners {
        assert!(
            f.contains(*c, 1e-3 * scale + 1e-6),
            "corner {c} outside {f:?}"
        );
    }
}

/// Input of [`check_splits`].
#[derive(Clone, Debug)]
pub struct SplitCase {
    /// The scheme.
    pub scheme: SplitScheme,
    /// Cascade count (may be 0 or too large).
    pub count: usize,
    /// Near and far (may be invalid).
    pub range: (f32, f32),
    /// Blend band fraction (may be invalid).
    pub overlap: f32,
    /// A depth to select.
    pub probe: f32,
}

/// Any split request.
pub fn split_case_raw(u: &mut Unstructured<'_>) -> GenResult<SplitCase> {
    let count = usize::from(u.int_in_range(0u8..=10)?);
    Ok(SplitCase {
        scheme: split_scheme_raw(u, count)?,
        count,
        range: depth_range_raw(u)?,
        overlap: if u.arbitrary()? {
            any_f32(u)?
        } else {
            in_range(u, 0.0, 0.99)?
        },
        probe: any_f32(u)?,
    })
}

/// Split schemes: accepted splits start at near, end at far, increase strictly, and
/// select a valid cascade with a weight in `[0, 1]`.
pub fn check_splits(case: &SplitCase) {
    let (near, far) = case.range;
    let Ok(splits) = CascadeSplits::new(&case.scheme, case.count, near, far) else {
        return;
    };
    let d = splits.depths();
    assert_eq!(d.len(), case.count + 1);
    assert_eq!(d[0], near);
    assert_eq!(d[case.count], far);
    assert!(d.windows(2).all(|w| w[0] < w[1]), "{d:?}");
    let splits = splits.clone().with_overlap(case.overlap).unwrap_or(splits);
    for i in 0..splits.count() {
        let (a, b) = splits.cascade_range(i).expect("index in range");
        assert!(a.is_finite() && b.is_finite() && a < b, "{a} {b}");
    }
    if let Some(sel) = splits.select(case.probe) {
        assert!(sel.index < splits.count());
        assert!((0.0..=1.0).contains(&sel.next_weight));
    }
}

/// Input of [`check_cascades`].
#[derive(Clone, Debug)]
pub struct CascadeCase {
    /// The camera (may be invalid).
    pub camera: Camera,
    /// Light direction (may be zero or non-finite).
    pub light: Vec3,
    /// Split scheme.
    pub scheme: SplitScheme,
    /// Cascade count.
    pub count: usize,
    /// Options (any resolution, up hint, scene).
    pub options: CascadeOptions,
}

/// Any cascade request, biased to nearly valid ones.
pub fn cascade_case_raw(u: &mut Unstructured<'_>) -> GenResult<CascadeCase> {
    let camera = if u.arbitrary()? {
        camera(u)?
    } else {
        camera_raw(u)?
    };
    let light = if u.int_in_range(0u8..=3)? == 0 {
        any_vec3(u)?
    } else {
        light_direction(u, &camera)?
    };
    let count = usize::from(u.int_in_range(1u8..=9)?);
    let scene = match u.int_in_range(0u8..=2)? {
        0 => None,
        1 => Some(SceneBounds {
            receivers: aabb_raw(u)?,
            casters: aabb_raw(u)?,
        }),
        _ => {
            let receivers = aabb(u, 1e3)?;
            Some(SceneBounds {
                receivers,
                casters: receivers.union(&aabb(u, 1e3)?),
            })
        }
    };
    let resolution = match u.int_in_range(0u8..=2)? {
        0 => u.arbitrary()?,
        _ => 1 << u.int_in_range(2u32..=14)?,
    };
    let options = CascadeOptions::default()
        .with_resolution(resolution)
        .with_fit(if u.arbitrary()? {
            CascadeFit::Tight
        } else {
            CascadeFit::Stable
        })
        .with_reversed_z(u.arbitrary()?)
        .with_up_hint(if u.arbitrary()? {
            unit_vec3(u)?
        } else {
            any_vec3(u)?
        })
        .with_scene(scene)
        .with_stable_size_step(match u.int_in_range(0u8..=2)? {
            0 => None,
            1 => Some(in_range(u, 1.0001, 4.0)?),
            _ => Some(any_f32(u)?),
        });
    Ok(CascadeCase {
        camera,
        light,
        scheme: split_scheme_raw(u, count)?,
        count,
        options,
    })
}

/// Cascade fitting: accepted sets have finite invertible matrices and positive texels.
pub fn check_cascades(case: &CascadeCase) {
    let Ok((near, far)) = case.camera.depth_range() else {
        return;
    };
    let Ok(splits) = CascadeSplits::new(&case.scheme, case.count, near, far) else {
        return;
    };
    let Ok(set) = CascadeSet::fit(&case.camera, case.light, &splits, &case.options) else {
        return;
    };
    assert_eq!(set.cascades.len(), case.count);
    check_cascade_set(&set);
    check_held_cascades(case, &splits, (near, far));
}

/// Every cascade of `set` has finite invertible matrices, a positive texel and a
/// depth range.
fn check_cascade_set(set: &CascadeSet) {
    for c in &set.cascades {
        assert_invertible(&c.transform.clip_from_world, "cascade clip_from_world");
        assert_invertible(&c.transform.uv_from_world, "cascade uv_from_world");
        assert!(
            c.texel_world_size.is_finite() && c.texel_world_size > 0.0,
            "{c:?}"
        );
        assert!(
            c.light_depth.0.is_finite() && c.light_depth.1 > c.light_depth.0,
            "{c:?}"
        );
    }
}

/// The fit with a held state (`fit_with_state`, the stable fit's held sizes): the
/// held depth range nests in the camera's, the sets it fits pass
/// [`check_cascade_set`], and fitting the same frame again keeps every cascade's
/// texel (a held map re-sized without cause would shimmer). The same with a
/// caller's measure (`fit_with_state_ranked`: each new map's orientation chosen
/// and its turn allowance priced), measuring the map's area across the light,
/// which prices the allowance at its whole growth.
fn check_held_cascades(case: &CascadeCase, splits: &CascadeSplits, (near, far): (f32, f32)) {
    let mut state = CascadeState::new();
    let range = state.hold_depth_range(near, far, (near, far));
    for (lo, hi) in [range.split, range.cover] {
        assert!(
            near <= lo && lo <= hi && hi <= far,
            "{range:?} in {near}..{far}"
        );
    }
    let Ok(valid) = ValidCamera::new(&case.camera) else {
        return;
    };
    check_refit(|| {
        CascadeSet::fit_with_state(&valid, case.light, splits, &case.options, &mut state)
    });
    let mut state = CascadeState::new();
    let area = |c: &Cascade| {
        let m = c.transform.uv_from_world;
        let across = m.row(0).truncate().cross(m.row(1).truncate()).length();
        1.0 / f64::from(across)
    };
    check_refit(|| {
        CascadeSet::fit_with_state_ranked(
            &valid,
            case.light,
            splits,
            &case.options,
            &mut state,
            &area,
        )
    });
}

/// A held fit's first set passes [`check_cascade_set`], and the same frame fitted
/// again keeps every cascade's texel.
fn check_refit(mut fit: impl FnMut() -> Result<CascadeSet, shadowmap_frustum::FrustumError>) {
    let Ok(first) = fit() else {
        return;
    };
    check_cascade_set(&first);
    let again = fit().expect("the frame that fitted fits again");
    for (a, b) in first.cascades.iter().zip(&again.cascades) {
        assert_eq!(a.texel_world_size, b.texel_world_size, "{a:?} then {b:?}");
    }
}

/// Input of [`check_convex_body`].
#[derive(Clone, Debug)]
pub struct BodyCase {
    /// The camera whose frustum is clipped.
    pub camera: Camera,
    /// The box (may be invalid).
    pub aabb: Aabb,
    /// Light direction for the extrusion (may be invalid).
    pub light: Vec3,
}

/// A valid camera with a box that overlaps its frustum (a random point of the
/// frustum as centre, half extents relative to the frustum's size).
pub fn body_case(u: &mut Unstructured<'_>) -> GenResult<BodyCase> {
    let camera = camera(u)?;
    let frustum = camera.frustum().expect("generated cameras are valid");
    let w: [f32; 8] = core::array::from_fn(|_| in_range(u, 0.0, 1.0).unwrap_or(0.5));
    let sum: f32 = w.iter().sum();
    let w = if sum > 1e-3 { w } else { [1.0; 8] };
    let sum: f32 = w.iter().sum();
    let center = frustum
        .corners
        .iter()
        .zip(w)
        .fold(Vec3::ZERO, |s, (c, w)| s + *c * (w / sum));
    let size = frustum.aabb().size().max_element();
    let half = Vec3::new(
        size * log_uniform(u, 1e-4, 2.0)?,
        size * log_uniform(u, 1e-4, 2.0)?,
        size * log_uniform(u, 1e-4, 2.0)?,
    );
    Ok(BodyCase {
        camera,
        aabb: Aabb::from_center_half_extents(center, half),
        light: light_direction(u, &camera)?,
    })
}

/// Any body request.
pub fn body_case_raw(u: &mut Unstructured<'_>) -> GenResult<BodyCase> {
    let mut case = body_case(u)?;
    if u.arbitrary()? {
        case.aabb = aabb_raw(u)?;
    }
    if u.arbitrary()? {
        case.light = any_vec3(u)?;
    }
    Ok(case)
}

/// Convex body: accepted bodies have finite vertices inside the frustum and the box
/// (up to a rounding tolerance), and the extrusion stays inside the box.
pub fn check_convex_body(case: &BodyCase) {
    let Ok(frustum) = case.camera.frustum() else {
        return;
    };
    let Ok(body) = ConvexBody::from_frustum_aabb(&frustum, &case.aabb) else {
        return;
    };
    let scale = frustum
        .aabb()
        .union(&case.aabb)
        .max
        .abs()
        .max(frustum.aabb().union(&case.aabb).min.abs())
        .max_element();
    let tol = 1e-4 * scale;
    for v in body.vertices() {
        assert!(v.is_finite());
        assert!(frustum.contains(*v, tol), "{v} outside the frustum");
        let grown = Aabb::new(case.aabb.min - tol, case.aabb.max + tol);
        assert!(grown.contains(*v), "{v} outside the box");
    }
    if let Ok(ext) = body.extruded_toward_light(case.light, &case.aabb) {
        let grown = Aabb::new(case.aabb.min - tol, case.aabb.max + tol);
        assert!(
            ext.vertices()
                .iter()
                .all(|v| v.is_finite() && grown.contains(*v))
        );
        // Every point the light reaches the body from is inside: sample rays from the
        // body's vertices and centroid toward the light, up to the scene boundary.
        if body.is_empty() {
            return;
        }
        let toward = -case.light.normalize();
        let n = body.vertices().len() as f32;
        let centroid = body.vertices().iter().fold(Vec3::ZERO, |s, v| s + *v) / n;
        let reach = case.aabb.size().length();
        for start in body.vertices().iter().chain([&centroid]) {
            for f in [0.0, 0.1, 0.35, 0.7, 1.0] {
                let x = *start + toward * (f * reach);
                if case.aabb.contains(x) {
                    assert!(
                        ext.contains(x, 4.0 * tol),
                        "{x} from {start} not in the extrusion"
                    );
                }
            }
        }
    }
}

/// Input of [`check_spot`].
#[derive(Clone, Debug)]
pub struct SpotCase {
    /// The light (any kind, maybe invalid).
    pub light: Light,
    /// The camera.
    pub camera: Camera,
    /// Optional scene.
    pub scene: Option<SceneBounds>,
    /// Reversed-Z.
    pub reversed_z: bool,
}

/// Any spot request; mostly valid spots near the camera.
pub fn spot_case_raw(u: &mut Unstructured<'_>) -> GenResult<SpotCase> {
    let camera = camera(u)?;
    let (near, far) = camera.depth_range().unwrap_or((0.1, 100.0));
    let scale = far.min(1e4).max(near);
    let light = match u.int_in_range(0u8..=5)? {
        0 => Light::Point {
            position: any_vec3(u)?,
            range: any_f32(u)?,
        },
        1 => Light::Spot {
            position: any_vec3(u)?,
            direction: any_vec3(u)?,
            half_angle: any_f32(u)?,
            range: any_f32(u)?,
        },
        _ => Light::Spot {
            position: camera.eye() + crate::position(u, scale)?,
            direction: unit_vec3(u)?,
            half_angle: in_range(u, 1e-3, 1.55)?,
            range: log_uniform(u, 1e-2, (2.0 * scale).max(0.02))?,
        },
    };
    let scene = if u.arbitrary()? {
        Some(SceneBounds {
            receivers: aabb_raw(u)?,
            casters: aabb_raw(u)?,
        })
    } else {
        None
    };
    Ok(SpotCase {
        light,
        camera,
        scene,
        reversed_z: u.arbitrary()?,
    })
}

/// Spot fit: accepted fits have finite invertible matrices and `near < far`; each
/// visible receiver point the map stores (frustum ∩ receivers: its vertices) lands
/// on the same texel as the point halfway to the light on its ray, to
/// [`spot_ray_tolerance`].
pub fn check_spot(case: &SpotCase) {
    let Ok(frustum) = case.camera.frustum() else {
        return;
    };
    let Ok(spot) = fit_spot(&case.light, &frustum, case.scene.as_ref(), case.reversed_z) else {
        return;
    };
    assert_invertible(&spot.transform.clip_from_world, "spot clip_from_world");
    assert!(spot.light_depth.0 > 0.0 && spot.light_depth.1 > spot.light_depth.0);
    assert!(spot.tangents.iter().all(|t| t.is_finite()));
    let Light::Spot {
        position,
        half_angle,
        ..
    } = case.light
    else {
        return;
    };
    let body = case
        .scene
        .map(|s| ConvexBody::from_frustum_aabb(&frustum, &s.receivers));
    let points = match &body {
        Some(Ok(body)) => body.vertices(),
        Some(Err(_)) => return,
        None => &frustum.corners,
    };
    let light = position.as_dvec3();
    for p in points.iter().map(|p| p.as_dvec3()) {
        if let Some(gap) = ray_gap(&spot.transform, light, p) {
            let tol = spot_ray_tolerance(&spot, half_angle, light, p);
            assert!(
                gap <= tol,
                "{p}: its ray's texels {gap} apart (tolerance {tol})"
            );
        }
    }
}

/// How far apart the two ends of a light ray through `p` may land in a map of the
/// spot fit `spot` (of a light at `light` with this half angle), in texture
/// coordinates: a tenth of a texel of a `1024²` map, or a texel where the fit kept
/// the whole cone on an axis (a cone too narrow for a tenth, or a region reaching
/// behind the light), plus a few `f32` steps of the coordinates over the distance
/// from the light.
pub fn spot_ray_tolerance(spot: &SpotShadow, half_angle: f32, light: DVec3, p: DVec3) -> f64 {
    let cone = 2.0 * f64::from(half_angle).tan() * (1.0 - 1e-6);
    let [l, r, b, t] = spot.tangents.map(f64::from);
    // The fit's own budget (a tenth of a texel), or the texel it allows a whole cone.
    let budget = if r - l >= cone || t - b >= cone {
        10.0 * SPOT_ROUNDING_BUDGET
    } else {
        SPOT_ROUNDING_BUDGET
    };
    let distance = (p - light).length().max(1e-30);
    budget + 1e-6 * p.abs().max_element().max(light.abs().max_element()) / distance
}

/// How far apart (largest `uv` difference) `map` stores `p` and the point halfway
/// from `light` to `p`, when it stores both inside the map with a depth in
/// `[0, 1]`.
pub fn ray_gap(map: &ShadowTransform, light: DVec3, p: DVec3) -> Option<f64> {
    let inside = |s: &ShadowSample| {
        s.uv.cmpge(DVec2::ZERO).all()
            && s.uv.cmple(DVec2::ONE).all()
            && (0.0..=1.0).contains(&s.depth)
    };
    let far = map.map_point(p).filter(inside)?;
    let halfway = map.map_point(light + (p - light) * 0.5).filter(inside)?;
    Some((far.uv - halfway.uv).abs().max_element())
}

/// Input of [`check_depth_bounds`].
#[derive(Clone, Debug)]
pub struct DepthBoundsCase {
    /// The camera.
    pub camera: Camera,
    /// Measured bounds (may be anything).
    pub bounds: DepthBounds,
    /// Cascade count.
    pub count: usize,
}

/// Any measured depth bounds for a valid camera.
pub fn depth_bounds_case_raw(u: &mut Unstructured<'_>) -> GenResult<DepthBoundsCase> {
    let camera = camera(u)?;
    let (min, max) = depth_range_raw(u)?;
    Ok(DepthBoundsCase {
        camera,
        bounds: DepthBounds { min, max },
        count: usize::from(u.int_in_range(1u8..=8)?),
    })
}

/// Depth bounds: the clamped range is finite, ordered, and inside the camera's range;
/// splits over it are accepted.
pub fn check_depth_bounds(case: &DepthBoundsCase) {
    let (near, far) = case.camera.depth_range().expect("valid camera");
    let (lo, hi) = case.bounds.clamped_to(&case.camera).expect("valid camera");
    assert!(lo.is_finite() && hi.is_finite() && lo < hi, "{lo} {hi}");
    assert!(lo >= near && hi <= far, "{lo} {hi} outside {near} {far}");
    let splits = CascadeSplits::from_depth_bounds(
        &SplitScheme::Practical { lambda: 0.5 },
        case.count,
        &case.camera,
        case.bounds,
    );
    if let Ok(s) = splits {
        assert_eq!(s.depths()[0], lo);
    }
}

/// Any light direction and up hint for the light frame.
pub fn light_frame_case_raw(u: &mut Unstructured<'_>) -> GenResult<(Vec3, Vec3)> {
    let dir = if u.arbitrary()? {
        any_vec3(u)?
    } else {
        unit_vec3(u)?
    };
    let up = match u.int_in_range(0u8..=2)? {
        0 => any_vec3(u)?,
        1 => crate::near_parallel(u, dir)?,
        _ => unit_vec3(u)?,
    };
    Ok((dir, up))
}

/// Light frame: accepted frames are rotations whose `-Z` is the light direction.
pub fn check_light_frame(case: &(Vec3, Vec3)) {
    let Ok(m) = directional_light_from_world(case.0, case.1) else {
        return;
    };
    assert_invertible(&m, "light_from_world");
    let d = case.0.as_dvec3().normalize();
    let light_dir = m.as_dmat4().transform_vector3(d);
    assert!(
        (light_dir - glam::DVec3::NEG_Z).length() < 1e-5,
        "{light_dir}"
    );
    assert!((m.as_dmat4().determinant() - 1.0).abs() < 1e-5);
}
