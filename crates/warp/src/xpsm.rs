//! Extended perspective shadow maps (Gusev 2007).

use arrayvec::ArrayVec;
use glam::{DMat4, DVec3, DVec4, Vec3};
use shadowmap_frustum::{Camera, ShadowTransform};

use crate::FocusBody;
use crate::WarpError;
use crate::focus::{Bounds, Focus, ReceiverPoints, View, finish, scale_of, smoothstep};
use crate::lispsm::{scaled_strength, turn_invariant};
use crate::predict::Fits;
use shadowmap_frustum::math;

/// Options of [`xpsm`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct XpsmOptions {
    /// Depth 1 at the light's near plane and 0 at its far plane.
    pub reversed_z: bool,
    /// `epsilonW` of the paper, in `(0, 1)`: the smallest homogeneous `w` a point of
    /// the focus region may get, i.e. how far toward infinity the warp may push in the
    /// critical case (casters behind the viewer). Default 0.1.
    pub epsilon_w: f32,
    /// `coef` of the paper (inverse world units): warping `1 / (coef d + 1)` at view
    /// distance `d`, `lengthP = coef / cos γ`. `None` (default) uses
    /// `coef = 1 / sqrt(z_n z_f)` from the visible receivers and keeps the warp
    /// ratio it means over the visible region wherever that region lies (see
    /// [`xpsm`], step 6).
    pub coef: Option<f32>,
    /// `|V_xy|` (the sine of the angle between view and light) below which the
    /// miner's-lamp case applies: orthographic shadows with focusing. The paper
    /// switches at 0.1; here the projection vector fades out between twice this
    /// value and this value, so nothing pops. Default 0.1.
    pub miner_lamp_threshold: f32,
    /// The share of the chosen warp to apply, in `[0, 1]`: its warp ratio is raised
    /// to this power (1, the default: the strength the error prediction chose; 0:
    /// the orthographic fit with focusing). For a renderer that measures the fit on its
    /// own view samples and backs off where the prediction, made on the receivers'
    /// box, misjudges what the eye sees (`shadowmap::fit` does, given the eye's
    /// samples). At 0 the prediction, most of the fit's time, is skipped.
    pub strength_scale: f32,
}

impl Default for XpsmOptions {
    fn default() -> Self {
        Self::new()
    }
}

impl XpsmOptions {
    /// Defaults: standard depth, `epsilon_w = 0.1`, automatic `coef`, threshold 0.1.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            reversed_z: false,
            epsilon_w: 0.1,
            coef: None,
            miner_lamp_threshold: 0.1,
            strength_scale: 1.0,
        }
    }

    /// Sets [`reversed_z`](Self::reversed_z).
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }

    /// Sets [`epsilon_w`](Self::epsilon_w).
    #[must_use]
    pub const fn with_epsilon_w(mut self, epsilon_w: f32) -> Self {
        self.epsilon_w = epsilon_w;
        self
    }

    /// Sets [`coef`](Self::coef).
    #[must_use]
    pub const fn with_coef(mut self, coef: f32) -> Self {
        self.coef = Some(coef);
        self
    }

    /// Sets [`miner_lamp_threshold`](Self::miner_lamp_threshold).
    #[must_use]
    pub const fn with_miner_lamp_threshold(mut self, threshold: f32) -> Self {
        self.miner_lamp_threshold = threshold;
        self
    }

    /// Sets [`strength_scale`](Self::strength_scale).
    #[must_use]
    pub const fn with_strength_scale(mut self, strength_scale: f32) -> Self {
        self.strength_scale = strength_scale;
        self
    }

    pub(crate) fn validate(&self) -> Result<(), WarpError> {
        let coef_ok = match self.coef {
            Some(c) => c.is_finite() && c >= 0.0,
            None => true,
        };
        let ok = self.epsilon_w > 0.0
            && self.epsilon_w < 1.0
            && coef_ok
            && self.miner_lamp_threshold >= 0.0
            && self.miner_lamp_threshold < 0.5
            && (0.0..=1.0).contains(&self.strength_scale);
        if ok {
            Ok(())
        } else {
            Err(WarpError::InvalidOption)
        }
    }
}

