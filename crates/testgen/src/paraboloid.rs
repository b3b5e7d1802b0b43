//! Generators and checks for `shadowmap-paraboloid` (fuzz targets and property tests).
//!
//! Each builder has a valid-input generator biased to the degenerate edges, a `*_raw`
//! generator (anything, for fuzzing), and a `check_*` function asserting the contract:
//! `Ok` output is finite and sane, anything else is a typed error, and nothing panics.

use arbitrary::Unstructured;
use glam::{DVec2, DVec3, Vec3};
use shadowmap_frustum::{Camera, DepthBounds, Light, ShadowMapping};
use shadowmap_paraboloid::{
    ConeFit, IpsmOptions, IpsmPlan, MAX_CONE_DIRECTIONS, MapOptions, ParaboloidMap, ParaboloidMode,
    Side, SubdivisionOptions, edge_subdivisions, fit_minimal_cone, fit_paper_cone,
    subdivide_triangle,
};

use crate::{
    GenResult, any_f32, any_vec3, camera, camera_raw, in_range, log_uniform, near_parallel,
    position, unit_vec3,
};

/// Input of [`IpsmPlan::new`].
#[derive(Clone, Debug)]
pub struct PlanInput {
    /// The light.
    pub light: Light,
    /// The camera.
    pub camera: Camera,
    /// Measured depth bounds, if any.
    pub bounds: Option<DepthBounds>,
    /// Options.
    pub options: IpsmOptions,
}

fn fit(u: &mut Unstructured<'_>) -> GenResult<ConeFit> {
    Ok(if u.arbitrary()? {
        ConeFit::Exact
    } else {
        ConeFit::Paper
    })
}

/// Valid plan options (fit, near, small margin, threshold, depth convention).
pub fn ipsm_options(u: &mut Unstructured<'_>) -> GenResult<IpsmOptions> {
    let margin = if u.arbitrary()? {
        0.0
    } else {
        log_uniform(u, 1e-6, 0.1)?
    };
    let max_single = if u.arbitrary()? {
        core::f32::consts::FRAC_PI_2
    } else {
        in_range(u, 0.1, core::f32::consts::FRAC_PI_2)?
    };
    Ok(IpsmOptions::default()
        .with_fit(fit(u)?)
        .with_near(log_uniform(u, 1e-3, 0.5)?)
        .with_margin(margin)
        .with_max_single_half_angle(max_single)
        .with_reversed_z(u.arbitrary()?)
        .with_up_hint(unit_vec3(u)?))
}

/// A valid plan input: a valid camera and bounds, a point or spot light placed inside
/// the truncated frustum, on or next to a border point, at the border points' centroid,
/// just outside a face, or far away.
pub fn plan_input(u: &mut Unstructured<'_>) -> GenResult<PlanInput> {
    let camera = camera(u)?;
    let (near, far) = camera.depth_range().unwrap_or((0.1, 100.0));
    let bounds = crate::depth_bounds_in(u, near, far)?;
    let (lo, hi) = match bounds {
        Some(b) => b.clamped_to(&camera).unwrap_or((near, far)),
        None => (near, far),
    };
    let corners = camera
        .slice(lo, hi)
        .map(|f| f.corners)
        .unwrap_or([Vec3::ZERO; 8]);
    let centroid = corners.iter().copied().sum::<Vec3>() / 8.0;
    let extent = corners
        .iter()
        .map(|c| c.distance(corners[0]))
        .fold(0.0, f32::max)
        .max(1e-3);
    let corner = corners[usize::from(u.int_in_range(0u8..=7)?)];
    let position = match u.int_in_range(0u8..=6)? {
        0 => corner,
        1 => corner + unit_vec3(u)? * extent * log_uniform(u, 1e-7, 1e-1)?,
        2 => centroid,
        3 => {
            // A random point of the frustum (inside).
            let w: [f32; 8] = core::array::from_fn(|_| in_range(u, 0.0, 1.0).unwrap_or(0.5));
            let s: f32 = w.iter().sum::<f32>().max(1e-6);
            corners.iter().zip(w).map(|(c, w)| *c * (w / s)).sum()
        }
        4 => centroid + unit_vec3(u)? * extent * log_uniform(u, 0.5, 1e4)?,
        5 => position(u, 1e3)?,
        _ => centroid + unit_vec3(u)? * extent * in_range(u, 0.3, 3.0)?,
    };
    let reach = corners
        .iter()
        .map(|c| c.distance(position))
        .fold(0.0, f32::max);
    let range = (reach * in_range(u, 1.0, 4.0)?).max(1.0) + 1.0;
    let light = if u.arbitrary()? {
        Light::Point { position, range }
    } else {
        Light::Spot {
            position,
            direction: unit_vec3(u)?,
            half_angle: in_range(u, 0.1, 1.5)?,
            range,
        }
    };
    Ok(PlanInput {
        light,
        camera,
        bounds,
        options: ipsm_options(u)?,
    })
}

