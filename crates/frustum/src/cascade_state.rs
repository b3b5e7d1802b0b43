//! Caller-held state of the stable cascade fit: each cascade's map size and
//! orientation, kept across frames with hysteresis.

use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec3, Vec3};

use crate::min_area::{MAX_HULL, edge_ups, hull_across};
use crate::projection::light_rotation;
use crate::{Aabb, FrustumError, MAX_CASCADES, math};

/// Largest turn of the camera about the world's up axis (`+Y`, radians) that a
/// stable cascade's map absorbs without re-sizing: each time a size is (re)chosen,
/// the map covers the light-space footprint of slice ∩ receivers turned about the
/// light by up to `STABLE_TURN * |l · Y|` either way (`l` the light direction),
/// the part of a turn about `Y` that is a rotation about the light, and no larger
/// than the receivers' box (no view of them has a larger footprint). For the map's
/// side along the light's azimuth this is the growth a turn of the ground by
/// `STABLE_TURN` gives; across it, a turn gives more under a low light (there the
/// ground along the azimuth, foreshortened by `sin e` in the map at elevation `e`,
/// swings across unshortened), and a turn of a few degrees can re-size a map
/// once. Covering that too cost one map 1.13 to 1.27 times the uniform fit in
/// rooms and under low suns. 0.1 rad
/// (about 5.7°) covers a camera that turns a few degrees while it walks; a map
/// that must cover its footprint in every orientation (the bounding sphere of the
/// slice, Zhang et al.'s stable fit) costs up to 1.41 times the tight fit on
/// every axis.
///
/// Why turning needs a margin at all: the box of a footprint of extents `L > S`
/// turned by `a` grows by about `L a` along its short side, which a margin in
/// proportion to each side's own extent would not cover (a 5:1 footprint turned by
/// 4° grows by 35% across).
pub const STABLE_TURN: f64 = 0.1;

/// Margin of a stable cascade's map over its footprint each time its size is
/// (re)chosen: the footprint may grow by this factor (the camera walks, the held
/// depth range's slices move with it) before the size has to change. The map covers
/// the larger of the footprint with this margin and the footprint turned by
/// [`STABLE_TURN`]; the two are not stacked, since a turn's allowance is held on
/// both sides while a camera turns one way, and stacked they cost 1.11 to 1.13
/// times the uniform fit in rooms of the quality report's sweeps (seeds 19, 20 and
/// 22) where the camera paths keep moving by whole texels without. Small, because
/// it is what a stable cascade pays over the tight fit of the same slice where the
/// camera does not turn.
pub const STABLE_HEADROOM: f64 = 1.03;

/// Largest ratio of a new stable cascade's error on the caller's measure (see
/// [`CascadeSet::fit_with_state_ranked`](crate::CascadeSet::fit_with_state_ranked)),
/// its turn allowance (see [`STABLE_TURN`]) included, to the tight box of the same
/// slice in this frame's orientation (the box the tight and uniform fits draw);
/// above it the map is sized with [`STABLE_HEADROOM`] alone where that measures
/// finer, and a turn of the camera re-sizes it once.
///
/// A turn grows a footprint's box across by its length times the angle, so the
/// allowance costs little on a compact footprint and much on a long one: a room
/// seen along its length under a high light (a 5:1 footprint) pays 27% across, and
/// the map with it measured 1.10 times the tight box. Where the stable map's own
/// orientation already beats the view's frame (a top-down view, whose map turned
/// along the footprint measures about 0.85 times the tight box) the allowance is
/// kept however much it costs, so the camera turns without a pop. With the
/// allowance dropped, the headroom (3%), the short-mantissa round-up (at most
/// 1.6%) and a texel of snap slack keep a new map within about 1.06 times the
/// tight box of its slice.
pub const STABLE_MAX_OVER_TIGHT: f64 = 1.08;

/// Largest ratio of a held size to the size it would be (re)chosen at before the
/// map shrinks. Shrinking only gives texels back (a map that is too big still
/// covers), so the band is wider on this side.
pub const STABLE_SHRINK_RATIO: f64 = 1.5;

