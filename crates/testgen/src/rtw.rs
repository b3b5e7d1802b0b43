//! Generators and checks for `shadowmap-rtw` (fuzz targets and property tests).
//!
//! Each `*_raw` generator pairs with a `check_*` function that asserts the contract
//! on any input: `Ok` with finite, monotone warps mapping `[0, 1]` onto `[0, 1]`, or
//! the typed error the input calls for; never a panic.

use arbitrary::Unstructured;
use glam::{DVec2, Mat4, Vec3};
use shadowmap_frustum::{
    Camera, CascadeFit, CascadeOptions, Light, LightDirection, SceneBounds, ShadowMapping,
    ShadowTransform, directional_light_from_world, fit_cascade, fit_spot, projection,
};
use shadowmap_rtw::{
    EyeSample, ImportanceMap, ImportanceOptions, MAX_BLUR_RADIUS, MIN_FLOOR, RtwError, RtwShadow,
    WarpMaps, WarpOptions, forward_warp, forward_warp_f64, inverse_warp_f64,
};

use crate::{
    GenResult, aabb, any_f32, any_vec3, camera, in_range, light_direction, log_uniform, unit_vec3,
};

/// Input of [`check_warp`]: an importance map given as raw values, and the options
/// of one or two builds (the second exercises temporal smoothing).
#[derive(Clone, Debug)]
pub struct WarpCase {
    /// Map width (may be 0 in raw cases).
    pub width: u32,
    /// Map height (may be 0 in raw cases).
    pub height: u32,
    /// Row-major values (raw cases: any length, NaN, negative).
    pub values: Vec<f32>,
    /// Values of a second frame (same rules), if any.
    pub second: Option<Vec<f32>>,
    /// Build options (raw cases: anything).
    pub options: WarpOptions,
}

/// A small map side: usually 1..=64, sometimes up to 256 (then the map is thin).
fn side(u: &mut Unstructured<'_>) -> GenResult<u32> {
    Ok(match u.int_in_range(0u8..=5)? {
        0 => u.int_in_range(1u32..=3)?,
        1 => u.int_in_range(128u32..=256)?,
        _ => u.int_in_range(1u32..=64)?,
    })
}

/// Valid, non-negative importance values for a `width x height` map, in one of a
/// few shapes (constant, zero, spikes, smooth bumps, `1/z` ramp, pseudo-random with a
/// huge dynamic range).
pub fn importance_values(u: &mut Unstructured<'_>, width: u32, height: u32) -> GenResult<Vec<f32>> {
    let (w, h) = (width as usize, height as usize);
    let mut v = vec![0.0f32; w * h];
    match u.int_in_range(0u8..=6)? {
        0 => v.fill(log_uniform(u, 1e-30, 1e30)?),
        1 => {}
        2 => {
            let base = if u.arbitrary()? {
                0.0
            } else {
                log_uniform(u, 1e-9, 1e-3)?
            };
            v.fill(base);
            for _ in 0..u.int_in_range(1u8..=8)? {
                let i = u.int_in_range(0..=v.len() - 1)?;
                v[i] = log_uniform(u, 1e-6, 1e6)?;
            }
        }
        3 => {
            let (x0, y0) = (in_range(u, 0.0, 1.0)?, in_range(u, 0.0, 1.0)?);
            let s = log_uniform(u, 1e-3, 1.0)?;
            let a = log_uniform(u, 1e-3, 1e3)?;
            for (i, c) in v.iter_mut().enumerate() {
                let x = ((i % w) as f32 + 0.5) / width as f32 - x0;
                let y = ((i / w) as f32 + 0.5) / height as f32 - y0;
                *c = a * (-(x * x + y * y) / (s * s)).exp();
            }
        }
        4 => {
            let k = log_uniform(u, 1e-2, 1e4)?;
            let horizontal: bool = u.arbitrary()?;
            for (i, c) in v.iter_mut().enumerate() {
                let t = if horizontal {
                    (i % w) as f32 / width as f32
                } else {
                    (i / w) as f32 / height as f32
                };
                *c = 1.0 / (1.0 + k * t);
            }
        }
        _ => {
            let mut seed: u64 = u.arbitrary::<u64>()? | 1;
            let range = in_range(u, 0.0, 30.0)?;
            for c in &mut v {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                let t = (seed >> 40) as f32 / (1u64 << 24) as f32;
                *c = if seed & 7 == 0 {
                    0.0
                } else {
                    10f32.powf(range * (t - 0.5))
                };
            }
        }
    }
    Ok(v)
}