/// Any plan input, often invalid (NaN lights, bad cameras, bad bounds and options).
pub fn plan_input_raw(u: &mut Unstructured<'_>) -> GenResult<PlanInput> {
    let mut input = plan_input(u)?;
    match u.int_in_range(0u8..=5)? {
        0 => input.camera = camera_raw(u)?,
        1 => {
            input.light = Light::Point {
                position: any_vec3(u)?,
                range: any_f32(u)?,
            };
        }
        2 => {
            input.bounds = Some(DepthBounds {
                min: any_f32(u)?,
                max: any_f32(u)?,
            });
        }
        3 => {
            input.options = input
                .options
                .with_near(any_f32(u)?)
                .with_margin(any_f32(u)?)
                .with_max_single_half_angle(any_f32(u)?)
                .with_up_hint(any_vec3(u)?);
        }
        4 => {
            input.light = Light::Directional {
                direction: any_vec3(u)?,
            }
        }
        _ => {}
    }
    Ok(input)
}

/// Runs [`IpsmPlan::new`] and checks the contract: bounds with `min > max` are refused;
/// an `Ok` plan is finite, its zoom in
/// `(0, 1]`, dual exactly when it gives a reason, every border point covered by the
/// fitted cone and, for a single map, mapped inside the usable disc.
///
/// # Errors
/// A description of the violated clause.
pub fn check_plan(input: &PlanInput) -> Result<(), String> {
    let result = IpsmPlan::new(&input.light, &input.camera, input.bounds, &input.options);
    if let Some(b) = input.bounds {
        if b.min > b.max && result.is_ok() {
            return Err(format!("bounds {b:?} with min > max accepted"));
        }
    }
    let plan = match result {
        Ok(p) => p,
        Err(_) => return Ok(()),
    };
    let m = &plan.map;
    if !(m.light_from_world.is_finite() && m.position.is_finite()) {
        return Err(format!("non-finite map {m:?}"));
    }
    if !(m.zoom > 0.0 && m.zoom <= 1.0) {
        return Err(format!("zoom {} outside (0, 1]", m.zoom));
    }
    if m.light_from_world.determinant().abs() < 0.5 {
        return Err("singular light frame".into());
    }
    if plan.is_single() == plan.dual_reason.is_some() {
        return Err(format!(
            "mode {:?} vs reason {:?}",
            m.mode, plan.dual_reason
        ));
    }
    if plan.is_single() && plan.cone.is_none() {
        return Err("single without a cone".into());
    }
    if let Some(cone) = plan.cone {
        if !(cone.axis.is_finite() && cone.half_angle.is_finite()) {
            return Err(format!("non-finite cone {cone:?}"));
        }
        for p in plan.border_points {
            let d = p - m.position;
            if d.length() > 1e-3 * (1.0 + p.length()) && !cone.contains(d, 1e-5) {
                return Err(format!("border point {p} outside {cone:?}"));
            }
        }
    }
    if plan.is_single() {
        for p in plan.border_points {
            let s = plan
                .map_point(p.as_dvec3())
                .or_else(|| m.project(p, Side::Front))
                .ok_or_else(|| format!("border point {p} unmapped"))?;
            let r = (s.uv - DVec2::splat(0.5)).length();
            if !(r <= 0.5 + 1e-4 && s.depth.is_finite()) {
                return Err(format!("border point {p} at uv {} (r = {r})", s.uv));
            }
        }
    }
    Ok(())
}