/// Margin of the depth range a stable cascade set covers (see
/// [`CascadeState::hold_depth_range`]): each time an end of the range is
/// (re)chosen it reaches this factor beyond the receivers' depth bound there, and
/// it is kept while it contains the bound and reaches at most this factor squared
/// beyond it. The depth bounds jump whenever a receiver enters or leaves the view
/// (a tree leaving the bottom of the image moves the near bound by a fifth) and
/// creep as the camera walks (the far bound of a camera gliding over terrain grows
/// by a few percent a frame), and every split moves with them: without a held
/// range each frame would re-size the cascades and move their texels by
/// fractions. The margin extends the first and the last cascade only; the splits
/// between them divide the bounds as they were when the range was chosen.
pub const STABLE_DEPTH_MARGIN: f32 = 1.25;

/// Smallest sine of the angle between a held orientation's up vector and the light
/// for the orientation to be kept (the light has turned by less than 60° since it
/// was chosen); otherwise the map is re-oriented and re-sized.
const HELD_UP_MIN_SIN: f64 = 0.5;

/// The view-depth ranges a stable cascade set holds across frames (see
/// [`CascadeState::hold_depth_range`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeldDepthRange {
    /// The range the splits divide (the depth bounds when each end was chosen).
    pub split: (f32, f32),
    /// The range the cascades cover: the first cascade from `cover.0`, the last
    /// to `cover.1`.
    pub cover: (f32, f32),
}

/// One stable cascade's held map: its extents in light-space units along the
/// frame's x and y (zero when unset) and the world up vector that orients the frame
/// about the light.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct HeldMap {
    side: DVec2,
    up: Vec3,
}

/// What the stable cascade fit remembers from one frame to the next: each cascade's
/// map extents in light-space units and the up vector that orients its light frame,
/// and the cascade count the caller chose.
///
/// The maps are held per cascade count (the fit of `n` cascades reads and writes
/// the `n`-cascade maps only), so that a caller that fits several counts each
/// frame to choose among them keeps every count's maps: a count not chosen this
/// frame is measured next frame with the maps it would be drawn with, and its new
/// maps are sized (and, where ranked, their orientations chosen) once rather than
/// every frame.
///
/// The stable fit ([`CascadeSet::fit_with_state`](crate::CascadeSet::fit_with_state))
/// fits each cascade's box to its slice ∩ receivers, as the tight fit does, but keeps
/// the box's extents and orientation from the previous frame while they still cover
/// the footprint and are at most [`STABLE_SHRINK_RATIO`] times too big. Only then does
/// it choose new ones, in the orientation the caller asks for this frame
/// ([`CascadeOptions::up_hint`](crate::CascadeOptions::up_hint)): the footprint's
/// extents turned by up to [`STABLE_TURN`], or times [`STABLE_HEADROOM`] where that
/// is larger (the headroom alone where the caller's measure finds the map with
/// the allowance more than [`STABLE_MAX_OVER_TIGHT`] times the tight box). While the
/// extents are kept the box is snapped to whole texels of a grid anchored at the
/// held light frame's origin, so the map moves by whole texels and shadow edges do
/// not shimmer. Unlike the bounding sphere of the whole slice (the stateless stable
/// fit of Zhang et al.'s parallel-split shadow maps, made rotation invariant), the
/// held box spends its texels on the visible receivers, and its orientation is the
/// one that fits them when it is chosen rather than one fixed in the world (a
/// footprint at 45° to a world-fixed frame needs a box up to 1.41 times larger):
/// the view's, or one along an edge of the footprint that boxes it in less area,
/// where the caller measures those
/// ([`CascadeSet::fit_with_state_ranked`](crate::CascadeSet::fit_with_state_ranked)).
///
/// The held sizes stay only while the slices stay: split a depth range held by
/// [`CascadeState::hold_depth_range`] (and extend the end cascades with
/// [`CascadeSplits::with_ends`](crate::CascadeSplits::with_ends)), not each frame's
/// depth bounds, which jump when a receiver enters or leaves the view.
///
/// A fresh state (`Default`) holds nothing: the first frame sizes every cascade.
/// Use one state per light and view; a changed light direction or resolution
/// simply re-sizes the cascades that no longer fit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CascadeState {
    /// Held map per cascade of each cascade count (`held[count - 1][index]`).
    held: [[HeldMap; MAX_CASCADES]; MAX_CASCADES],
    /// Cascade count of the previous frame (0: none), for callers that keep the
    /// count with hysteresis.
    count: usize,
    /// Held view-depth ranges: the one the splits divide and the one the cascades
    /// cover (zero: none).
    depth_range: HeldDepthRange,
}