/// Valid warp options: blur radius biased small, floor log-uniform in
/// `[`[`MIN_FLOOR`]`, 1]`, temporal weight sometimes zero.
pub fn warp_options(u: &mut Unstructured<'_>) -> GenResult<WarpOptions> {
    let radius = match u.int_in_range(0u8..=3)? {
        0 => 0,
        1 => MAX_BLUR_RADIUS,
        _ => u.int_in_range(0u32..=8)?,
    };
    let floor = match u.int_in_range(0u8..=4)? {
        0 => MIN_FLOOR,
        1 => 1.0,
        _ => log_uniform(u, MIN_FLOOR, 1.0)?,
    };
    let temporal = if u.arbitrary()? {
        0.0
    } else {
        in_range(u, 0.0, 0.99)?
    };
    Ok(WarpOptions::default()
        .with_blur_radius(radius)
        .with_floor(floor)
        .with_temporal(temporal))
}

/// A valid warp case.
pub fn warp_case(u: &mut Unstructured<'_>) -> GenResult<WarpCase> {
    let (width, height) = (side(u)?, side(u)?);
    let values = importance_values(u, width, height)?;
    let second = if u.arbitrary()? {
        Some(importance_values(u, width, height)?)
    } else {
        None
    };
    Ok(WarpCase {
        width,
        height,
        values,
        second,
        options: warp_options(u)?,
    })
}

/// Any warp case: zero sizes, wrong lengths, NaN / infinite / negative values,
/// options out of range.
pub fn warp_case_raw(u: &mut Unstructured<'_>) -> GenResult<WarpCase> {
    let mut case = warp_case(u)?;
    match u.int_in_range(0u8..=6)? {
        0 => case.width = u.int_in_range(0u32..=2)?,
        1 => case.height = u.int_in_range(0u32..=2)?,
        2 => {
            let n = case.values.len();
            case.values
                .truncate(n.saturating_sub(u.int_in_range(0usize..=2)?));
        }
        3 => {
            for _ in 0..u.int_in_range(1u8..=4)? {
                if case.values.is_empty() {
                    break;
                }
                let i = u.int_in_range(0..=case.values.len() - 1)?;
                case.values[i] = any_f32(u)?;
            }
        }
        _ => {}
    }
    if u.int_in_range(0u8..=3)? == 0 {
        case.options = WarpOptions::default()
            .with_blur_radius(u.int_in_range(0u32..=MAX_BLUR_RADIUS + 2)?)
            .with_floor(any_f32(u)?)
            .with_temporal(any_f32(u)?);
    }
    Ok(case)
}