/// Directions for a cone fit, valid (non-zero, finite), 1 to 8 of them: clustered
/// around an axis (tight or wide), a few exactly repeated, antipodal pairs, or spread.
pub fn cone_directions(u: &mut Unstructured<'_>) -> GenResult<Vec<Vec3>> {
    let n = usize::from(u.int_in_range(1u8..=8)?);
    let base = unit_vec3(u)?;
    let spread = match u.int_in_range(0u8..=3)? {
        0 => log_uniform(u, 1e-5, 1e-2)?,
        1 => in_range(u, 0.1, 1.2)?,
        2 => in_range(u, 1.2, 1.7)?,
        _ => 3.2,
    };
    let mut out: Vec<Vec3> = Vec::with_capacity(n);
    for _ in 0..n {
        let d = match u.int_in_range(0u8..=9)? {
            0 if !out.is_empty() => out[usize::from(u.int_in_range(0u8..=7)?) % out.len()],
            1 if !out.is_empty() => -out[out.len() - 1],
            2 => near_parallel(u, base)?,
            _ => {
                let angle = in_range(u, 0.0, spread)?;
                let (a, b) = base.any_orthonormal_pair();
                let phi = in_range(u, 0.0, core::f32::consts::TAU)?;
                base * angle.cos() + (a * phi.cos() + b * phi.sin()) * angle.sin()
            }
        };
        let len = log_uniform(u, 1e-3, 1e3)?;
        out.push((d.try_normalize().unwrap_or(base)) * len);
    }
    Ok(out)
}

/// Any directions, 0 to 20 of them (too many, zero, NaN).
pub fn cone_directions_raw(u: &mut Unstructured<'_>) -> GenResult<Vec<Vec3>> {
    if u.arbitrary()? {
        return cone_directions(u);
    }
    let n = usize::from(u.int_in_range(0u8..=20)?);
    (0..n).map(|_| any_vec3(u)).collect()
}

/// The smallest cone around the directions by brute force over support sets: the caps
/// through one direction, through two (diametral) and through three (circumscribed).
/// Returns `(axis, half_angle)` in `f64`, or `None` when no cap under 90 degrees
/// contains every direction.
#[must_use]
pub fn brute_force_min_cone(directions: &[Vec3]) -> Option<(DVec3, f64)> {
    let d: Vec<DVec3> = directions
        .iter()
        .filter_map(|v| v.as_dvec3().try_normalize())
        .collect();
    let angle = |a: DVec3, b: DVec3| a.cross(b).length().atan2(a.dot(b));
    let mut best: Option<(DVec3, f64)> = None;
    let mut try_cap = |axis: DVec3| {
        let Some(axis) = axis.try_normalize() else {
            return;
        };
        let half = d.iter().map(|&x| angle(axis, x)).fold(0.0, f64::max);
        let all_in = d.iter().all(|&x| angle(axis, x) <= half + 1e-12);
        if all_in && half < core::f64::consts::FRAC_PI_2 && best.is_none_or(|b| half < b.1) {
            best = Some((axis, half));
        }
    };
    let n = d.len();
    for i in 0..n {
        try_cap(d[i]);
        for j in i + 1..n {
            try_cap(d[i] + d[j]);
            for k in j + 1..n {
                let nrm = (d[j] - d[i]).cross(d[k] - d[i]);
                // The circumscribed cap's axis, on the side of the three points.
                let nrm = if nrm.dot(d[i]) < 0.0 { -nrm } else { nrm };
                // Only a cap whose boundary passes through the three points counts.
                try_cap(nrm);
            }
        }
    }
    // A cap must have its defining points on its boundary: the enumeration above
    // measures the half-angle as the largest angle, so every candidate contains all.
    best
}