impl CascadeState {
    /// A state that holds nothing (same as `Default`).
    #[must_use]
    pub const fn new() -> Self {
        Self {
            held: [[HeldMap {
                side: DVec2::ZERO,
                up: Vec3::ZERO,
            }; MAX_CASCADES]; MAX_CASCADES],
            count: 0,
            depth_range: HeldDepthRange {
                split: (0.0, 0.0),
                cover: (0.0, 0.0),
            },
        }
    }

    /// The cascade count recorded by [`CascadeState::set_count`] (0: none yet).
    #[must_use]
    pub const fn count(&self) -> usize {
        self.count
    }

    /// Records the cascade count chosen for this frame.
    pub fn set_count(&mut self, count: usize) {
        self.count = count;
    }

    /// The view-depth ranges of the stable cascades, for receivers between view
    /// depths `near` and `far` (the depth bounds) and a camera that sees `limits`
    /// (its near and far planes). Each end is held while the held cover range
    /// contains its bound and reaches at most [`STABLE_DEPTH_MARGIN`]² beyond it;
    /// otherwise it is re-chosen: the split range ends at the bound, the cover
    /// range [`STABLE_DEPTH_MARGIN`] beyond it (within `limits`). Splitting the held
    /// range keeps the splits, and with them the cascades' sizes, still while the
    /// bounds jump or creep from one frame to the next; extend the first and the
    /// last cascade to the cover range ([`CascadeSplits::with_ends`](crate::CascadeSplits::with_ends)).
    ///
    /// Bounds outside `limits`, reversed or not finite are clamped to `limits`
    /// (the camera's own range).
    ///
    /// ```
    /// use shadowmap_frustum::CascadeState;
    /// let mut state = CascadeState::new();
    /// let first = state.hold_depth_range(40.0, 600.0, (1.0, 1000.0));
    /// assert_eq!((first.split, first.cover), ((40.0, 600.0), (32.0, 750.0)));
    /// // The nearest receiver leaves the view, the farthest recedes a little:
    /// // the same ranges.
    /// assert_eq!(state.hold_depth_range(50.0, 700.0, (1.0, 1000.0)), first);
    /// // A receiver nearer than the margin: a new near end only.
    /// let nearer = state.hold_depth_range(20.0, 700.0, (1.0, 1000.0));
    /// assert_eq!((nearer.split, nearer.cover), ((20.0, 600.0), (16.0, 750.0)));
    /// ```
    pub fn hold_depth_range(&mut self, near: f32, far: f32, limits: (f32, f32)) -> HeldDepthRange {
        let clamp = |x: f32| {
            if x.is_finite() {
                x.clamp(limits.0, limits.1)
            } else {
                limits.1
            }
        };
        let (near, far) = (clamp(near), clamp(far));
        let (near, far) = (near.min(far), far.max(near));
        let held = self.depth_range;
        let (cover_near, cover_far) = held.cover;
        let wide = STABLE_DEPTH_MARGIN * STABLE_DEPTH_MARGIN;
        // Each end on its own: a jump at one end moves no end the other one set.
        let valid = limits.0 <= cover_near && cover_near < cover_far && cover_far <= limits.1;
        let range = &mut self.depth_range;
        if !(valid && cover_near <= near && near <= cover_near * wide) {
            range.split.0 = near;
            range.cover.0 = clamp(near / STABLE_DEPTH_MARGIN);
        }
        if !(valid && far <= cover_far && cover_far <= far * wide) {
            range.split.1 = far;
            range.cover.1 = clamp(far * STABLE_DEPTH_MARGIN);
        }
        if range.split.0 >= range.split.1 {
            // A near end re-chosen past a held far end's bound (or the reverse):
            // both from this frame's bounds.
            *range = HeldDepthRange {
                split: (near, far),
                cover: (
                    clamp(near / STABLE_DEPTH_MARGIN),
                    clamp(far * STABLE_DEPTH_MARGIN),
                ),
            };
        }
        *range
    }

