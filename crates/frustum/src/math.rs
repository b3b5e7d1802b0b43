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
    /// Largest integer not above `x`.
    floor => floor;
    /// Smallest integer not below `x`.
    ceil => ceil;
    /// Nearest integer, halves away from zero.
    round => round;
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