/// Asserts the contract of one warp table built by this crate (see the crate docs of
/// `shadowmap-rtw`): finite; zero at both ends; knots non-decreasing; the `f32`
/// forward warp maps 0 to 0 and 1 to 1, stays in `[0, 1]` and is monotone (to 2 ulps
/// of 1); the `f64` inverse undoes the `f64` forward warp.
pub fn check_table(table: &[f32]) {
    let n = table.len();
    assert!(n > 0, "empty table");
    assert!(
        table.iter().all(|t| t.is_finite()),
        "non-finite table {table:?}"
    );
    assert_eq!(table[0], 0.0, "first texel must be 0");
    assert_eq!(table[n - 1], 0.0, "last texel must be 0");
    let nf = n as f64;
    let mut prev = f64::NEG_INFINITY;
    for (i, &t) in table.iter().enumerate() {
        let k = (i as f64 + 0.5) / nf + f64::from(t);
        assert!(k >= prev, "knot {i} decreases: {k} < {prev}");
        prev = k;
    }
    assert_eq!(forward_warp(table, 0.0), 0.0);
    assert_eq!(forward_warp(table, 1.0), 1.0);
    let steps = 4 * n.min(1024) + 1;
    let mut last = 0.0f32;
    for s in 0..=steps {
        let u = s as f32 / steps as f32;
        let w = forward_warp(table, u);
        assert!(
            (0.0..=1.0).contains(&w),
            "forward({u}) = {w} outside [0, 1]"
        );
        assert!(
            w >= last - 2.5e-7,
            "forward not monotone at {u}: {w} < {last}"
        );
        last = last.max(w);
        // The inverse lands on a point with the same image (exact up to rounding).
        let w64 = forward_warp_f64(table, f64::from(u));
        let back = inverse_warp_f64(table, w64);
        let residual = (forward_warp_f64(table, back) - w64).abs();
        assert!(
            residual <= 1e-12,
            "forward(inverse({w64})) off by {residual}"
        );
    }
}

fn expected_values_error(width: u32, height: u32, values: &[f32]) -> Option<RtwError> {
    let len = width as usize * height as usize;
    if values.len() != len {
        return Some(RtwError::SizeMismatch {
            expected: len,
            got: values.len(),
        });
    }
    values.iter().find_map(|&v| {
        if !v.is_finite() {
            Some(RtwError::NonFinite)
        } else if v < 0.0 {
            Some(RtwError::NegativeImportance)
        } else {
            None
        }
    })
}

/// The warp builder's contract on any [`WarpCase`]: the documented error for zero
/// sizes, bad values and bad options (nothing modified); otherwise tables that pass
/// [`check_table`] and densities in `[floor, 1]`.
pub fn check_warp(case: &WarpCase) {
    let map = ImportanceMap::new(case.width, case.height);
    let warps = WarpMaps::new(case.width, case.height);
    if case.width == 0 || case.height == 0 {
        assert_eq!(map, Err(RtwError::EmptyMap));
        assert_eq!(warps, Err(RtwError::EmptyMap));
        return;
    }
    let (mut map, mut warps) = (map.expect("valid size"), warps.expect("valid size"));
    let options_ok = case.options.validate().is_ok();
    for values in core::iter::once(&case.values).chain(case.second.as_ref()) {
        let before = map.clone();
        match (
            map.copy_from_slice(values),
            expected_values_error(case.width, case.height, values),
        ) {
            (Ok(()), None) => assert_eq!(map.as_slice(), &values[..]),
            (Err(e), Some(x)) => {
                assert_eq!(e, x);
                assert_eq!(map, before, "map modified on error");
            }
            (got, want) => panic!("copy_from_slice gave {got:?}, expected error {want:?}"),
        }
        let previous = warps.clone();
        match warps.build(&map, &case.options) {
            Ok(()) => {
                assert!(options_ok, "accepted invalid options {:?}", case.options);
                check_built(&warps, &map, &case.options);
            }
            Err(e) => {
                assert!(!options_ok, "valid options rejected: {e:?}");
                assert_eq!(e, RtwError::InvalidOption);
                assert_eq!(warps, previous, "warps modified on error");
            }
        }
    }
}

/// Checks of a successful build: tables, densities, collapse, fallback.
pub fn check_built(warps: &WarpMaps, map: &ImportanceMap, options: &WarpOptions) {
    check_table(warps.x_table());
    check_table(warps.y_table());
    assert_eq!(warps.width(), map.width() as usize);
    assert_eq!(warps.height(), map.height() as usize);
    for d in warps.density_x().iter().chain(warps.density_y()) {
        assert!(
            d.is_finite() && *d >= options.floor * (1.0 - 1e-6) && *d <= 1.0,
            "density {d} outside [floor, 1]"
        );
    }
    let w = map.width() as usize;
    let cells = map.as_slice();
    for (x, &c) in warps.column_max().iter().enumerate() {
        let m = cells
            .iter()
            .skip(x)
            .step_by(w)
            .copied()
            .fold(0.0f32, f32::max);
        assert_eq!(c, m, "column {x} max");
    }
    for (y, &r) in warps.row_max().iter().enumerate() {
        let m = cells[y * w..(y + 1) * w]
            .iter()
            .copied()
            .fold(0.0f32, f32::max);
        assert_eq!(r, m, "row {y} max");
    }
    let zero = cells.iter().all(|&c| c == 0.0);
    assert_eq!(warps.identity_fallback(), [zero, zero]);
}

