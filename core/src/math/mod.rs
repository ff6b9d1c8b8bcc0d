//! The only place that calls a floating-point maths library.
//!
//! Inference needs one transcendental function, `exp`, for the Gaussian prior of the MAP
//! head (the ML head needs none). Which implementation runs is chosen by the caller
//! through a [`Backend`] type parameter, never by a Cargo feature, so adding a
//! dependency can never change anybody else's numbers. [`Libm`] is the default.
//!
//! Functions are called as free functions (`libm::expf(x)`), never as methods: with
//! `std` linked, as in host tests, std's inherent methods would silently shadow a
//! trait's and the tests would check code that does not ship.
//!
//! The submodules hold the numerical building blocks the heads are made of: the
//! likelihoods (`histogram`), the prior (`gaussian`), the crate's own `exp` (`fastmath`)
//! and the baselines a layer is compared with (`baseline`).

pub mod baseline;
pub mod fastmath;
pub mod gaussian;
pub mod histogram;

/// A source of `exp` for the MAP head's Gaussian prior.
///
/// Implemented by [`Libm`] (correctly rounded to within 1 ulp, the default) and, with
/// the `micromath` feature, by `FastMath`.
pub trait Backend {
    /// Short name used in reports and benchmarks.
    const NAME: &'static str;
    /// `e^x` for `x <= 0` (the only range the prior needs); `exp(-inf) = 0`.
    fn exp(x: f32) -> f32;
}

/// The default backend: `libm`'s `expf`, within 1 ulp of the exact result.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Libm;

impl Backend for Libm {
    const NAME: &'static str = "libm";

    #[inline]
    fn exp(x: f32) -> f32 {
        libm::expf(x)
    }
}

/// `sqrt` for table preparation (decode time, never per detection).
#[inline]
pub(crate) fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// `e^x` for table preparation (decode time, never per detection).
#[inline]
pub(crate) fn exp(x: f32) -> f32 {
    libm::expf(x)
}

/// Natural logarithm for table preparation (decode time, never per detection).
#[inline]
pub(crate) fn ln(x: f32) -> f32 {
    libm::logf(x)
}