    /// Forgets every held size and the count.
    pub fn clear(&mut self) {
        *self = Self::new();
    }

    /// The held map extents of cascade `index` of a set of `count` cascades
    /// (light-space x and y), `None` when unset.
    #[must_use]
    pub fn size(&self, count: usize, index: usize) -> Option<DVec2> {
        self.held
            .get(count.checked_sub(1)?)?
            .get(index)
            .map(|h| h.side)
            .filter(|s| s.min_element() > 0.0)
    }

    /// The held map of cascade `index` of a set of `count` cascades.
    pub(crate) fn slot(&mut self, count: usize, index: usize) -> Option<HeldSlot<'_>> {
        self.held
            .get_mut(count.checked_sub(1)?)?
            .get_mut(index)
            .map(HeldSlot)
    }
}

/// Mutable access to one cascade's held map, for the fit.
pub(crate) struct HeldSlot<'a>(&'a mut HeldMap);

impl HeldSlot<'_> {
    /// The held orientation's up vector, when a size is held and the light
    /// `direction` (unit) has not turned too far from it.
    fn up_for(&self, direction: DVec3) -> Option<Vec3> {
        let h = &*self.0;
        let sin = direction.cross(h.up.as_dvec3()).length();
        (h.side.min_element() > 0.0 && sin > HELD_UP_MIN_SIN).then_some(h.up)
    }
}

/// Mantissa bits kept in a held size (see [`short_mantissa_above`]).
const SIZE_MANTISSA_BITS: u32 = 6;

/// The smallest number at least `x` (positive, finite) with a
/// [`SIZE_MANTISSA_BITS`]-bit mantissa: at most `2^-6` (1.6%) above `x`. With such a
/// size and a power-of-two resolution the texel `size / resolution` has a short
/// mantissa too, so whole-texel offsets `k * texel` stay exact in the `f32` matrices
/// far from the origin and the snapped map does not drift by fractions of a texel
/// (eight bits already drift by `1e-5` texel a frame 130 m from the origin).
fn short_mantissa_above(x: f64) -> f64 {
    let mask = (1u64 << (52 - SIZE_MANTISSA_BITS)) - 1;
    let bits = x.to_bits();
    if bits & mask == 0 {
        x
    } else {
        f64::from_bits((bits | mask) + 1)
    }
}

/// The held extents for a footprint whose extents (snap slack included) are
/// `needed`, and `turned()` when turned by up to the allowance (see [`STABLE_TURN`]):
/// the previous `held` while it covers `needed` and is at most
/// [`STABLE_SHRINK_RATIO`] times the size it would be chosen at, otherwise that
/// size, `max(needed * STABLE_HEADROOM, turned)` rounded up to a short mantissa;
/// and whether `held` was kept. The turned footprint is computed only where the
/// footprint with the headroom does not settle the choice (most frames keep the
/// held size without it).
fn hold_side(
    held: DVec2,
    needed: DVec2,
    turned: impl FnOnce() -> Result<DVec2, FrustumError>,
) -> Result<(DVec2, bool), FrustumError> {
    let least = needed * STABLE_HEADROOM;
    let covers = held.cmpge(needed).all();
    // The size it would be chosen at is at least `least`: a held size within the
    // band over `least` is kept whatever the turned footprint.
    if covers && held.cmple(least * STABLE_SHRINK_RATIO).all() {
        return Ok((held, true));
    }
    let target = turned()?.max(least);
    if covers && held.cmple(target * STABLE_SHRINK_RATIO).all() {
        Ok((held, true))
    } else {
        Ok((
            DVec2::new(
                short_mantissa_above(target.x),
                short_mantissa_above(target.y),
            ),
            false,
        ))
    }
}