/// Input of [`check_accumulate`].
#[derive(Clone, Debug)]
pub struct AccumulateCase {
    /// The camera (valid).
    pub camera: Camera,
    /// The base projection (raw cases: possibly non-finite).
    pub base: ShadowTransform,
    /// Importance-map size (small, non-zero).
    pub size: (u32, u32),
    /// Eye samples (raw cases: NaN, infinite).
    pub samples: Vec<EyeSample>,
    /// Edge mask (raw cases: wrong length).
    pub edge_mask: Option<Vec<bool>>,
    /// Options (raw cases: anything).
    pub options: ImportanceOptions,
    /// Focal length in pixels for the oracle (raw cases: anything).
    pub pixels_per_radian: f32,
    /// A previous shadow map for forward analysis, `(width, height, depths)`.
    pub depths: (u32, u32, Vec<f32>),
}

fn fallback_base() -> ShadowTransform {
    let clip = projection::orthographic(-10.0, 10.0, -10.0, 10.0, 0.0, 100.0, false).as_mat4();
    let light = Mat4::from_translation(Vec3::new(0.0, 0.0, -50.0))
        * directional_light_from_world(Vec3::NEG_Y, Vec3::Z).unwrap_or(Mat4::IDENTITY);
    ShadowTransform::new(
        light,
        clip * light,
        false,
        LightDirection::Directional(Vec3::NEG_Y),
    )
}

/// `count` eye samples inside the camera's frustum (a quarter with no normal), with
/// their true eye distances.
pub(crate) fn frustum_samples(
    u: &mut Unstructured<'_>,
    camera: &Camera,
    count: usize,
) -> GenResult<Vec<EyeSample>> {
    let corners = camera
        .frustum()
        .map(|f| f.corners)
        .unwrap_or([Vec3::ZERO; 8]);
    let eye = camera.eye();
    let mut samples = Vec::with_capacity(count);
    for _ in 0..count {
        let (a, b, c) = (
            in_range(u, 0.0, 1.0)?,
            in_range(u, 0.0, 1.0)?,
            in_range(u, 0.0, 1.0)?,
        );
        let lerp = |p: Vec3, q: Vec3, t: f32| p + (q - p) * t;
        let near = lerp(
            lerp(corners[0], corners[1], a),
            lerp(corners[3], corners[2], a),
            b,
        );
        let far = lerp(
            lerp(corners[4], corners[5], a),
            lerp(corners[7], corners[6], a),
            b,
        );
        let position = lerp(near, far, c);
        let normal = if u.int_in_range(0u8..=3)? == 0 {
            Vec3::ZERO
        } else {
            unit_vec3(u)?
        };
        samples.push(EyeSample {
            position,
            normal,
            eye_distance: position.distance(eye),
        });
    }
    Ok(samples)
}

/// A valid accumulation case: a generated camera, a light, the tight uniform fit of
/// its whole range as the base, and samples inside the frustum.
pub fn accumulate_case(u: &mut Unstructured<'_>) -> GenResult<AccumulateCase> {
    let camera = camera(u)?;
    accumulate_case_for(u, camera)
}