/// An XPSM fit: the matrices, the Z bias scale of step 18, and the quantities the
/// algorithm chose.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct XpsmShadow {
    /// The matrices (depth pass and lookup).
    pub transform: ShadowTransform,
    /// `1 / (MaxZ - MinZ)`: a bias of `b` world units toward the light, applied in
    /// light space, changes clip `z` (before the division by `w`) by exactly
    /// `-b * z_bias_scale` (standard depth) or `+b * z_bias_scale` (reversed-Z); see
    /// [`XpsmShadow::biased_clip_z`].
    pub z_bias_scale: f32,
    /// Length of the projection vector after clipping (0: orthographic).
    pub length_p: f32,
    /// The back-projection bound `maxLengthP` (infinite when there is none).
    #[cfg_attr(
        feature = "serde",
        serde(with = "crate::serde_impls::infinite_as_none")
    )]
    pub max_length_p: f32,
    /// Miner's-lamp weight in `[0, 1]`: 1 is full warp, 0 the miner's-lamp case
    /// (orthographic with focusing).
    pub warp_weight: f32,
}

impl XpsmShadow {
    /// Step 18, the correct Z bias: the clip `z` of a point biased by `bias` world
    /// units toward the light, from its unbiased clip `z` (the shader then divides by
    /// `w`): `Z' = Z - bias / (MaxZ - MinZ)` (standard depth; `+` for reversed-Z).
    #[must_use]
    pub fn biased_clip_z(&self, clip_z: f32, bias: f32) -> f32 {
        let dz = bias * self.z_bias_scale;
        if self.transform.reversed_z {
            clip_z + dz
        } else {
            clip_z - dz
        }
    }
}

/// Homogeneous post-projective light-space point.
type Hom = DVec4;

/// Extended perspective shadow map (Gusev 2007).
///
/// The 18 steps of the paper, in this crate's conventions (column vectors, light
/// looking down `-Z`, WebGPU depth). Receivers are the vertices of frustum ∩
/// receivers; casters the corners of the caster box.
///
/// 1. Light space: the shared light frame ([`light_frame`](crate::light_frame)) with
///    its origin at the viewer (for the automatic length of step 6, moved along
///    `unit P` to the near face of the focus body).
/// 2. The view vector in light space, `V`.
/// 3. `unit P = V_xy / |V_xy|`, which is the frame's `+Y` whenever `V_xy` is not tiny
///    (in the near-parallel band the frame turns continuously toward the camera's
///    up vector). Miner's lamp: the paper switches to orthographic focusing at
///    `|V_xy| < 0.1`; here the projection vector fades out between `2 t` and `t`
///    ([`XpsmOptions::miner_lamp_threshold`]; the warp ratio `1 + lengthP D` is
///    raised to a smoothstep weight, as LiSPSM and TSM fade), ending in the same
///    orthographic fit with focusing, so nothing pops.
/// 4. `minCastersProj`, `minReceiversProj`: smallest projections on `unit P`.
/// 5. `maxLengthP = (epsilonW - 1) / max(minCastersProj, minReceiversProj)` when the
///    focus interval starts behind the viewer (no bound otherwise).
/// 6. `lengthP = coef / cos γ`, `cos γ = |V_xy|`, for a given
///    [`XpsmOptions::coef`]. By default the warp ratio the paper's
///    `coef = 1 / sqrt(z_n z_f)` means over the visible depth range,
///    `1 + coef (z_f - z_n)`, is spread over the receivers' extent `D` along
///    `unit P`, `lengthP = coef (z_f - z_n) / D`, and the origin of step 1 moves
///    along `unit P` from the viewer to the near face of the focus body. This equals
///    the paper's length and origin when the visible region starts at the viewer
///    and its extent is the depth range times `cos γ`; a camera looking down or
///    toward the light breaks both, and the paper's length then over-warps.
///    Even so the automatic length can starve what is seen (a camera standing in
///    a large scene, whose nearest surfaces are far beyond the near plane; a length
///    clipped at the back-projection singularity, which magnifies the receivers
///    next to it): the quality report's random sweep measured up to 61 times the
///    uniform fit's 95th-percentile error. So the automatic length is then scaled,
///    in `ln(1 + lengthP D)`, to the fraction of least predicted error over the
///    focus body, as in [`lispsm`](crate::lispsm): the paper's length where it is
///    predicted clearly better than the uniform fit, continuously down to the
///    miner's-lamp fit elsewhere. A given `coef` is used as it is.
/// 7. Clip: `lengthP = min(lengthP, maxLengthP)` when `maxLengthP > 0`. Then two
///    precision guards: `1 + lengthP * maxProj <= MAX_WARP_RATIO` and
///    `lengthP <= MAX_WARP_RATIO / L` ([`MAX_WARP_RATIO`](crate::MAX_WARP_RATIO)).
/// 8. `Projection`: `w = 1 + lengthP (P · xy)`.
/// 9. `ZRotation`, mapping `unit P` to `+X` (a rotation; the paper's matrix is a
///    reflection, right for D3D's left-handed frame).
/// 10. `PPLS = ZRotation * Projection` (they commute: the rotation leaves `w` alone).
/// 11. Casters and receivers to PPLS, clipped at `w = epsilonW` (below).
/// 12. Their PPLS boxes.
/// 13. Focus region: intersection of the boxes in xy ([`WarpError::EmptyFocusRegion`]
///     when empty; boxes that only touch, up to `f32` rounding, give a zero-area
///     region that is widened).
/// 14. `MinZ`, `MaxZ` over both boxes; the focus region basis.
/// 15. Its inverse, the unit-cube transform.
/// 16. Normalized space for WebGPU: `x, y` to `[-1, 1]`, depth `1 - z` (standard) or
///     `z` (reversed-Z), both in `[0, 1]`.
/// 17. `clip_from_world = Normalized * UnitCube * PPLS * LightSpace`.
/// 18. Z bias: [`XpsmShadow::z_bias_scale`] `= 1 / (MaxZ - MinZ)` (the paper's D3D
///     form, which is WebGPU's), applied by [`XpsmShadow::biased_clip_z`]:
///
/// ```text
/// Z' = (Z - bias / (MaxZ - MinZ)) / W      standard depth
/// Z' = (Z + bias / (MaxZ - MinZ)) / W      reversed-Z
/// ```
///
/// Points with `w < epsilonW` (beyond the back-projection bound) are handled so that
/// they never shrink the focus region wrongly: each point set is clipped by the plane
/// `w = epsilonW` (its vertices in front plus the crossings of every segment between a
/// vertex in front and one behind), and that clipped set gives the Z bounds and the xy
/// boxes; the points behind the plane also enter the xy boxes with `w` raised to
/// `epsilonW` (only widening them), but are excluded from the Z bounds. A caster that
/// can shadow a visible receiver lies above it and so never has `w < epsilonW`.
///
/// Visible receivers outside the casters' light-space footprint are not covered by
/// the focus region (nothing can shadow them): sample outside the map as lit.
///
/// # Errors
/// As [`uniform_focused`](crate::uniform_focused); [`WarpError::InvalidOption`];
/// [`WarpError::EmptyFocusRegion`] when caster and receiver boxes do not overlap in
/// post-projective light space (nothing visible can be shadowed).
pub fn xpsm(
    camera: &Camera,
    light_direction: Vec3,
    scene: &crate::SceneBounds,
    options: &XpsmOptions,
) -> Result<XpsmShadow, WarpError> {
    options.validate()?;
    FocusBody::fit_from(camera, light_direction, scene, |body| body.xpsm(options))
}