/// The light-space footprint of `points` in the frame `light` turned about the
/// light by up to `phi` either way: the largest extents of the turned points,
/// sampled at `0, ±phi / 2, ±phi` (over so small a range the extents change
/// monotonically or peak once).
fn turned_extent(points: &(impl Iterator<Item = DVec3> + Clone), light: &DMat4, phi: f64) -> DVec2 {
    let mut out = DVec2::ZERO;
    for k in -2i32..=2 {
        let t = phi * f64::from(k) / 2.0;
        let (sin, cos) = (math::sin(t), math::cos(t));
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in points.clone() {
            let q = light.transform_point3(p).truncate();
            let r = DVec2::new(q.x * cos - q.y * sin, q.x * sin + q.y * cos);
            lo = lo.min(r);
            hi = hi.max(r);
        }
        out = out.max(hi - lo);
    }
    out
}

/// The light-space bounds (x, y) of `points` in the frame `light`.
fn light_bounds(points: &(impl Iterator<Item = DVec3> + Clone), light: &DMat4) -> (DVec2, DVec2) {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for p in points.clone() {
        let q = light.transform_point3(p).truncate();
        lo = lo.min(q);
        hi = hi.max(q);
    }
    (lo, hi)
}

/// The light-space extents (x, y) of box `b` in the frame `light`.
fn box_extent(b: &Aabb, light: &DMat4) -> DVec2 {
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    // Each light-space axis is a row of the rotation: its extent over the box is the
    // sum over world axes of |row component| times the box's extent.
    let size = hi - lo;
    let row = |i: usize| DVec3::new(light.x_axis[i], light.y_axis[i], light.z_axis[i]);
    DVec2::new(row(0).abs().dot(size), row(1).abs().dot(size))
}

/// The extents the box must cover for `extent` on a map of `res` texels: one
/// texel of slack for the snap (which moves the box by at most half a texel either
/// way), at least an extent `f32` can resolve around the footprint (`scale` its
/// largest coordinate).
fn with_slack(extent: DVec2, scale: f64, res: f64) -> Result<DVec2, FrustumError> {
    // A footprint seen edge-on still gets a box f32 can resolve around it.
    let needed = (extent * (res / (res - 1.0))).max(DVec2::splat(1e-5 * scale));
    if needed.min_element() > 0.0 && needed.is_finite() {
        Ok(needed)
    } else {
        Err(FrustumError::EmptyBounds)
    }
}

/// The caller's error of a candidate box (lower is finer; not finite: not
/// measured), see [`CascadeMeasure`](crate::CascadeMeasure).
pub(crate) type MeasureBox<'a> = &'a dyn Fn(&HeldBox) -> f64;

/// A stable cascade's box, chosen by [`held_box`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct HeldBox {
    /// The light frame (rotation) the box lies in.
    pub(crate) light_from_world: DMat4,
    /// The box's light-space corners.
    pub(crate) lo: DVec2,
    pub(crate) hi: DVec2,
    /// Its larger texel side.
    pub(crate) texel: f64,
}