/// [`accumulate_case`] for a given camera.
fn accumulate_case_for(u: &mut Unstructured<'_>, camera: Camera) -> GenResult<AccumulateCase> {
    let light = light_direction(u, &camera)?;
    let base = camera
        .depth_range()
        .and_then(|(n, f)| {
            let opts = CascadeOptions::default().with_fit(CascadeFit::Tight);
            fit_cascade(&camera, light, n, f, &opts)
        })
        .map_or_else(|_| fallback_base(), |c| c.transform);
    let size = (u.int_in_range(1u32..=48)?, u.int_in_range(1u32..=48)?);
    let count = u.int_in_range(0usize..=64)?;
    let samples = frustum_samples(u, &camera, count)?;
    let edge_mask = if u.arbitrary()? {
        Some((0..count).map(|_| u.arbitrary().unwrap_or(false)).collect())
    } else {
        None
    };
    let (dw, dh) = (u.int_in_range(1u32..=16)?, u.int_in_range(1u32..=16)?);
    let depths = (0..dw * dh)
        .map(|_| in_range(u, 0.0, 1.0))
        .collect::<GenResult<Vec<f32>>>()?;
    Ok(AccumulateCase {
        camera,
        base,
        size,
        samples,
        edge_mask,
        options: ImportanceOptions::default()
            .with_distance_exponent(in_range(u, 0.0, 3.0)?)
            .with_orientation_weight(in_range(u, 0.0, 4.0)?),
        pixels_per_radian: log_uniform(u, 1.0, 1e4)?,
        depths: (dw, dh, depths),
    })
}

/// Any accumulation case: non-finite samples and transforms, wrong mask lengths,
/// options out of range, bad depth maps.
pub fn accumulate_case_raw(u: &mut Unstructured<'_>) -> GenResult<AccumulateCase> {
    let mut case = accumulate_case(u)?;
    for _ in 0..u.int_in_range(0u8..=3)? {
        match u.int_in_range(0u8..=7)? {
            0 if !case.samples.is_empty() => {
                let i = u.int_in_range(0..=case.samples.len() - 1)?;
                case.samples[i] = EyeSample {
                    position: any_vec3(u)?,
                    normal: any_vec3(u)?,
                    eye_distance: any_f32(u)?,
                };
            }
            1 => case.edge_mask = Some(vec![true; u.int_in_range(0usize..=3)?]),
            2 => {
                case.options = ImportanceOptions::default()
                    .with_reference_distance(any_f32(u)?)
                    .with_min_distance(any_f32(u)?)
                    .with_distance_exponent(any_f32(u)?)
                    .with_orientation_weight(any_f32(u)?)
                    .with_edge_weight(any_f32(u)?);
            }
            3 => case.pixels_per_radian = any_f32(u)?,
            4 => case.base.uv_from_world.w_axis.x = any_f32(u)?,
            5 => case.depths.2.truncate(u.int_in_range(0usize..=3)?),
            6 if !case.depths.2.is_empty() => {
                let i = u.int_in_range(0..=case.depths.2.len() - 1)?;
                case.depths.2[i] = any_f32(u)?;
            }
            _ => case.base.light = LightDirection::Directional(any_vec3(u)?),
        }
    }
    Ok(case)
}

fn map_is_sane(map: &ImportanceMap) {
    assert!(
        map.as_slice().iter().all(|c| c.is_finite() && *c >= 0.0),
        "importance map has a negative or non-finite cell"
    );
}