impl FocusBody {
    /// The XPSM fit of this body (see [`xpsm`]).
    ///
    /// # Errors
    /// [`WarpError::InvalidOption`]; [`WarpError::EmptyFocusRegion`];
    /// [`WarpError::Degenerate`].
    pub fn xpsm(&self, options: &XpsmOptions) -> Result<XpsmShadow, WarpError> {
        options.validate()?;
        xpsm_body(self, options)
    }
}

fn xpsm_body(body: &FocusBody, options: &XpsmOptions) -> Result<XpsmShadow, WarpError> {
    let (view, f) = (&body.view, &body.focus);
    // Steps 2-3: view vector in light space and its xy direction. The shared light
    // frame has +Y along V_xy whenever V_xy is not tiny, so unit P = (0, 1); in the
    // near-parallel band the frame follows the camera's up vector continuously.
    let v_xy = f.sin_gamma;
    let thr = f64::from(options.miner_lamp_threshold);
    let weight = smoothstep(thr, 2.0 * thr, v_xy);
    // Step 6 (first, since the automatic length places the origin): optimal length.
    let (length_p, shift) = match options.coef {
        Some(c) if weight > 0.0 => {
            let (y0, y1) = f.warp_axis_range();
            (faded_length(f64::from(c) / v_xy, y1 - y0, weight), 0.0)
        }
        Some(_) => (0.0, 0.0),
        None => auto_length(f, view, weight),
    };
    let space = XpsmSpace::new(view, f, options, shift);
    // The automatic length after the prediction, and the prediction's `t` where it
    // ran (scaled to 0 below whatever the prediction: skipped).
    let mut fits = Fits::new();
    let (length_p, predicted) = if options.coef.is_none() && options.strength_scale > 0.0 {
        predicted_length(body, &space, options, length_p, &mut fits)
    } else {
        (length_p, None)
    };
    // A scale of 1 keeps the length exactly (`scaled_strength`), and so the
    // prediction's fit at it, where it made one.
    let fresh;
    let fit = match predicted.and_then(|t| fits.at(t)) {
        Some(fit) if options.strength_scale >= 1.0 => fit,
        _ => {
            let length_p = scaled_strength(f, length_p, options.strength_scale);
            fresh = xpsm_fit(&space, f, options, length_p)?;
            &fresh
        }
    };
    // The lookup is evaluated at the receivers: the matrix must resolve them too,
    // not only the whole caster box's reach (a depth range spanning absurdly tall
    // casters can leave it singular there).
    let scales = [fit.world_scale as f32, f.receiver_scale as f32];
    let transform = finish(f, fit.clip(&space), options.reversed_z, &scales)?;
    // Step 18: Z bias scale, 1 / (MaxZ - MinZ).
    let z_bias_scale = (1.0 / fit.z_extent) as f32;
    if !(z_bias_scale.is_finite() && z_bias_scale > 0.0) {
        return Err(WarpError::Degenerate);
    }
    Ok(XpsmShadow {
        transform,
        z_bias_scale,
        length_p: fit.length_p as f32,
        max_length_p: fit.max_length_p as f32,
        warp_weight: weight as f32,
    })
}

