//! The prediction layers mlmap replaces, in `f32` on the device (DESIGN §1.4): the
//! YOLOv4-style Sigmoid layer, the Softmax layer and its temperature-scaled form. They
//! exist so benchmarks and firmware can compare like with like; host evaluation uses
//! `f64` versions.

use crate::diagnostics::error::InferError;
use crate::heads::layer::{self, Scores};
use crate::math::Backend;

/// `OS * sigma(x_i)` per class, the Sigmoid layer of YOLOv4 (the paper's "SG").
///
/// Uses `exp` of a non-positive argument only, so it cannot overflow.
///
/// # Errors
///
/// As [`Table::ml`](crate::Table::ml).
///
/// # Panics
///
/// Never.
#[inline]
pub fn sigmoid<M: Backend, const K: usize>(
    logits: &[f32; K],
    objectness: f32,
) -> Result<Scores<K>, InferError> {
    layer::check(logits, objectness, K, K)?;
    let mut out = [0.0; K];
    for (o, &x) in out.iter_mut().zip(logits) {
        let s = if x >= 0.0 {
            1.0 / (1.0 + M::exp(-x))
        } else {
            let e = M::exp(x);
            e / (1.0 + e)
        };
        *o = objectness * s;
    }
    Ok(Scores(out))
}

/// `OS * softmax(x)_i`, computed with the maximum subtracted first.
///
/// # Errors
///
/// As [`Table::ml`](crate::Table::ml).
///
/// # Panics
///
/// Never.
#[inline]
pub fn softmax<M: Backend, const K: usize>(
    logits: &[f32; K],
    objectness: f32,
) -> Result<Scores<K>, InferError> {
    layer::check(logits, objectness, K, K)?;
    let max = logits.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let mut out = [0.0; K];
    if max.is_infinite() {
        // All -inf, or some +inf: the limit puts equal mass on the largest entries.
        let n = logits.iter().filter(|&&x| x == max).count() as f32;
        for (o, &x) in out.iter_mut().zip(logits) {
            *o = if x == max { objectness / n } else { 0.0 };
        }
        return Ok(Scores(out));
    }
    let mut sum = 0.0;
    for (o, &x) in out.iter_mut().zip(logits) {
        *o = M::exp(x - max);
        sum += *o;
    }
    let scale = objectness / sum;
    for o in out.iter_mut() {
        *o *= scale;
    }
    Ok(Scores(out))
}

/// `OS * softmax(x / T)_i`, the temperature-scaled Softmax layer (DESIGN §1.4) with a
/// temperature `T > 0`, in `f32`: `exp((x_i - max) / T)` normalised (infinite logits as
/// in [`softmax`]). The open head (DESIGN §1.8) ends in exactly this computation.
///
/// # Errors
///
/// As [`Table::ml`](crate::Table::ml); [`InferError::Evidence`] when `temperature` is
/// not finite and positive.
///
/// # Panics
///
/// Never.
#[inline]
pub fn temperature<M: Backend, const K: usize>(
    logits: &[f32; K],
    temperature: f32,
    objectness: f32,
) -> Result<Scores<K>, InferError> {
    layer::check(logits, objectness, K, K)?;
    if !(temperature > 0.0 && temperature.is_finite()) {
        return Err(InferError::Evidence);
    }
    let mut out = [0.0; K];
    temperature_into::<M>(logits, temperature, objectness, &mut out);
    Ok(Scores(out))
}

/// [`temperature`] on checked inputs, into `out` (as many entries as `logits`). The
/// largest logit is subtracted before the division by `T`, so a finite logit never
/// overflows to an infinite quotient however small `T` is: each argument of `exp` is
/// `(x_i - max) / T <= 0`.
#[inline(always)]
pub(crate) fn temperature_into<M: Backend>(
    logits: &[f32],
    temperature: f32,
    objectness: f32,
    out: &mut [f32],
) {
    let max = logits.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    if max.is_infinite() {
        // All -inf, or some +inf: the limit puts equal mass on the largest entries.
        let n = logits.iter().filter(|&&x| x == max).count() as f32;
        for (o, &x) in out.iter_mut().zip(logits) {
            *o = if x == max { objectness / n } else { 0.0 };
        }
        return;
    }
    let mut sum = 0.0;
    for (o, &x) in out.iter_mut().zip(logits) {
        *o = M::exp((x - max) / temperature);
        sum += *o;
    }
    let scale = objectness / sum;
    for o in out.iter_mut() {
        *o *= scale;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;

    #[test]
    fn sigmoid_values() {
        // sigma(0) = 0.5, sigma(2) = 0.8807970779778823, sigma(-2) = 0.11920292202211755.
        let s = sigmoid::<Libm, 3>(&[0.0, 2.0, -2.0], 0.5).unwrap().0;
        let want = [0.25, 0.440_398_538_988_941_1, 0.059_601_461_011_058_77];
        for (g, w) in s.iter().zip(want) {
            assert!((*g as f64 - w).abs() < 1e-7, "{g} vs {w}");
        }
    }

    #[test]
    fn temperature_never_overflows_a_finite_logit() {
        // (x - max) / T: the two large logits differ by 9.75e30, which at T = 1e-6 puts
        // all the mass on the larger; x / T alone would overflow both to +inf and split it.
        let x = [1.305_761_2e36, -2.881_616_4, 1.305_771e36];
        let s = temperature::<Libm, 3>(&x, 1e-6, 0.484).unwrap().0;
        assert_eq!(s, [0.0, 0.0, 0.484]);
        // At T = 1 the layer is the Softmax layer.
        let x = [1.0, 2.0, 3.0];
        assert_eq!(
            temperature::<Libm, 3>(&x, 1.0, 1.0).unwrap(),
            softmax::<Libm, 3>(&x, 1.0).unwrap()
        );
        // softmax([1, 2, 3] / 2) = [0.18632372, 0.30719589, 0.50648039].
        let s = temperature::<Libm, 3>(&x, 2.0, 1.0).unwrap().0;
        let want = [0.186_323_721_6, 0.307_195_890_1, 0.506_480_388_3];
        for (g, w) in s.iter().zip(want) {
            assert!((f64::from(*g) - w).abs() < 1e-7, "{g} vs {w}");
        }
        assert!(temperature::<Libm, 3>(&x, 0.0, 1.0).is_err());
        assert!(temperature::<Libm, 3>(&x, f32::NAN, 1.0).is_err());
    }

    #[test]
    fn softmax_values_and_limits() {
        // softmax([1, 2, 3]) = [0.09003057, 0.24472847, 0.66524096].
        let s = softmax::<Libm, 3>(&[1.0, 2.0, 3.0], 1.0).unwrap().0;
        let want = [
            0.090_030_573_170_380_46,
            0.244_728_471_054_797_64,
            0.665_240_955_774_821_9,
        ];
        for (g, w) in s.iter().zip(want) {
            assert!((*g as f64 - w).abs() < 1e-7, "{g} vs {w}");
        }
        let s = softmax::<Libm, 3>(&[f32::INFINITY, 0.0, f32::INFINITY], 1.0)
            .unwrap()
            .0;
        assert_eq!(s, [0.5, 0.0, 0.5]);
        let s = softmax::<Libm, 2>(&[f32::NEG_INFINITY; 2], 0.8).unwrap().0;
        assert_eq!(s, [0.4, 0.4]);
    }
}