/// Runs both cone fits and checks: `Ok` cones are finite, contain every direction,
/// the minimal one is under 90 degrees and never wider than the paper's; bad input
/// gives the documented errors.
///
/// # Errors
/// A description of the violated clause.
pub fn check_cone(directions: &[Vec3]) -> Result<(), String> {
    let exact = fit_minimal_cone(directions);
    let paper = fit_paper_cone(directions);
    let valid = !directions.is_empty()
        && directions.len() <= MAX_CONE_DIRECTIONS
        && directions
            .iter()
            .all(|d| d.is_finite() && d.as_dvec3().length() > 1e-300);
    for cone in [exact, paper].into_iter().flatten() {
        if !valid {
            return Err(format!("Ok cone {cone:?} for invalid input"));
        }
        if !(cone.axis.is_finite() && (cone.axis.length() - 1.0).abs() < 1e-5) {
            return Err(format!("bad axis {cone:?}"));
        }
        if !(0.0..=core::f32::consts::PI).contains(&cone.half_angle) {
            return Err(format!("bad half-angle {cone:?}"));
        }
        for &d in directions {
            if !cone.contains(d, 0.0) {
                return Err(format!("{d} outside {cone:?}"));
            }
        }
    }
    if let Ok(e) = exact {
        if e.half_angle >= core::f32::consts::FRAC_PI_2 {
            return Err(format!("minimal cone not under 90 degrees: {e:?}"));
        }
        if let Ok(p) = paper {
            if e.half_angle > p.half_angle + 1e-6 {
                return Err(format!("minimal {e:?} wider than paper {p:?}"));
            }
        }
    }
    Ok(())
}

/// Input of the [`ParaboloidMap`] builders and lookups.
#[derive(Clone, Debug)]
pub struct MapInput {
    /// Light position.
    pub position: Vec3,
    /// Front axis.
    pub axis: Vec3,
    /// `None` for a dual map, else the single map's half-angle.
    pub half_angle: Option<f32>,
    /// Near distance.
    pub near: f32,
    /// Far distance.
    pub far: f32,
    /// Options.
    pub options: MapOptions,
    /// Probe points (world).
    pub points: Vec<Vec3>,
}

/// A valid map and probe points between `near` and `far` from the light, in every
/// direction (biased to the axis, the rim, straight behind).
pub fn map_input(u: &mut Unstructured<'_>) -> GenResult<MapInput> {
    let position = position(u, 1e3)?;
    let axis = unit_vec3(u)?;
    let near = log_uniform(u, 1e-3, 1.0)?;
    let far = near * log_uniform(u, 2.0, 1e4)?;
    let half_angle = if u.arbitrary()? {
        None
    } else {
        Some(in_range(u, 1e-4, core::f32::consts::FRAC_PI_2)?)
    };
    let options = MapOptions::default()
        .with_up_hint(unit_vec3(u)?)
        .with_reversed_z(u.arbitrary()?);
    let n = usize::from(u.int_in_range(1u8..=8)?);
    let mut points = Vec::with_capacity(n);
    for _ in 0..n {
        let dir = match u.int_in_range(0u8..=4)? {
            0 => near_parallel(u, axis)?,
            1 => near_parallel(u, axis.any_orthonormal_vector())?,
            _ => unit_vec3(u)?,
        };
        let dist = in_range(u, near * 1.5, far)?;
        points.push(position + dir * dist);
    }
    Ok(MapInput {
        position,
        axis,
        half_angle,
        near,
        far,
        options,
        points,
    })
}

/// Any map input (NaN, zero axis, bad depth range, bad half-angle).
pub fn map_input_raw(u: &mut Unstructured<'_>) -> GenResult<MapInput> {
    let mut m = map_input(u)?;
    match u.int_in_range(0u8..=4)? {
        0 => m.position = any_vec3(u)?,
        1 => m.axis = any_vec3(u)?,
        2 => (m.near, m.far) = crate::depth_range_raw(u)?,
        3 => m.half_angle = Some(any_f32(u)?),
        _ => m.points.push(any_vec3(u)?),
    }
    Ok(m)
}

/// Builds the map.
///
/// # Errors
/// The builder's error.
pub fn build_map(input: &MapInput) -> Result<ParaboloidMap, shadowmap_paraboloid::ParaboloidError> {
    match input.half_angle {
        None => ParaboloidMap::dual(
            input.position,
            input.axis,
            input.near,
            input.far,
            &input.options,
        ),
        Some(h) => ParaboloidMap::single(
            input.position,
            input.axis,
            h,
            input.near,
            input.far,
            &input.options,
        ),
    }
}