/// The automatic `lengthP` after the error prediction: the fraction of the warp
/// ratio `ln(1 + lengthP D)` (`D` the focus body's extent along `unit P`) of least
/// predicted error (see the module `predict`), so that XPSM degrades continuously
/// to the orthographic fit with focusing where the paper's length does not pay: a
/// camera looking down or toward the light, a body reaching far behind the viewer,
/// or a projection vector clipped at the back-projection singularity (step 7),
/// which magnifies the receivers nearest the singularity and starves the rest.
/// Also the fraction `t` chosen, where the prediction ran (its fits in `fits`).
fn predicted_length(
    body: &FocusBody,
    space: &XpsmSpace,
    options: &XpsmOptions,
    length: f64,
    fits: &mut Fits<XpsmFit>,
) -> (f64, Option<f64>) {
    let f = &body.focus;
    let (y0, y1) = f.warp_axis_range();
    let d = (y1 - y0).max(0.0);
    if !(length > 0.0 && d > 0.0) {
        return (length, None);
    }
    let ln_r = math::ln(1.0 + length * d);
    if !(ln_r.is_finite() && ln_r > 0.0) {
        return (length, None);
    }
    let at = |t: f64| {
        if t >= 1.0 {
            length
        } else {
            (math::exp(t * ln_r) - 1.0) / d
        }
    };
    let t = body.probe().strength(
        fits,
        |t| xpsm_fit(space, f, options, at(t)).ok(),
        |fit| &fit.clip_from_light,
    );
    (at(t), Some(t))
}

/// The fitted matrices of steps 4-17 for a given `lengthP`.
struct XpsmFit {
    /// Step 17 before its product with light space (`XpsmSpace::light_space`).
    clip_from_light_space: DMat4,
    /// The same from the light frame (`Focus::rot`), which the error prediction
    /// reads.
    clip_from_light: DMat4,
    world_scale: f64,
    /// `MaxZ - MinZ`.
    z_extent: f64,
    /// `lengthP` after the clip of step 7 and the precision guards.
    length_p: f64,
    max_length_p: f64,
}

impl XpsmFit {
    /// Step 17: the fit's `clip_from_world` in `space`.
    fn clip(&self, space: &XpsmSpace) -> DMat4 {
        self.clip_from_light_space * space.light_space
    }
}

/// What the fits of one XPSM call share, whatever their `lengthP` (step 1, the
/// projections of step 4 and the bound of step 5): built once, so the prediction's
/// fits at several lengths and the final one do not transform the body again.
struct XpsmSpace {
    /// Step 1: light space, origin at the viewer (moved along unit P by `shift`
    /// for the automatic length), light along -Z.
    light_space: DMat4,
    /// The receivers and the caster box's corners in light space.
    receivers: ReceiverPoints,
    casters: ArrayVec<DVec3, 8>,
    /// Largest projection on unit P of either.
    max_proj: f64,
    /// Step 5: the longest projection vector (eq. 3).
    max_length_p: f64,
    /// The largest world coordinate the `f32` matrix computes `w` at.
    world_scale: f64,
}