/// The stable box of one cascade over the world-space footprint `points` (the
/// vertices of slice ∩ `receivers`) for a light travelling along `direction`
/// (unit): in the held frame with the held extents while they still cover and are
/// not too big (see [`hold_side`]), otherwise in `frame` (this frame's orientation)
/// with new extents, written back to `held`. The centre is snapped to whole texels
/// of the frame's grid.
///
/// The turned footprint (see [`STABLE_TURN`]) is capped by the receivers' box: no
/// turn or walk of the camera gives a footprint larger than the box's own, so a
/// slice that sees most of a room pays no turn allowance beyond the room.
///
/// With the caller's `measure`, a new box is chosen among this frame's
/// orientation and its rivals (the least error, the first on ties), and its turn
/// allowance is kept only where the box measures within [`STABLE_MAX_OVER_TIGHT`]
/// of the tight box in this frame's orientation (see there).
pub(crate) fn held_box(
    points: &(impl Iterator<Item = DVec3> + Clone),
    receivers: &Aabb,
    direction: DVec3,
    frame: &DMat4,
    res: f64,
    held: &mut HeldSlot<'_>,
    measure: Option<MeasureBox<'_>>,
) -> Result<HeldBox, FrustumError> {
    let fit = Fit {
        receivers,
        res,
        phi: STABLE_TURN * direction.y.abs(),
    };
    if let Some(up) = held.up_for(direction) {
        let light = light_rotation(direction, up);
        let (b, _, kept) = fit.boxed(points, light, held.0.side, true)?;
        if kept {
            return Ok(b);
        }
    }
    // This frame's orientation, by its y axis (the rotation's second row), stored in
    // f32 and the frame rebuilt from it, so that the frames that keep it rebuild
    // exactly the same rotation.
    let own = DVec3::new(frame.x_axis.y, frame.y_axis.y, frame.z_axis.y).as_vec3();
    let (b, map) = match measure {
        Some(measure) => fit.measured(points, direction, own, measure)?,
        None => fit.new_box(points, direction, own, true)?,
    };
    *held.0 = map;
    Ok(b)
}

/// Most orientations besides the frame's own that a new stable box is chosen among.
const RIVALS: usize = 3;

/// Most orientations a new stable cascade's map is chosen among on the caller's
/// measure (see [`CascadeSet::fit_with_state_ranked`](crate::CascadeSet::fit_with_state_ranked)):
/// this frame's orientation and its rivals. The measure is asked at most twice
/// more: for the tight box in this frame's orientation and for the chosen
/// orientation without its turn allowance.
pub const MAX_HELD_CANDIDATES: usize = 1 + RIVALS;

/// The orientations along edges of the footprint's hull across the light
/// ([`min_area`](crate::min_area)) that box it, turn allowance included, in less
/// area than `own` (whose box has extents `own_side`): the [`RIVALS`] of least
/// area, one per area (a rectangle's edges give each box twice, a quarter turn
/// apart, the same texels).
fn rivals(
    points: &(impl Iterator<Item = DVec3> + Clone),
    direction: DVec3,
    own: Vec3,
    own_side: DVec2,
    fit: &Fit<'_>,
) -> Result<ArrayVec<Vec3, RIVALS>, FrustumError> {
    let own_frame = light_rotation(direction, own);
    let hull = hull_across(points.clone(), &own_frame);
    let corners = hull.iter().map(|(_, p)| *p);
    let own_area = own_side.x * own_side.y;
    let mut smaller: ArrayVec<(f64, Vec3), MAX_HULL> = ArrayVec::new();
    for up in edge_ups(&hull, &own_frame) {
        let (_, side, _) = fit.boxed(&corners, light_rotation(direction, up), DVec2::ZERO, true)?;
        let area = side.x * side.y;
        let new = smaller.iter().all(|(a, _)| (area - a).abs() > 1e-9 * area);
        if area < own_area * (1.0 - 1e-6) && new {
            smaller.push((area, up));
        }
    }
    smaller.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    Ok(smaller.iter().take(RIVALS).map(|(_, up)| *up).collect())
}

/// What a stable box is fitted against: the receivers' box, the resolution and
/// the turn allowance's angle about the light.
struct Fit<'a> {
    receivers: &'a Aabb,
    res: f64,
    phi: f64,
}

