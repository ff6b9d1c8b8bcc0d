//! The optional fast-math backend, built on `micromath` (feature `micromath`).

use crate::math::Backend;

/// Fast approximate `exp` from `micromath`, chosen explicitly by the caller.
///
/// Enabling the `micromath` feature only *adds* this type: tables keep using [`Libm`]
/// unless a call names `FastMath` (for example `table.map_with::<FastMath>(..)`).
///
/// # Accuracy
///
/// Over every `f32` in `[-87, 0]` (the only arguments the prior produces; checked
/// exhaustively), this `exp` is within `-2.1e-6` and `+2.39e-3` of the exact value,
/// relatively (the worst case is at `x = -85.95025`; the unit test `exp_relative_error`
/// re-checks a sample). Through the normalisation a relative error `e` on one class's
/// mass moves a score by at most `s (1 - s) e <= e / 4`, so a MAP score differs from the
/// [`Libm`] one by at most about `6.0e-4` (times `OS`). Measured over the shipped table
/// (every MAP bin of every class against every bin of the others, and 50 000 random
/// vectors), the worst difference is `5.8e-4` (at logits `[2.947, -4.731, 1.948]`).
/// [`FAST_MATH_MAX_SCORE_ERROR`](crate::FAST_MATH_MAX_SCORE_ERROR) = `7e-4` bounds both,
/// and is asserted by the test `fast_math_error_bound` and, on random tables, by the
/// property tests.
///
/// The bound needs `lambda_MAP` not to be negligible against `norm * e^-87` (`norm` the
/// prior's `1 / sqrt(2 pi var)`): below `-87` this `exp` answers 0 where `libm` gives a
/// tiny positive value, which only matters when `lambda_MAP` is tinier still. Every
/// table with `lambda_MAP >= 1e-13` qualifies.
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
/// [`Libm`](crate::Libm), for `OS = 1` (scores scale with `OS`): `7e-4`.
///
/// Measured worst case over the shipped table and a dense grid of logits: `5.8e-4`;
/// analytic bound for any table with `lambda_MAP >= 1e-13`: about `6.0e-4` (see
/// [`FastMath`]). Asserted by the test `fast_math_error_bound`.
pub const FAST_MATH_MAX_SCORE_ERROR: f32 = 7e-4;

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed relative error of `FastMath::exp` against `libm`'s float64 `exp`, as
    /// measured exhaustively over every `f32` in `[-87, 0]` (see the `FastMath` docs).
    const MIN_REL_ERR: f64 = -2.1e-6;
    const MAX_REL_ERR: f64 = 2.4e-3;

    fn rel_err(x: f32) -> f64 {
        let exact = libm::exp(f64::from(x));
        (f64::from(FastMath::exp(x)) - exact) / exact
    }

    #[test]
    fn exp_relative_error() {
        // Every 4099th f32 from -0 down to -87, plus the exhaustive search's worst
        // cases and the points where micromath switches code paths.
        let mut xs: std::vec::Vec<f32> = std::vec![-85.95025, -44.411667, -0.0, -1.0, -87.0];
        let end = (-87.0f32).to_bits();
        xs.extend((0x8000_0000u32..=end).step_by(4099).map(f32::from_bits));
        let (mut lo, mut hi) = (0.0f64, 0.0f64);
        for &x in &xs {
            let e = rel_err(x);
            assert!(
                (MIN_REL_ERR..=MAX_REL_ERR).contains(&e),
                "exp({x}): relative error {e:e} outside [{MIN_REL_ERR:e}, {MAX_REL_ERR:e}]"
            );
            lo = lo.min(e);
            hi = hi.max(e);
        }
        // The sample reaches the documented worst case, so the bound is tight.
        assert!(hi > 2.3e-3, "largest error seen {hi:e}");
        assert!(lo < 0.0, "smallest error seen {lo:e}");
    }

    #[test]
    fn exp_flushes_below_minus_87() {
        assert_eq!(FastMath::exp(-87.5), 0.0);
        assert_eq!(FastMath::exp(f32::NEG_INFINITY), 0.0);
        assert_eq!(FastMath::exp(-1e30), 0.0);
        assert_eq!(FastMath::exp(0.0), 1.0);
        assert_eq!(FastMath::exp(-0.0), 1.0);
    }
}