impl XpsmSpace {
    /// The space of `f` seen from `view`, with the origin moved by `shift`.
    fn new(view: &View, f: &Focus, options: &XpsmOptions, shift: f64) -> Self {
        let eps_w = f64::from(options.epsilon_w);
        let light_space = light_space(&f.rot, view.eye, shift);
        // One pass over each set: the points in light space, their smallest and
        // largest projections on unit P (step 4) and their largest coordinate.
        let proj = |p: &DVec3| p.x * UNIT_P.x + p.y * UNIT_P.y;
        let mut max_proj = f64::NEG_INFINITY;
        let mut receivers = ReceiverPoints::new();
        let (mut min_receivers, mut receiver_scale) = (f64::INFINITY, f64::MIN_POSITIVE);
        for p in &f.receivers {
            let q = light_space.transform_point3(*p);
            min_receivers = min_receivers.min(proj(&q));
            max_proj = max_proj.max(proj(&q));
            receiver_scale = receiver_scale.max(q.abs().max_element());
            // The same capacity as the body's receivers.
            let _ = receivers.try_push(q);
        }
        let mut casters = ArrayVec::<DVec3, 8>::new();
        let (mut min_casters, mut caster_scale) = (f64::INFINITY, f64::MIN_POSITIVE);
        for p in f.caster_box.corners() {
            let q = light_space.transform_point3(p.as_dvec3());
            min_casters = min_casters.min(proj(&q));
            max_proj = max_proj.max(proj(&q));
            caster_scale = caster_scale.max(q.abs().max_element());
            let _ = casters.try_push(q);
        }
        // Step 5: maximal length of the projection vector (eq. 3).
        let min_focus = min_casters.max(min_receivers);
        let scale = receiver_scale.max(caster_scale);
        let max_length_p = if min_focus < -1e-12 * scale {
            (eps_w - 1.0) / min_focus
        } else {
            f64::INFINITY
        };
        // The f32 matrix computes w in world coordinates: keep its rounding small
        // (see MAX_WARP_RATIO).
        let world_scale = f.caster_scale.max(
            f.caster_box
                .min
                .abs()
                .max(f.caster_box.max.abs())
                .max_element()
                .into(),
        );
        Self {
            light_space,
            receivers,
            casters,
            max_proj,
            max_length_p,
            world_scale,
        }
    }
}

/// Step 1: light space, `T(0, -shift, 0) · rot · T(-eye)` (`rot` the light frame,
/// `eye` the viewer), built as that product computes it, without its products of
/// zeros: the rotation's columns, and the translation `rot · (-eye)` moved by
/// `-shift` along `y` (the same values).
fn light_space(rot: &DMat4, eye: DVec3, shift: f64) -> DMat4 {
    let t = rot.mul_vec4((-eye).extend(1.0));
    DMat4::from_cols(
        rot.x_axis,
        rot.y_axis,
        rot.z_axis,
        DVec4::new(t.x, t.y - shift, t.z, t.w),
    )
}

/// Unit P in light space: the shared light frame has `+Y` along `V_xy`.
const UNIT_P: glam::DVec2 = glam::DVec2::Y;

