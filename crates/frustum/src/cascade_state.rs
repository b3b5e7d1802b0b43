//! Caller-held state of the stable cascade fit: each cascade's map size, kept across
//! frames with hysteresis.

use glam::DVec2;

use crate::{FrustumError, MAX_CASCADES};

/// Margin of a stable cascade's map over the light-space footprint it must cover,
/// each time its size is (re)chosen: the footprint may grow by this factor as the
/// camera moves or turns before the size has to change.
pub const STABLE_HEADROOM: f64 = 1.25;

/// Largest ratio of a held size to the footprint it covers before the map shrinks.
/// Shrinking only gives texels back (a map that is too big still covers), so the
/// band is wider on this side: after a resize the footprint may shrink to
/// `STABLE_HEADROOM / STABLE_SHRINK_RATIO` (about 0.71) of its size, as it may grow
/// by [`STABLE_HEADROOM`], before the size changes again.
pub const STABLE_SHRINK_RATIO: f64 = 1.75;

/// What the stable cascade fit remembers from one frame to the next: each cascade's
/// map size in light-space units (per axis), and the cascade count the caller chose.
///
/// The stable fit ([`CascadeSet::fit_with_state`](crate::CascadeSet::fit_with_state))
/// fits each cascade's box to its slice ∩ receivers, as the tight fit does, but keeps
/// the box's size from the previous frame while it still covers the footprint and is
/// at most [`STABLE_SHRINK_RATIO`] times too big. Only then does it choose a new size,
/// [`STABLE_HEADROOM`] times the footprint. While the size is kept the box is
/// snapped to whole texels of a grid anchored at the light frame's origin, so
/// the map moves by whole texels and shadow edges do not shimmer; unlike the bounding
/// sphere of the whole slice (the stateless stable fit of Zhang et al.'s parallel-split
/// shadow maps, made rotation invariant), the held box spends its texels on the
/// visible receivers.
///
/// A fresh state (`Default`) holds no size: the first frame sizes every cascade.
/// Use one state per light and view; a changed light direction or resolution
/// simply re-sizes the cascades that no longer fit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CascadeState {
    /// Held map size per cascade (light-space x and y extent); zero when unset.
    sizes: [DVec2; MAX_CASCADES],
    /// Cascade count of the previous frame (0: none), for callers that keep the
    /// count with hysteresis.
    count: usize,
}

