//! How far the `f32` rounding of a spot map's matrices moves its lookups near the
//! light, which the spot fit ([`fit_spot`](crate::fit_spot)) and the warps of its
//! post-projective space keep within [`SPOT_ROUNDING_BUDGET`].

use glam::{DMat4, DVec4, Vec3};

use crate::mapping::{ShadowTransform, UV_FROM_CLIP};
use crate::math;

/// The most `f32` rounding may move a lookup of a spot map at a visible receiver
/// (its texture coordinates, the two ends of a light ray apart, or its depth): a
/// tenth of a texel of a `1024²` map.
///
/// A perspective map divides what its rounded `x`, `y` and `w` rows leave at the
/// light's position, where they vanish in exact arithmetic, by the distance from
/// the light: the window of a receiver seen edge-on 3 mm from a light 0.05 from
/// the origin, 44 `f32` steps tall there, put the two ends of one ray 0.4 texels
/// apart.
pub const SPOT_ROUNDING_BUDGET: f64 = 0.1 / 1024.0;

/// How many `f32` steps of the light's coordinates the matrices may add to a lookup
/// at `w`, over `w`, besides [`SPOT_ROUNDING_BUDGET`]: what a point's own `f32`
/// coordinates already carry.
const F32_STEPS: f64 = 4.0;

/// How far the rounding of a spot map's `f32` matrices moves a lookup at the
/// visible receivers: its texture coordinates, the two ends of a light ray apart,
/// and its depth.
///
/// A stored row `r` (of `clip_from_world`, the depth pass's, or `uv_from_world`,
/// the lookup's, its rows summed in `f32`) errs at a point `p` by its value at the
/// light's position plus its rounding times `p - light`; a point at `w` carries
/// that as a move of `r / w` by about `(|r(light)| + |w(light)|) / w` plus
/// `(|δr|₁ + |δw|₁) |p - light| / w` (`δ` the rounding, `|r / w| ≤ 1`). In exact
/// arithmetic the `x`, `y` and `w` rows (so `u w` and `v w`) vanish at the light:
/// every light ray is one line through it, and what the stored rows leave there,
/// divided by the small `w` of a point near the light, is what separates the two
/// ends of a ray. Depth (`z / w`, with `z` nearly `w` where a warp compresses it
/// toward the far value) reads the rounding alone. Inside the map `w` is at least
/// the distance `d ≥ nearest` along the spot's axis (a warp of the map divides by
/// `q ≥ 1` more), and `|p - light| ≤ spread d`.
///
/// ```
/// use glam::{DMat4, DVec4, Vec3};
/// use shadowmap_frustum::{LightDirection, SPOT_ROUNDING_BUDGET, ShadowTransform, SpotRounding};
///
/// // A spot 3,000 from the origin looking down -z, a window a thousandth wide.
/// let light = Vec3::new(3000.1, 10.3, 0.0);
/// let tangents = [-1e-3, 1e-3, -1e-3, 1e-3];
/// let light_from_world = DMat4::from_translation(-light.as_dvec3());
/// // x and y over a thousandth of the distance `w = -z` fill the map.
/// let clip_from_light = DMat4::from_cols(
///     DVec4::new(1000.0, 0.0, 0.0, 0.0),
///     DVec4::new(0.0, 1000.0, 0.0, 0.0),
///     DVec4::new(0.0, 0.0, -3.0, -1.0),
///     DVec4::new(0.0, 0.0, -4.0, 0.0),
/// );
/// let clip = clip_from_light * light_from_world;
/// let map = ShadowTransform::new(
///     light_from_world.as_mat4(),
///     clip.as_mat4(),
///     false,
///     LightDirection::Position(light),
/// );
/// // Receivers 2 from the light: the rows' rounding at the light, over 2, is
/// // far more than a tenth of a texel.
/// let rounding = SpotRounding::new(light, tangents, 2.0);
/// assert!(rounding.texel(&clip, &map) > SPOT_ROUNDING_BUDGET);
/// ```
#[derive(Clone, Copy, Debug)]
pub struct SpotRounding {
    /// The light's position, `(light, 1)`.
    light: DVec4,
    /// The nearest receivers' distance along the spot's axis.
    nearest: f64,
    /// The largest distance from the light per unit along its axis in the window.
    spread: f64,
    /// What a point's own `f32` coordinates already carry at `w`, times `w`
    /// ([`F32_STEPS`] steps of the light's largest coordinate, over `spread`: the
    /// point's distance from the light is up to `spread w`): allowed besides the
    /// budget, so a region reaching the light's plane, whose points come
    /// arbitrarily near it, keeps its map.
    slack: f64,
}

impl SpotRounding {
    /// The rounding of a spot light at `light` whose window has the tangents
    /// `[left, right, bottom, top]`, looked up no nearer than `nearest` along its
    /// axis.
    #[inline]
    #[must_use]
    pub fn new(light: Vec3, tangents: [f64; 4], nearest: f64) -> Self {
        let [l, r, b, t] = tangents;
        let tan_x = l.abs().max(r.abs());
        let tan_y = b.abs().max(t.abs());
        let spread = math::sqrt(1.0 + tan_x * tan_x + tan_y * tan_y);
        Self {
            light: light.as_dvec3().extend(1.0),
            nearest,
            spread,
            slack: F32_STEPS * f64::from(f32::EPSILON) * f64::from(light.abs().max_element())
                / spread,
        }
    }

    /// The bound of the texture coordinates' move, and of the two ends of a light
    /// ray apart, for `map`, stored from the exact clip matrix `clip`.
    #[inline]
    #[must_use]
    pub fn texel(&self, clip: &DMat4, map: &ShadowTransform) -> f64 {
        let stored_clip = map.clip_from_world.as_dmat4();
        let stored_uv = map.uv_from_world.as_dmat4();
        let uv = UV_FROM_CLIP.as_dmat4() * *clip;
        // Device coordinates span 2 across the map, texture coordinates 1.
        let row = |row: usize| {
            self.moved(&stored_uv, &uv, row, false)
                .max(0.5 * self.moved(&stored_clip, clip, row, false))
        };
        row(0).max(row(1))
    }

    /// [`SpotRounding::texel`] and the depth's move: the bound a map's lookups are
    /// held to (`≤` [`SPOT_ROUNDING_BUDGET`]).
    #[inline]
    #[must_use]
    pub fn bound(&self, clip: &DMat4, map: &ShadowTransform) -> f64 {
        let depth = self.moved(&map.clip_from_world.as_dmat4(), clip, 2, true);
        self.texel(clip, map).max(depth)
    }

    /// How far the rounding of `stored` (from `exact`) moves its row `row` over `w`
    /// at a receiver; at the light, the stored rows' values, or with
    /// `rounding_only` their rounding's.
    #[inline]
    fn moved(&self, stored: &DMat4, exact: &DMat4, row: usize, rounding_only: bool) -> f64 {
        let rounding = |r: usize| stored.row(r) - exact.row(r);
        let at_light = |r: usize| {
            let value = if rounding_only {
                rounding(r)
            } else {
                stored.row(r)
            };
            value.dot(self.light).abs()
        };
        let per_unit = |r: usize| rounding(r).truncate().abs().element_sum();
        let at_light = (at_light(row) + at_light(3) - self.slack).max(0.0);
        at_light / self.nearest + (per_unit(row) + per_unit(3)) * self.spread
    }
}
