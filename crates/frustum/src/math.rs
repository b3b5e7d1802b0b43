//! Scalar `f64` math that works with `std` and in `no_std` builds (through `libm`).
//!
//! The sibling crates use these so that every crate builds with
//! `--no-default-features --features libm`.

#[cfg(all(not(feature = "std"), not(feature = "libm")))]
compile_error!("shadowmap-frustum needs the `std` or the `libm` feature for float math");

macro_rules! unary {
    ($($(#[$doc:meta])* $name:ident => $libm:ident;)*) => {$(
        $(#[$doc])*
        #[inline]
        #[must_use]
        pub fn $name(x: f64) -> f64 {
            #[cfg(feature = "std")]
            {
                x.$name()
            }
            #[cfg(not(feature = "std"))]
            {
                libm::$libm(x)
            }
        }
    )*};
}

unary! {
    /// Square root.
    sqrt => sqrt;
    /// Sine (radians).
    sin => sin;
    /// Cosine (radians).
    cos => cos;
    /// Tangent (radians).
    tan => tan;
    /// Arc sine, in radians.
    asin => asin;
    /// Arc cosine, in radians.
    acos => acos;
    /// Arc tangent, in radians.
    atan => atan;
    /// Natural logarithm.
    ln => log;
    /// `e^x`.
    exp => exp;
    /// `ln(1 + x)`, accurate for small `x`.
    ln_1p => log1p;
    /// `e^x - 1`, accurate for small `x`.
    exp_m1 => expm1;
    /// Largest integer not above `x`.
    floor => floor;
    /// Smallest integer not below `x`.
    ceil => ceil;
}

/// Nearest integer, halves away from zero: `f64::round`, inline (on x86-64 without
/// SSE4.1 `f64::round` is a library call) and without branches. Exact: below `2^52`,
/// `|x| + 2^52` lies where the doubles are the integers, so the sum rounds `|x|` to
/// the nearest integer `t` (halves to even) and subtracting `2^52` is exact; a half
/// rounded down (`|x| - t == 0.5`, exact) goes up instead. The sign of `x` is kept
/// (`round(-0.3) == -0.0`); larger magnitudes, infinities and NaN are returned as
/// they are.
#[inline]
#[must_use]
pub fn round(x: f64) -> f64 {
    const INTEGRAL: f64 = 4_503_599_627_370_496.0; // 2^52
    let a = x.abs();
    let t = (a + INTEGRAL) - INTEGRAL;
    let r = if a - t == 0.5 { t + 1.0 } else { t };
    if a < INTEGRAL { r.copysign(x) } else { x }
}

/// Whether `x` is positive and finite (`x > 0.0 && x < f64::INFINITY`), as one
/// integer comparison: the bits of a positive finite double, less one, lie below
/// those of infinity, less one, and those of zero, negative numbers and NaN do not
/// (the float comparisons compile to a longer classification).
#[inline]
#[must_use]
pub fn positive_finite(x: f64) -> bool {
    x.to_bits().wrapping_sub(1) < f64::INFINITY.to_bits() - 1
}

/// The smaller of two numbers, for arguments that are not NaN (then it is `f64::min`,
/// in one instruction where `f64::min` needs several to handle NaN; with a NaN
/// argument it returns `b`).
#[inline]
#[must_use]
pub fn min_num(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// The larger of two numbers that are not NaN (see [`min_num`]).
#[inline]
#[must_use]
pub fn max_num(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

/// `x^y`.
#[inline]
#[must_use]
pub fn powf(x: f64, y: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        x.powf(y)
    }
    #[cfg(not(feature = "std"))]
    {
        libm::pow(x, y)
    }
}

/// Four-quadrant arc tangent of `y / x`, in radians.
#[inline]
#[must_use]
pub fn atan2(y: f64, x: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        y.atan2(x)
    }
    #[cfg(not(feature = "std"))]
    {
        libm::atan2(y, x)
    }
}

/// Arc cosine with the argument clamped to `[-1, 1]`, so rounding never yields NaN.
#[inline]
#[must_use]
pub fn acos_clamped(x: f64) -> f64 {
    acos(x.clamp(-1.0, 1.0))
}

/// `1 / s²`, `s` the [`smaller_singular_value`] of the 2x2 matrix with columns `a`
/// and `b`, with one square root (the discriminant's) and one division:
///
/// ```text
/// 1 / s_min² = (F + sqrt(F² - 4D²)) / (2D²)
/// ```
///
/// Infinite or NaN where `s` is 0 or undefined (a singular or non-finite matrix).
#[must_use]
#[inline]
pub fn inverse_square_smaller_singular_value(a: glam::DVec2, b: glam::DVec2) -> f64 {
    let frobenius = a.length_squared() + b.length_squared();
    let det = a.perp_dot(b);
    // `D²` once: scaling it by 4 or 2 is exact, so `4 D²` and `2 D²` are the
    // products `4 D D` and `2 D D` bit for bit (short of underflow, where the
    // result is past any error that matters).
    let det2 = det * det;
    let root = sqrt((frobenius * frobenius - 4.0 * det2).max(0.0));
    let inv = (frobenius + root) / (2.0 * det2);
    if inv > 0.0 { inv } else { f64::INFINITY }
}

/// The smaller singular value of the 2x2 matrix with columns `a` and `b`: how much
/// the map stretches the direction it stretches least (the texels per pixel of
/// Lloyd et al.'s aliasing error, whose inverse is the error).
///
/// ```text
/// F = |a|² + |b|²,  D = det[a b],  s_min² = (F - sqrt(F² - 4D²)) / 2 = 2D² / (F + sqrt(F² - 4D²))
/// ```
///
/// computed in the second, cancellation-free form; 0 for the zero matrix.
#[must_use]
pub fn smaller_singular_value(a: glam::DVec2, b: glam::DVec2) -> f64 {
    let frobenius = a.length_squared() + b.length_squared();
    let det = a.perp_dot(b);
    let root = sqrt((frobenius * frobenius - 4.0 * det * det).max(0.0));
    let denom = frobenius + root;
    if denom > 0.0 {
        sqrt(2.0 * det * det / denom)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    /// `round` is `f64::round` bit for bit, halves, signed zeros, the edges of
    /// `2^52` and non-finite values included.
    #[test]
    fn round_matches_std_at_the_edges() {
        let big = 4_503_599_627_370_496.0f64;
        let cases = [
            0.0,
            -0.0,
            0.3,
            -0.3,
            0.5,
            -0.5,
            1.5,
            -2.5,
            0.499_999_999_999_999_94,
            -0.499_999_999_999_999_94,
            big - 0.5,
            -(big - 0.5),
            big,
            -big,
            big * 2.0 + 1.0,
            f64::MAX,
            f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for x in cases {
            assert_eq!(super::round(x).to_bits(), x.round().to_bits(), "{x}");
        }
        assert!(super::round(f64::NAN).is_nan());
    }

    proptest! {
        #[test]
        fn round_matches_std(bits in any::<u64>(), scale in -60i32..60) {
            let x = f64::from_bits(bits);
            if x.is_nan() {
                // A NaN stays a NaN (std may quiet a signalling one: other bits).
                prop_assert!(super::round(x).is_nan());
            } else {
                prop_assert_eq!(super::round(x).to_bits(), x.round().to_bits());
            }
            // Values near the scale of texel snapping, halves included.
            let y = (bits >> 11) as f64 * 2f64.powi(scale - 53);
            for v in [y, -y, y.floor() + 0.5, -(y.floor() + 0.5)] {
                prop_assert_eq!(super::round(v).to_bits(), v.round().to_bits(), "{}", v);
            }
        }

        /// `inverse_square_smaller_singular_value` with `D²` taken once is the
        /// formula with `4 D D` and `2 D D`, bit for bit, over matrices whose
        /// entries span 2^-60 to 2^60.
        #[test]
        fn the_shared_square_of_the_determinant_is_exact(
            m in proptest::array::uniform4(-1.0f64..1.0),
            scales in proptest::array::uniform4(-60i32..60),
        ) {
            let e: [f64; 4] = core::array::from_fn(|i| m[i] * 2f64.powi(scales[i]));
            let (a, b) = (glam::DVec2::new(e[0], e[1]), glam::DVec2::new(e[2], e[3]));
            let frobenius = a.length_squared() + b.length_squared();
            let det = a.perp_dot(b);
            let root = super::sqrt((frobenius * frobenius - 4.0 * det * det).max(0.0));
            let inv = (frobenius + root) / (2.0 * det * det);
            let by_products = if inv > 0.0 { inv } else { f64::INFINITY };
            prop_assert_eq!(
                super::inverse_square_smaller_singular_value(a, b).to_bits(),
                by_products.to_bits()
            );
        }

        /// `positive_finite` is `x > 0.0 && x < f64::INFINITY`, for any bits and at
        /// the edges (zeros, the smallest subnormal, the largest double, infinities,
        /// NaN of either sign).
        #[test]
        fn positive_finite_matches_comparisons(bits in any::<u64>()) {
            let edges = [0.0, -0.0, f64::from_bits(1), f64::MAX, f64::INFINITY,
                f64::NEG_INFINITY, f64::NAN, -f64::NAN, -f64::from_bits(1), 1.0];
            for x in edges.into_iter().chain([f64::from_bits(bits)]) {
                prop_assert_eq!(super::positive_finite(x), x > 0.0 && x < f64::INFINITY, "{}", x);
            }
        }
    }
}