impl CascadeState {
    /// A state that holds nothing (same as `Default`).
    #[must_use]
    pub const fn new() -> Self {
        Self {
            sizes: [DVec2::ZERO; MAX_CASCADES],
            count: 0,
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

    /// Forgets every held size and the count.
    pub fn clear(&mut self) {
        *self = Self::new();
    }

    /// The held size of cascade `index` (light-space x and y), `None` when unset.
    #[must_use]
    pub fn size(&self, index: usize) -> Option<DVec2> {
        self.sizes
            .get(index)
            .copied()
            .filter(|s| s.x > 0.0 && s.y > 0.0)
    }

    pub(crate) fn slot(&mut self, index: usize) -> Option<&mut DVec2> {
        self.sizes.get_mut(index)
    }
}

/// Mantissa bits kept in a held size (see [`short_mantissa_above`]).
const SIZE_MANTISSA_BITS: u32 = 6;

/// The smallest number at least `x` (positive, finite) with a
/// [`SIZE_MANTISSA_BITS`]-bit mantissa: at most `2^-6` (1.6%) above `x`. With such a
/// size and a power-of-two resolution the texel `size / resolution` has a short
/// mantissa too, so whole-texel offsets `k * texel` stay exact in the `f32` matrices
/// far from the origin and the snapped map does not drift by fractions of a texel.
fn short_mantissa_above(x: f64) -> f64 {
    let mask = (1u64 << (52 - SIZE_MANTISSA_BITS)) - 1;
    let bits = x.to_bits();
    if bits & mask == 0 {
        x
    } else {
        f64::from_bits((bits | mask) + 1)
    }
}

/// The held size for a footprint of extent `needed` (per axis): the previous size
/// `held` while it covers `needed` and is at most [`STABLE_SHRINK_RATIO`] times
/// larger, otherwise `needed * STABLE_HEADROOM` (rounded up to a short mantissa).
/// Each axis on its own.
pub(crate) fn hold_size(held: DVec2, needed: DVec2) -> DVec2 {
    let axis = |h: f64, n: f64| {
        if h >= n && h <= n * STABLE_SHRINK_RATIO {
            h
        } else {
            short_mantissa_above(n * STABLE_HEADROOM)
        }
    };
    DVec2::new(axis(held.x, needed.x), axis(held.y, needed.y))
}

/// The stable box over the light-space footprint `[lo, hi]` with a held size:
/// the needed extent per axis is the footprint's plus one texel of slack on each
/// side for the snap; the size is kept or renewed by [`hold_size`] (and written back
/// to `held`), and the centre is snapped to whole texels per axis.
/// Returns the box and its larger texel side.
pub(crate) fn held_box(
    lo: DVec2,
    hi: DVec2,
    res: f64,
    held: &mut DVec2,
) -> Result<(DVec2, DVec2, f64), FrustumError> {
    let scale = lo.abs().max(hi.abs()).max_element();
    // A footprint seen edge-on still gets a box f32 can resolve around it.
    let needed = ((hi - lo) * (res / (res - 2.0))).max(DVec2::splat(1e-5 * scale));
    if !(needed.min_element() > 0.0 && needed.is_finite()) {
        return Err(FrustumError::EmptyBounds);
    }
    let side = hold_size(*held, needed);
    *held = side;
    let texel = side / res;
    let center = (lo + hi) * 0.5;
    let snapped = (center / texel).round() * texel;
    let half = texel * (0.5 * res);
    Ok((snapped - half, snapped + half, texel.max_element()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn size_is_kept_inside_the_band_and_renewed_outside() {
        let n = DVec2::new(10.0, 4.0);
        let first = hold_size(DVec2::ZERO, n);
        assert!(first.cmpge(n * STABLE_HEADROOM).all());
        assert!(first.cmple(n * (STABLE_HEADROOM * 1.016)).all());
        // Grows by 10%: still covered, kept.
        assert_eq!(hold_size(first, n * 1.1), first);
        // Grows past the headroom: renewed.
        let renewed = hold_size(first, n * 1.3);
        assert!(renewed.cmpge(n * 1.3 * STABLE_HEADROOM).all());
        // Shrinks to 80%: at most 1.75x too big, kept; to half: renewed.
        assert_eq!(hold_size(first, n * 0.9), first);
        assert!(hold_size(first, n * 0.5).cmplt(first).all());
        // Axes are independent.
        let mixed = hold_size(first, DVec2::new(10.0, 8.0));
        assert_eq!(mixed.x, first.x);
        assert!(mixed.y >= 8.0 * STABLE_HEADROOM);
    }

    #[test]
    fn short_mantissa_rounds_up_by_at_most_two_percent() {
        for x in [1e-3, 0.37, 1.0, 3.3, 1234.5678, 9.9e6] {
            let r = short_mantissa_above(x);
            assert!(r >= x && r <= x * (1.0 + 1.0 / 64.0), "{x} -> {r}");
            // Six mantissa bits: times 64 over its power of two is an integer.
            let scaled = r / 2f64.powi(r.log2().floor() as i32) * 64.0;
            assert_eq!(scaled, scaled.round(), "{r}");
        }
    }

    #[test]
    fn held_box_moves_by_whole_texels_and_covers_the_footprint() {
        let res = 512.0;
        let mut held = DVec2::ZERO;
        let (lo, hi) = (DVec2::new(-3.2, 7.1), DVec2::new(40.3, 19.9));
        let (a, b, _) = held_box(lo, hi, res, &mut held).unwrap();
        assert!(a.cmple(lo).all() && b.cmpge(hi).all());
        let shift = DVec2::new(1.37, -0.61);
        let (a2, b2, _) = held_box(lo + shift, hi + shift, res, &mut held).unwrap();
        assert!(a2.cmple(lo + shift).all() && b2.cmpge(hi + shift).all());
        assert_eq!(b2 - a2, b - a);
        let texel = (b - a) / res;
        let moved = (a2 - a) / texel;
        assert!(
            (moved - moved.round()).abs().max_element() < 1e-9,
            "{moved}"
        );
    }
}
