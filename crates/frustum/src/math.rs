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