/// Steps 4-17 for the projection length `length_p` of step 6 in `space`.
fn xpsm_fit(
    space: &XpsmSpace,
    f: &Focus,
    options: &XpsmOptions,
    mut length_p: f64,
) -> Result<XpsmFit, WarpError> {
    let eps_w = f64::from(options.epsilon_w);
    let light_space = space.light_space;
    let (receivers, casters) = (&space.receivers, &space.casters);
    let (max_proj, max_length_p, world_scale) =
        (space.max_proj, space.max_length_p, space.world_scale);
    // Step 7: clip against the back-projection singularity.
    if max_length_p > 0.0 && length_p > max_length_p {
        length_p = max_length_p;
    }
    // Precision guard: keep the w range of the focus region within MAX_WARP_RATIO.
    if max_proj > 0.0 {
        length_p = length_p.min((crate::MAX_WARP_RATIO - 1.0) / max_proj);
    }
    length_p = length_p.min(crate::MAX_WARP_RATIO / world_scale);
    // A footprint too thin for f32 texels gets the widened uniform fit.
    let wide = f.wide;
    length_p *= wide;
    if !(length_p.is_finite() && length_p >= 0.0) {
        length_p = 0.0;
    }
    // Steps 8-10: post-perspective light space (PPLS).
    let ppls = Ppls { length_p };
    // Step 11: transform into PPLS, clipping by w >= epsilonW.
    // The points that set maxLengthP land on w = epsilonW itself: classify with a
    // relative margin so rounding cannot drop them.
    let eps_clip = eps_w * (1.0 - 1e-9);
    // Step 12: boxes.
    let cbox = clipped_bounds(ppls, casters, eps_clip);
    let rbox = clipped_bounds(ppls, receivers, eps_clip);
    let (Some((cxy, cz)), Some((rxy, rz))) = (cbox, rbox) else {
        return Err(WarpError::EmptyFocusRegion);
    };
    // Step 13: focus region = intersection in xy.
    let mut region = Bounds {
        min: cxy.min.max(rxy.min),
        max: cxy.max.min(rxy.max),
    };
    // Boxes that touch (a point or a flat receiver inside a flat caster box) may miss
    // each other by the rounding of f32 input: boxes closer than a relative 1e-4
    // count as touching (the zero-area focus region is then widened).
    let slack = 1e-4 * scale_of(&[cxy.min, cxy.max, rxy.min, rxy.max]);
    for axis in 0..2 {
        if region.min[axis] > region.max[axis] {
            if region.min[axis] - region.max[axis] > slack {
                return Err(WarpError::EmptyFocusRegion);
            }
            let mid = 0.5 * (region.min[axis] + region.max[axis]);
            region.min[axis] = mid;
            region.max[axis] = mid;
        }
    }
    // Step 14: Z range over both boxes (points with w < epsilonW excluded).
    region.min.z = cz.0.min(rz.0);
    region.max.z = cz.1.max(rz.1);
    // Near the light frame's two zeros the region must not depend on how the frame
    // is turned (see `turn_invariant`).
    let ppls_from_light_space = ppls.matrix();
    let region = turn_invariant(region, f, || ppls_from_light_space * light_space);
    // Widen a thin region as the uniform fit does: relative to the focus body's
    // coordinates, where the lookup is evaluated, not to the far corners of the
    // caster box (which would make the miner's-lamp fit coarser than the uniform
    // fit of the same body).
    // (Depth keeps the padding relative to the whole caster box, which its range
    // spans.)
    let by_body = region.padded(f.caster_scale, 1.0 - wide);
    let by_world = region.padded(world_scale, 1.0 - wide);
    let region = Bounds {
        min: by_body.min.truncate().extend(by_world.min.z),
        max: by_body.max.truncate().extend(by_world.max.z),
    };
    let (min, max) = (region.min, region.max);
    let ext = max - min;
    // Steps 15-17 (its product with light space made for the fit kept:
    // `XpsmFit::clip`).
    let clip_from_light_space =
        clip_from_region(min, ext, options.reversed_z) * ppls_from_light_space;
    // Light space is the light frame (`Focus::rot`) moved by its translation: the
    // product with that translation keeps the first three columns.
    let m = &clip_from_light_space;
    let clip_from_light = DMat4::from_cols(
        m.x_axis,
        m.y_axis,
        m.z_axis,
        *m * light_space.w_axis.truncate().extend(1.0),
    );
    // A region beyond what f64 resolves (a caster box 1e30 from the receivers)
    // overflows its scale or offset: refused here, before the prediction reads it.
    if !(clip_from_light_space.is_finite() && clip_from_light.is_finite()) {
        return Err(WarpError::Degenerate);
    }
    Ok(XpsmFit {
        clip_from_light_space,
        clip_from_light,
        world_scale,
        z_extent: ext.z,
        length_p,
        max_length_p,
    })
}

/// Steps 15 and 16, the map from a focus region (its corner `min` and extent `ext`)
/// to clip space: the unit cube (the inverse of the region's basis), then WebGPU's
/// normalized space, `x` and `y` to `[-1, 1]`; the unit cube's `z` grows toward
/// the light, so standard depth is `1 - z` and reversed-Z depth is `z`.
///
/// Both are scales with offsets, so their product is one: each column of a matrix
/// it multiplies maps as `scale * c + offset * c.w`, the values the product of the
/// full matrices computes (its other terms are products with zeros).
#[derive(Clone, Copy)]
struct AxisMap {
    scale: DVec4,
    offset: DVec4,
}

impl core::ops::Mul<DMat4> for AxisMap {
    type Output = DMat4;

    fn mul(self, m: DMat4) -> DMat4 {
        let column = |c: DVec4| self.scale * c + self.offset * c.w;
        DMat4::from_cols(
            column(m.x_axis),
            column(m.y_axis),
            column(m.z_axis),
            column(m.w_axis),
        )
    }
}