/// Builds the map and checks: finite rigid frame, lookups finite with depth in
/// `[0, 1]` for points within `[near, far]`, front-hemisphere points of a dual map
/// inside the unit disc, and (for lookups that succeed) unproject returning the point.
///
/// # Errors
/// A description of the violated clause.
pub fn check_map(input: &MapInput) -> Result<(), String> {
    let Ok(map) = build_map(input) else {
        return Ok(());
    };
    if !map.light_from_world.is_finite() || map.light_from_world.determinant().abs() < 0.5 {
        return Err(format!("bad frame {map:?}"));
    }
    for &p in &input.points {
        let Some(s) = map.lookup(p) else {
            if map.mode == ParaboloidMode::Dual
                && p.is_finite()
                && p.as_dvec3().distance(map.position.as_dvec3()) > 1e-3
            {
                return Err(format!("dual map lost {p}"));
            }
            continue;
        };
        if !(s.uv.is_finite() && s.depth.is_finite()) {
            return Err(format!("non-finite sample {s:?}"));
        }
        let dist = p.as_dvec3().distance(map.position.as_dvec3());
        let (n, f) = (f64::from(map.near), f64::from(map.far));
        // f32 frames round the light's position: allow that much distance error.
        let slack =
            1e-6 * (1.0 + p.as_dvec3().length() + map.position.as_dvec3().length()) / (f - n);
        if dist >= n && dist <= f && !(-1e-4 - slack..=1.0 + 1e-4 + slack).contains(&s.depth) {
            return Err(format!("depth {} for distance {dist}", s.depth));
        }
        let side = if s.layer == 0 {
            Side::Front
        } else {
            Side::Back
        };
        if map.mode == ParaboloidMode::Dual && (s.uv - DVec2::splat(0.5)).length() > 0.5 + 1e-6 {
            return Err(format!("{p} on {side:?} outside the unit disc: {}", s.uv));
        }
        if let Some(back) = map.unproject(s.uv.as_vec2(), s.depth as f32, side) {
            let scale = 1.0 + p.as_dvec3().length() + map.position.as_dvec3().length();
            let far = f64::from(map.far);
            let err = back.as_dvec3().distance(p.as_dvec3());
            if err > 1e-5 * scale + 1e-4 * dist + 1e-6 * far {
                return Err(format!("roundtrip {p} -> {s:?} -> {back}"));
            }
        }
        let density = map.texels_per_steradian(p, 1024);
        if let Some(d) = density {
            if !(d.is_finite() && d > 0.0) {
                return Err(format!("density {d}"));
            }
        }
    }
    Ok(())
}

/// Input of the subdivision functions.
#[derive(Clone, Debug)]
pub struct SubdivideInput {
    /// The map.
    pub map: MapInput,
    /// The side to render.
    pub side: Side,
    /// Triangle.
    pub triangle: [Vec3; 3],
    /// Options.
    pub options: SubdivisionOptions,
}

/// A valid map, a triangle around it (sometimes through the light or behind), options.
pub fn subdivide_input(u: &mut Unstructured<'_>) -> GenResult<SubdivideInput> {
    let map = map_input(u)?;
    let side = if u.arbitrary()? {
        Side::Front
    } else {
        Side::Back
    };
    let scale = map.far * in_range(u, 0.01, 1.0)?;
    let c = map.position;
    let triangle = [
        c + unit_vec3(u)? * scale * in_range(u, 0.0, 1.0)?,
        c + unit_vec3(u)? * scale * in_range(u, 0.0, 1.0)?,
        c + unit_vec3(u)? * scale * in_range(u, 0.0, 1.0)?,
    ];
    let options = SubdivisionOptions::default()
        .with_resolution(u.int_in_range(16u32..=4096)?)
        .with_tolerance_texels(log_uniform(u, 0.05, 4.0)?)
        .with_max_segments(u.int_in_range(1u32..=32)?);
    Ok(SubdivideInput {
        map,
        side,
        triangle,
        options,
    })
}

/// Any subdivision input (bad options, NaN vertices).
pub fn subdivide_input_raw(u: &mut Unstructured<'_>) -> GenResult<SubdivideInput> {
    let mut s = subdivide_input(u)?;
    match u.int_in_range(0u8..=3)? {
        0 => {
            s.options = s
                .options
                .with_resolution(u.arbitrary()?)
                .with_tolerance_texels(any_f32(u)?)
                .with_max_segments(u.int_in_range(0u32..=300)?);
        }
        1 => s.triangle[usize::from(u.int_in_range(0u8..=2)?)] = any_vec3(u)?,
        2 => s.map = map_input_raw(u)?,
        _ => {}
    }
    Ok(s)
}

