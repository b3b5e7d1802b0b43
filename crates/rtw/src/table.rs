//! Forward and inverse warp of one axis, with exactly the sampling semantics of a
//! linear, clamp-to-edge texture lookup (see the crate docs, "Sampling semantics").

/// The warp offset `S(u)` of a table, as a linearly filtered, clamp-to-edge texture
/// of `N = table.len()` texels returns it, computed in `f32` the way the reference
/// WGSL does:
///
/// ```text
/// x = u * N - 0.5
/// x <= 0      -> T[0]
/// x >= N - 1  -> T[N-1]
/// otherwise   -> i = floor(x), f = x - i, T[i] + f * (T[i+1] - T[i])
/// ```
///
/// An empty table reads as 0. A NaN `u` reads as `T[0]`.
#[must_use]
pub fn sample_table(table: &[f32], u: f32) -> f32 {
    let Some((&first, _)) = table.split_first() else {
        return 0.0;
    };
    let n = table.len() as f32;
    let x = u * n - 0.5;
    if x.is_nan() || x <= 0.0 {
        return first;
    }
    let last_x = n - 1.0;
    if x >= last_x {
        return table[table.len() - 1];
    }
    let i = x as usize; // floor: x > 0
    let f = x - i as f32;
    match (table.get(i), table.get(i + 1)) {
        (Some(&a), Some(&b)) => a + f * (b - a),
        _ => table[table.len() - 1],
    }
}

/// The same piecewise-linear function as [`sample_table`], evaluated in `f64` (for
/// accurate derivatives in the evaluation harness).
#[must_use]
pub fn sample_table_f64(table: &[f32], u: f64) -> f64 {
    let Some((&first, _)) = table.split_first() else {
        return 0.0;
    };
    let n = table.len() as f64;
    let x = u * n - 0.5;
    if x.is_nan() || x <= 0.0 {
        return f64::from(first);
    }
    if x >= n - 1.0 {
        return f64::from(table[table.len() - 1]);
    }
    let i = x as usize;
    let f = x - i as f64;
    match (table.get(i), table.get(i + 1)) {
        (Some(&a), Some(&b)) => {
            let (a, b) = (f64::from(a), f64::from(b));
            a + f * (b - a)
        }
        _ => f64::from(table[table.len() - 1]),
    }
}

/// Warped coordinate `u' = u + S(u)` in `f32`, exactly as the shader computes it.
///
/// For a table built by this crate, `u'` is monotone in `u` and maps `[0, 1]` onto
/// `[0, 1]`; outside `[0, 1]` (and in the outer half texels) it is the identity.
/// A NaN `u` gives `0`; `±inf` gives `±inf`.
#[must_use]
pub fn forward_warp(table: &[f32], u: f32) -> f32 {
    if u.is_nan() {
        return 0.0;
    }
    u + sample_table(table, u)
}

/// [`forward_warp`] evaluated in `f64` (the same piecewise-linear function).
#[must_use]
pub fn forward_warp_f64(table: &[f32], u: f64) -> f64 {
    if u.is_nan() {
        return 0.0;
    }
    u + sample_table_f64(table, u)
}

/// The knot `i` of the piecewise-linear forward warp: the texel centre
/// `c_i = (i + 0.5) / N` and its image `c_i + T[i]`, in `f64`.
#[inline]
fn knot(table: &[f32], i: usize) -> (f64, f64) {
    let c = (i as f64 + 0.5) / table.len() as f64;
    (c, c + f64::from(table[i]))
}

/// Inverse of [`forward_warp_f64`]: the base coordinate `u` with `u + S(u) = w`.
///
/// The forward warp is piecewise linear with knots at the texel centres, so the
/// inverse is exact up to rounding: binary search for the segment, then one linear
/// interpolation. Where the forward warp is flat (only possible at rounding level) the
/// smallest preimage is returned. Outside the knots the forward warp is
/// `u + T[0]` (left) or `u + T[N-1]` (right), which is inverted as such. A NaN `w`
/// gives `0`.
#[must_use]
pub fn inverse_warp_f64(table: &[f32], w: f64) -> f64 {
    if w.is_nan() {
        return 0.0;
    }
    let n = table.len();
    if n == 0 {
        return w;
    }
    let (c0, k0) = knot(table, 0);
    if w <= k0 {
        return w - f64::from(table[0]);
    }
    let (cn, kn) = knot(table, n - 1);
    if w >= kn {
        return w - f64::from(table[n - 1]);
    }
    // Invariant: knot(lo) < w < knot(hi).
    let (mut lo, mut hi) = (0usize, n - 1);
    let (mut c_lo, mut k_lo, mut c_hi, mut k_hi) = (c0, k0, cn, kn);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        let (c, k) = knot(table, mid);
        if k < w {
            (lo, c_lo, k_lo) = (mid, c, k);
        } else {
            (hi, c_hi, k_hi) = (mid, c, k);
        }
    }
    let dk = k_hi - k_lo;
    if dk > 0.0 {
        let t = ((w - k_lo) / dk).clamp(0.0, 1.0);
        c_lo + t * (c_hi - c_lo)
    } else {
        c_lo
    }
}

/// [`inverse_warp_f64`] with `f32` input and output.
#[must_use]
pub fn inverse_warp(table: &[f32], w: f32) -> f32 {
    inverse_warp_f64(table, f64::from(w)) as f32
}

/// The slope `d u' / d u` of the forward warp of a table at `u`: constant between
/// texel centres, 1 outside them (where the warp is a translation).
pub(crate) fn warp_slope(table: &[f32], u: f64) -> f64 {
    let n = table.len() as f64;
    let x = u * n - 0.5;
    if !(x > 0.0 && x < n - 1.0) {
        return 1.0;
    }
    let i = x as usize;
    match (table.get(i), table.get(i + 1)) {
        (Some(a), Some(b)) => 1.0 + (f64::from(*b) - f64::from(*a)) * n,
        _ => 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_clamps_and_interpolates() {
        let t = [0.0, 0.25, 0.0, 0.0];
        // Centres at 0.125, 0.375, 0.625, 0.875.
        assert_eq!(sample_table(&t, 0.0), 0.0);
        assert_eq!(sample_table(&t, 0.375), 0.25);
        assert!((sample_table(&t, 0.25) - 0.125).abs() < 1e-7);
        assert_eq!(sample_table(&t, 1.0), 0.0);
        assert_eq!(sample_table(&[], 0.3), 0.0);
        assert_eq!(sample_table(&[0.5], 0.3), 0.5);
        assert_eq!(forward_warp(&t, f32::NAN), 0.0);
        assert!((sample_table_f64(&t, 0.25) - 0.125).abs() < 1e-12);
    }

    #[test]
    fn inverse_inverts() {
        let t = [0.0, 0.1, 0.05, 0.0];
        for k in 0..=100 {
            let u = f64::from(k) / 100.0;
            let w = forward_warp_f64(&t, u);
            assert!((inverse_warp_f64(&t, w) - u).abs() < 1e-12, "u = {u}");
        }
        assert_eq!(inverse_warp_f64(&t, f64::NAN), 0.0);
        assert_eq!(inverse_warp(&[], 0.25), 0.25);
    }
}