/// [`AxisMap`] of the region at `min` of extent `ext`.
fn clip_from_region(min: DVec3, ext: DVec3, reversed_z: bool) -> AxisMap {
    // The unit cube: `(p - min) / ext`, as `p / ext - min / ext`.
    let inv = DVec3::new(1.0 / ext.x, 1.0 / ext.y, 1.0 / ext.z);
    let start = DVec3::new(-min.x / ext.x, -min.y / ext.y, -min.z / ext.z);
    // Then `2 u - 1` across the light and `1 - u` (standard) or `u` (reversed)
    // along it.
    let (z_scale, z_offset) = if reversed_z {
        (inv.z, start.z)
    } else {
        (-inv.z, -start.z + 1.0)
    };
    AxisMap {
        scale: DVec4::new(2.0 * inv.x, 2.0 * inv.y, z_scale, 0.0),
        offset: DVec4::new(2.0 * start.x - 1.0, 2.0 * start.y - 1.0, z_offset, 1.0),
    }
}

/// `lengthP` for the full length `full` over an extent `d` along `unit P`, faded
/// by `weight` in `[0, 1]` as LiSPSM and TSM fade: the warp ratio `1 + lengthP d`
/// is raised to the power `weight` (its logarithm scaled), so the fit goes to the
/// orthographic one as smoothly as the weight. (Scaling `lengthP` itself keeps
/// most of a strong warp until the weight is nearly 0: a warp ratio of 50 at weight
/// 0.075 stays 4.7, not 1.34, and a sweep case with a low sun 6.7° off the view
/// lost 1.29x to the uniform fit on it.)
pub(crate) fn faded_length(full: f64, d: f64, weight: f64) -> f64 {
    if weight >= 1.0 || !(d > 0.0) {
        return full * weight.min(1.0);
    }
    let s = math::exp_m1(weight * math::ln_1p(full * d)) / d;
    if s.is_finite() && s > 0.0 { s } else { 0.0 }
}

/// The automatic `lengthP`, faded by `weight` ([`faded_length`]).
///
/// The paper warps by `w = 1 + coef d` at view distance `d`, `coef = 1 / sqrt(z_n z_f)`
/// over the visible receivers, so the warp ratio across the visible depth range is
/// `1 + coef (z_f - z_n)`; its `lengthP = coef / cos γ` reaches that ratio only when
/// the light-space extent of the visible region along `unit P` is the depth range
/// times `cos γ` (the paper's `γ`, here `sin γ`) and the region starts at the
/// viewer. Neither holds when the light is near the view (a camera looking down, a
/// low sun ahead): the region spreads sideways and reaches behind the viewer, and
/// the paper's length then over-warps it, and the back-projection clip of step 7
/// drives one edge to `epsilonW` (ten times magnified, the rest starved). So the
/// ratio is kept, and placed on the region: `lengthP = coef (z_f - z_n) / D`, `D`
/// the receivers' extent along `unit P`, with the light-space origin moved along
/// `unit P` from the viewer to the near face `y_0` of the focus body (the returned
/// shift `y_0 - y_eye`), so the projection centre lies `1 / lengthP` before the
/// region wherever the viewer is. In the paper's own setting
/// (`D = (z_f - z_n) cos γ`, region starting at the viewer) this is its
/// `coef / cos γ` with its origin. Returns `(lengthP, shift)`.
fn auto_length(f: &Focus, view: &View, weight: f64) -> (f64, f64) {
    if !(weight > 0.0) {
        return (0.0, 0.0);
    }
    let (z_n, z_f) = f.receiver_depth;
    let (r0, r1) = (f.footprint.min.y, f.footprint.max.y);
    let z_scale = z_f.abs().max(z_n.abs()).max(f64::MIN_POSITIVE);
    let z_n = z_n.max(1e-6 * z_scale);
    let z_f = z_f.max(z_n);
    let coef = 1.0 / crate::focus::sqrt0(z_n * z_f);
    let s = faded_length(coef * (z_f - z_n) / (r1 - r0), r1 - r0, weight);
    if !(s.is_finite() && s > 0.0) {
        return (0.0, 0.0);
    }
    let (y0, _) = f.warp_axis_range();
    let y_eye = f.rot.transform_point3(view.eye).y;
    (s, y0 - y_eye)
}

/// Steps 8-10 for the projection length `lengthP`: post-perspective light space
/// (PPLS) from light space, `Projection * ZRotation` of the paper in column-vector
/// form: `X = P.xy`, `Y = P.xy` rotated a quarter turn, `w = 1 + lengthP (P.xy)`.
#[derive(Clone, Copy)]
struct Ppls {
    length_p: f64,
}