/// Backward, oracle and forward accumulation on any [`AccumulateCase`]: `Ok` only for
/// valid input (then every sample is counted once, cells stay finite and
/// non-negative, and the warps built from the map pass [`check_built`]), otherwise
/// the documented error with the map unchanged.
pub fn check_accumulate(case: &AccumulateCase) {
    let (w, h) = case.size;
    let mut map = ImportanceMap::new(w, h).expect("generated sizes are valid");
    let samples_ok = case
        .samples
        .iter()
        .all(|s| s.position.is_finite() && s.normal.is_finite() && s.eye_distance.is_finite());
    let base_ok = case.base.uv_from_world.is_finite()
        && case.base.light_from_world.is_finite()
        && match case.base.light {
            LightDirection::Directional(d) | LightDirection::Position(d) => d.is_finite(),
        };
    let mask_ok = case
        .edge_mask
        .as_ref()
        .is_none_or(|m| m.len() == case.samples.len());
    let options_ok = case.options.validate().is_ok();

    let before = map.clone();
    let r = map.accumulate_backward(
        &case.base,
        &case.samples,
        case.edge_mask.as_deref(),
        &case.options,
    );
    match r {
        Ok(stats) => {
            assert!(
                samples_ok && base_ok && mask_ok && options_ok,
                "accepted bad input"
            );
            assert_eq!(stats.accepted + stats.skipped, case.samples.len());
            map_is_sane(&map);
        }
        Err(e) => {
            let explained = match e {
                RtwError::NonFinite => !samples_ok || !base_ok,
                RtwError::SizeMismatch { .. } => !mask_ok,
                RtwError::InvalidOption => !options_ok,
                _ => false,
            };
            assert!(explained, "unexpected error {e:?}");
            assert_eq!(map, before, "map modified on error");
        }
    }

    let ppr_ok = case.pixels_per_radian.is_finite() && case.pixels_per_radian > 0.0;
    let before = map.clone();
    match map.accumulate_oracle(
        &case.base,
        &case.camera,
        case.pixels_per_radian,
        &case.samples,
    ) {
        Ok(stats) => {
            assert!(samples_ok && base_ok && ppr_ok, "oracle accepted bad input");
            assert_eq!(stats.accepted + stats.skipped, case.samples.len());
            map_is_sane(&map);
        }
        Err(e) => {
            let explained = match e {
                RtwError::NonFinite => !samples_ok || !base_ok,
                RtwError::InvalidOption => !ppr_ok,
                _ => false,
            };
            assert!(explained, "unexpected oracle error {e:?}");
            assert_eq!(map, before, "map modified on error");
        }
    }

    let (dw, dh, depths) = &case.depths;
    let before = map.clone();
    let forward = map.accumulate_forward(
        &case.base,
        &case.base,
        None,
        depths,
        *dw,
        *dh,
        &case.camera,
        &case.options,
    );
    match forward {
        Ok(stats) => {
            assert!(options_ok && base_ok, "forward analysis accepted bad input");
            assert_eq!(stats.accepted + stats.skipped, depths.len());
            map_is_sane(&map);
        }
        Err(e) => {
            let explained = match e {
                RtwError::NonFinite => {
                    let m = case.base.uv_from_world.as_dmat4();
                    !base_ok || m.determinant().abs() < 1e-300 || !m.inverse().is_finite()
                }
                RtwError::SizeMismatch { .. } => depths.len() != (*dw * *dh) as usize,
                RtwError::InvalidOption => !options_ok,
                _ => false,
            };
            assert!(explained, "unexpected forward error {e:?}");
            assert_eq!(map, before, "map modified on error");
        }
    }

    let mut warps = WarpMaps::new(w, h).expect("valid size");
    let options = WarpOptions::default();
    warps.build(&map, &options).expect("valid options");
    check_built(&warps, &map, &options);
}

/// Input of [`check_spot_rtw`]: RTW over the spot fit (a perspective base).
#[derive(Clone, Debug)]
pub struct SpotRtwCase {
    /// Camera, samples, map size and options; its base is replaced by the spot fit.
    pub accumulate: AccumulateCase,
    /// The light (raw cases: any spot, or not a spot).
    pub light: Light,
    /// Receiver and caster bounds, if any.
    pub scene: Option<SceneBounds>,
    /// Warp options.
    pub warp: WarpOptions,
}