impl Fit<'_> {
    /// A new box over `points` in the frame oriented by `up` about the light
    /// `direction`, with the turn allowance or (not `turn`) without, and the map
    /// it holds.
    fn new_box(
        &self,
        points: &(impl Iterator<Item = DVec3> + Clone),
        direction: DVec3,
        up: Vec3,
        turn: bool,
    ) -> Result<(HeldBox, HeldMap), FrustumError> {
        let light = light_rotation(direction, up);
        let (b, side, _) = self.boxed(points, light, DVec2::ZERO, turn)?;
        Ok((b, HeldMap { side, up }))
    }

    /// The new box of least error on `measure` among this frame's orientation
    /// `own` (first on ties) and its rivals, without its turn allowance where the
    /// box with it measures more than [`STABLE_MAX_OVER_TIGHT`] times the tight
    /// box in `own` and without measures finer. Not finite errors never win, and
    /// keep the allowance. Measures only what decides: nothing for a lone
    /// orientation whose sides are within the bound of the tight box's.
    fn measured(
        &self,
        points: &(impl Iterator<Item = DVec3> + Clone),
        direction: DVec3,
        own: Vec3,
        measure: MeasureBox<'_>,
    ) -> Result<(HeldBox, HeldMap), FrustumError> {
        let mut best = self.new_box(points, direction, own, true)?;
        let mut best_error = None;
        for up in rivals(points, direction, own, best.1.side, self)? {
            let least = *best_error.get_or_insert_with(|| measure(&best.0));
            let candidate = self.new_box(points, direction, up, true)?;
            let error = measure(&candidate.0);
            if error < least * (1.0 - 1e-9) || (!least.is_finite() && error.is_finite()) {
                (best, best_error) = (candidate, Some(error));
            }
        }
        let unturned = self.new_box(points, direction, best.1.up, false)?;
        if unturned.1.side == best.1.side {
            return Ok(best);
        }
        let tight = self.tight(points, light_rotation(direction, own));
        // In the same frame an orthographic map's error grows at most as its
        // texels' sides: within the bound on both, it is within it on the measure.
        let within = best.1.up == own
            && best
                .1
                .side
                .cmple((tight.hi - tight.lo) * STABLE_MAX_OVER_TIGHT)
                .all();
        if within {
            return Ok(best);
        }
        let best_error = best_error.unwrap_or_else(|| measure(&best.0));
        let tight = measure(&tight);
        let over = best_error.is_finite() && tight.is_finite();
        if over && best_error > STABLE_MAX_OVER_TIGHT * tight && measure(&unturned.0) < best_error {
            return Ok(unturned);
        }
        Ok(best)
    }

    /// The tight box over `points` in the frame `light`: their bounds, no margin,
    /// no snap.
    fn tight(&self, points: &(impl Iterator<Item = DVec3> + Clone), light: DMat4) -> HeldBox {
        let (lo, hi) = light_bounds(points, &light);
        HeldBox {
            light_from_world: light,
            lo,
            hi,
            texel: (hi - lo).max_element() / self.res,
        }
    }

    /// The box over `points` in the frame `light` with the extents [`hold_side`]
    /// keeps or chooses from `held` (zero: none), with the turn allowance or (not
    /// `turn`) the headroom alone, its extents and whether `held` was kept; the
    /// centre snapped to whole texels.
    fn boxed(
        &self,
        points: &(impl Iterator<Item = DVec3> + Clone),
        light: DMat4,
        held: DVec2,
        turn: bool,
    ) -> Result<(HeldBox, DVec2, bool), FrustumError> {
        let (lo, hi) = light_bounds(points, &light);
        let scale = lo.abs().max(hi.abs()).max_element();
        let needed = with_slack(hi - lo, scale, self.res)?;
        let turned = || {
            if !turn {
                return Ok(needed);
            }
            let turned =
                turned_extent(points, &light, self.phi).min(box_extent(self.receivers, &light));
            with_slack(turned, scale, self.res)
        };
        let (side, kept) = hold_side(held, needed, turned)?;
        let texel = side / self.res;
        let center = ((lo + hi) * 0.5 / texel).round() * texel;
        let b = HeldBox {
            light_from_world: light,
            lo: center - side * 0.5,
            hi: center + side * 0.5,
            texel: texel.max_element(),
        };
        Ok((b, side, kept))
    }
}

#[cfg(test)]
mod tests;