impl Ppls {
    /// The matrix, for unit P of any direction.
    ///
    /// The paper's ZRotation (rows (Px, Py), (Py, -Px)) is a reflection, right for
    /// D3D's left-handed frame; here the rotation (Px, Py), (-Py, Px) keeps the
    /// winding. ZRotation maps unit P to `+X` (row 1 of the paper's ZRotation); `w`
    /// is unchanged.
    ///
    /// `rot_z = [(Px, -Py, 0, 0), (Py, Px, 0, 0), Z, W]` (columns) times
    /// `projection = [(1, 0, 0, Px lengthP), (0, 1, 0, Py lengthP), Z, W]`, written
    /// out: each column of the product has one nonzero term per entry.
    fn matrix(self) -> DMat4 {
        let (p, length_p) = (UNIT_P, self.length_p);
        DMat4::from_cols(
            DVec4::new(p.x, -p.y, 0.0, p.x * length_p),
            DVec4::new(p.y, p.x, 0.0, p.y * length_p),
            DVec4::Z,
            DVec4::W,
        )
    }

    /// `matrix() * p.extend(1.0)` for unit P along `+Y` ([`UNIT_P`]):
    /// `(y, -x, z, 1 + lengthP y)`, the product's values (its other terms have a
    /// zero factor) in four operations rather than twenty-eight.
    fn hom(self, p: DVec3) -> Hom {
        DVec4::new(p.y, -p.x, p.z, 1.0 + self.length_p * p.y)
    }
}

/// The xy box and the z range of the PPLS points of a vertex set split by the plane
/// `w = eps_w`: every vertex (those behind, `w < eps_w`, with `w` raised to `eps_w`
/// for the xy box and left out of the z range), plus the crossing of every segment
/// between a vertex in front and one behind (a superset of the clipped hull's
/// vertices). `None` when no vertex has `w >= eps_w`. The points are bounded as they
/// are made, never stored.
fn clipped_bounds<const N: usize>(
    ppls: Ppls,
    points: &ArrayVec<DVec3, N>,
    eps_w: f64,
) -> Option<(Bounds, (f64, f64))> {
    let mut acc = CloudBounds::EMPTY;
    if ppls.length_p == 0.0 {
        // Every `w` is 1, above `eps_w` (below 1): nothing to clip, and the
        // divisions by `w` would return their numerators.
        for p in points {
            let h = ppls.hom(*p);
            acc.xy.add(DVec3::new(h.x, h.y, 0.0));
            acc.z = (acc.z.0.min(h.z), acc.z.1.max(h.z));
        }
        acc.any = !points.is_empty();
        return acc.finish();
    }
    // The points in front of the plane and behind it, each made once.
    let (mut front, mut behind) = (ArrayVec::<Hom, N>::new(), ArrayVec::<Hom, N>::new());
    for p in points {
        let h = ppls.hom(*p);
        acc.add(h, eps_w);
        // As many of either as there are points.
        if h.w < eps_w {
            let _ = behind.try_push(h);
        } else if h.w >= eps_w {
            let _ = front.try_push(h);
        }
    }
    // Nothing behind (the usual case): no pair to visit.
    for a in &front {
        for b in &behind {
            let t = (a.w - eps_w) / (a.w - b.w);
            let mut c = *a + (*b - *a) * t;
            c.w = eps_w;
            acc.add(c, eps_w);
        }
    }
    acc.finish()
}

/// Running bounds of [`clipped_bounds`].
struct CloudBounds {
    xy: Bounds,
    z: (f64, f64),
    any: bool,
}

impl CloudBounds {
    const EMPTY: Self = Self {
        xy: Bounds::EMPTY,
        z: (f64::INFINITY, f64::NEG_INFINITY),
        any: false,
    };

    fn add(&mut self, h: Hom, eps_w: f64) {
        let w = h.w.max(eps_w);
        self.xy.add(DVec3::new(h.x / w, h.y / w, 0.0));
        if h.w >= eps_w {
            self.any = true;
            self.z = (self.z.0.min(h.z / h.w), self.z.1.max(h.z / h.w));
        }
    }

    fn finish(self) -> Option<(Bounds, (f64, f64))> {
        let (xy, (z0, z1)) = (self.xy, self.z);
        (self.any && xy.min.is_finite() && xy.max.is_finite() && z0.is_finite() && z1.is_finite())
            .then_some((xy, (z0, z1)))
    }
}

#[cfg(test)]
mod tests;
