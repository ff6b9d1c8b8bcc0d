//! The optional fast-math backend, built on `micromath` (feature `micromath`).

use crate::math::Backend;

/// Fast approximate `exp` from `micromath`, chosen explicitly by the caller.
///
/// Enabling the `micromath` feature only *adds* this type: tables keep using [`Libm`]
/// unless a call names `FastMath` (for example `table.map_with::<FastMath>(..)`).
///
/// # Accuracy
///
/// `micromath`'s `exp` has a relative error of about `1e-3`. Through the normalisation
/// of the MAP head the error on a posterior score stays below
/// [`FAST_MATH_MAX_SCORE_ERROR`](crate::FAST_MATH_MAX_SCORE_ERROR) (absolute, for
/// `OS = 1`), measured over the shipped table and asserted by the test
/// `fast_math_error_bound`.
///
/// [`Libm`]: crate::Libm
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
#[cfg_attr(docsrs, doc(cfg(feature = "micromath")))]
pub struct FastMath;

impl Backend for FastMath {
    const NAME: &'static str = "micromath";

    #[inline]
    fn exp(x: f32) -> f32 {
        // Below -87.3 the exact result is under f32's smallest normal; micromath's
        // range reduction is not meant for it, so answer 0 directly (also for -inf).
        if x < -87.0 {
            0.0
        } else {
            micromath::F32(x).exp().0
        }
    }
}

/// Largest absolute difference between a MAP score computed with [`FastMath`] and with
/// [`Libm`](crate::Libm), for `OS = 1` (scores scale with `OS`). Asserted by the test
/// `fast_math_error_bound` over the shipped table and a dense grid of logits.
pub const FAST_MATH_MAX_SCORE_ERROR: f32 = 1e-2;