/// A spot light around a point the camera looks at, at any distance from it, mostly
/// aimed at it, sometimes back at the viewer (dueling frusta) or anywhere; half-angle
/// up to 86 degrees; sometimes non-finite or not a spot (raw).
pub fn spot_rtw_case_raw(u: &mut Unstructured<'_>) -> GenResult<SpotRtwCase> {
    // The light first: the samples take what is left of the input.
    let camera = &camera(u)?;
    let (near, far) = camera.depth_range().unwrap_or((0.1, 100.0));
    let scale = far.min(1e3).max(near);
    let target = camera.eye() + camera.forward() * in_range(u, near, scale)?;
    let distance = log_uniform(u, 1e-3 * scale, 2.0 * scale)?;
    let position = target + unit_vec3(u)? * distance;
    let direction = match u.int_in_range(0u8..=4)? {
        0 => -camera.forward(),
        1 => unit_vec3(u)?,
        _ => (target - position).normalize_or(Vec3::NEG_Y),
    };
    let light = match u.int_in_range(0u8..=7)? {
        0 => Light::Spot {
            position: any_vec3(u)?,
            direction: any_vec3(u)?,
            half_angle: any_f32(u)?,
            range: any_f32(u)?,
        },
        1 => Light::Point {
            position,
            range: scale,
        },
        _ => Light::Spot {
            position,
            direction,
            half_angle: in_range(u, 1e-3, 1.5)?,
            range: distance * log_uniform(u, 0.5, 1e3)?,
        },
    };
    let scene = if u.int_in_range(0u8..=3)? == 0 {
        Some(SceneBounds {
            receivers: aabb(u, scale)?,
            casters: aabb(u, scale)?,
        })
    } else {
        None
    };
    let warp = warp_options(u)?;
    Ok(SpotRtwCase {
        accumulate: accumulate_case_for(u, *camera)?,
        light,
        scene,
        warp,
    })
}

/// RTW over the spot fit, where the spot fit succeeds: accumulation on the
/// perspective base keeps the contract of [`check_accumulate`]; every sample the spot
/// fit maps into its map is mapped into the map by RTW too (coverage), with the base's
/// depth, a finite `uv` that the inverse warp takes back, and the order of the base
/// `u` and `v` kept (monotone warp). Returns how many samples were checked that way.
pub fn check_spot_rtw(case: &SpotRtwCase) -> usize {
    let Ok(frustum) = case.accumulate.camera.frustum() else {
        return 0;
    };
    let Ok(spot) = fit_spot(&case.light, &frustum, case.scene.as_ref(), false) else {
        return 0;
    };
    let accumulate = AccumulateCase {
        base: spot.transform,
        ..case.accumulate.clone()
    };
    check_accumulate(&accumulate);
    let (w, h) = accumulate.size;
    let mut map = ImportanceMap::new(w, h).expect("generated sizes are valid");
    map.accumulate_backward(
        &spot.transform,
        &accumulate.samples,
        None,
        &accumulate.options,
    )
    .expect("valid samples and options");
    let mut warps = WarpMaps::new(w, h).expect("valid size");
    warps.build(&map, &case.warp).expect("valid options");
    check_built(&warps, &map, &case.warp);
    let rtw = RtwShadow {
        base: spot.transform,
        warps: &warps,
    };
    let mut mapped: Vec<(DVec2, DVec2)> = Vec::new();
    for s in &accumulate.samples {
        let p = s.position.as_dvec3();
        let Some(b) = spot.transform.map_point(p) else {
            continue;
        };
        let inside = |uv: DVec2| uv.cmpge(DVec2::ZERO).all() && uv.cmple(DVec2::ONE).all();
        if !inside(b.uv) {
            continue;
        }
        let r = rtw
            .map_point(p)
            .expect("inside the base map, mapped by RTW");
        assert!(r.uv.is_finite() && inside(r.uv), "{:?} left the map", r.uv);
        assert_eq!(r.depth, b.depth, "RTW changed the base depth");
        let back = warps.unwarp_uv(r.uv.as_vec2()).as_dvec2();
        assert!(
            (back - b.uv).abs().max_element() < 1e-4,
            "{back} vs {}",
            b.uv
        );
        mapped.push((b.uv, r.uv));
    }
    for (a, b) in mapped
        .iter()
        .flat_map(|a| mapped.iter().map(move |b| (a, b)))
    {
        for axis in 0..2 {
            if a.0[axis] < b.0[axis] {
                assert!(a.1[axis] <= b.1[axis] + 1e-12, "warp not monotone");
            }
        }
    }
    mapped.len()
}