/// Subdivides and checks: the count is `n²` with `1 <= n <= max_segments`, the pieces
/// are finite and tile the triangle (their vector areas sum to its), and an edge
/// count below the limit really meets the tolerance at the segment midpoints.
///
/// # Errors
/// A description of the violated clause.
pub fn check_subdivide(input: &SubdivideInput) -> Result<(), String> {
    let Ok(map) = build_map(&input.map) else {
        return Ok(());
    };
    let mut pieces = Vec::new();
    let Ok(count) = subdivide_triangle(&map, input.side, input.triangle, &input.options, |t| {
        pieces.push(t);
    }) else {
        return Ok(());
    };
    let n = (count as f64).sqrt().round() as u32;
    let max = input.options.max_segments;
    if n * n != count || n == 0 || n > max || pieces.len() != count as usize {
        return Err(format!("count {count}, pieces {}, max {max}", pieces.len()));
    }
    if !pieces.iter().flatten().all(|p| p.is_finite()) {
        return Err("non-finite piece".into());
    }
    let t = input.triangle.map(Vec3::as_dvec3);
    let area = |t: [DVec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]);
    let sum: DVec3 = pieces.iter().map(|p| area(p.map(Vec3::as_dvec3))).sum();
    let whole = area(t);
    let scale = t.iter().map(|p| p.length()).fold(1.0, f64::max);
    if (sum - whole).length() > 1e-5 * scale * scale {
        return Err(format!("pieces area {sum} vs {whole}"));
    }
    // Every edge's own count meets the tolerance at its midpoints when below the limit.
    let res = f64::from(input.options.resolution);
    let tol = f64::from(input.options.tolerance_texels);
    for (a, b) in [(0, 1), (1, 2), (2, 0)] {
        let (pa, pb) = (input.triangle[a], input.triangle[b]);
        let k = edge_subdivisions(&map, input.side, pa, pb, &input.options)
            .map_err(|e| format!("edge error {e}"))?;
        if k >= max {
            continue;
        }
        // The check probes the curve through f32 world points: skip edges where that
        // rounding alone (about 1.2e-7 |p| seen from the light) moves the image by more
        // than a tenth of the tolerance.
        let l = map.position.as_dvec3();
        let (da, db) = (pa.as_dvec3(), pb.as_dvec3());
        let ab = db - da;
        let s = if ab.length_squared() > 0.0 {
            ((l - da).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d_min = (da + ab * s).distance(l);
        let magnitude = 1.0 + da.length().max(db.length()) + l.length();
        // Near the side's pole the image is stretched by d(disc radius)/d(angle) =
        // (1 + r^2) / 2.
        let r_max = [0.0, 0.5, 1.0]
            .into_iter()
            .filter_map(|s| map.project((da + ab * s).as_vec3(), input.side))
            .map(|x| (x.uv - DVec2::splat(0.5)).length() * 2.0 * f64::from(map.zoom))
            .fold(0.0, f64::max);
        let stretch = 1.0 + r_max * r_max;
        let rounding = 1.2e-7 * magnitude / d_min * res / f64::from(map.zoom) * 4.0 * stretch;
        if rounding.is_nan() || rounding >= 0.1 * tol {
            continue;
        }
        let at = |s: f64| {
            let p = pa.as_dvec3() + (pb.as_dvec3() - pa.as_dvec3()) * s;
            map.project(p.as_vec3(), input.side).map(|x| x.uv * res)
        };
        for i in 0..k {
            let (s0, s1) = (f64::from(i) / f64::from(k), f64::from(i + 1) / f64::from(k));
            let (Some(c0), Some(c1), Some(m)) = (at(s0), at(s1), at(0.5 * (s0 + s1))) else {
                continue;
            };
            let ab = c1 - c0;
            let t = if ab.length_squared() > 0.0 {
                ((m - c0).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let dev = m.distance(c0 + ab * t);
            // The f32 round trip of the world points moves the curve a little.
            if dev > tol * 1.01 + 1e-3 {
                return Err(format!(
                    "edge {a}-{b}: {k} segments, deviation {dev} > {tol}"
                ));
            }
        }
    }
    Ok(())
}
