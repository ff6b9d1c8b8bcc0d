//! The open head's invariants (DESIGN §1.8): its decision, and an `f64` reference for its
//! scores.

use super::*;
use crate::OpenParams;

/// The open head of DESIGN §1.8 evaluated in `f64` from the Bayes head's stored terms
/// and rows and the open head's parameters: `q` from the categories' log-scores and the
/// unknown category's `ln(epsilon) + K ln(1/B + lambda)`, times `softmax(z / T)`
/// (infinite logits as their limit), times `OS`; written into `out` (length K), and `q`
/// returned. A reference for the head's `f32` inference. Inputs must be valid (no NaN
/// logit, objectness in `[0, 1]`); `scratch` holds one value per Bayes category.
///
/// Returns `None` (and writes nothing) when a length does not fit the head.
pub fn open_reference(
    head: &BayesView<'_>,
    params: &OpenParams,
    logits: &[f32],
    objectness: f32,
    out: &mut [f64],
    scratch: &mut [f64],
) -> Option<f64> {
    let (k, cats) = (head.logits(), head.categories());
    if logits.len() != k || out.len() != k || scratch.len() != cats {
        return None;
    }
    // The categories' log-scores, as the Bayes reference computes them.
    let log_lambda = libm::log(f64::from(head.lambda()));
    let total: f64 = head.all_rows().iter().map(|&n| n as f64).sum();
    for (c, l) in scratch.iter_mut().enumerate() {
        let pi = head.rows(c).map_or(f64::NAN, |n| n as f64 / total);
        *l = libm::log(pi);
        for (j, &x) in logits.iter().enumerate() {
            let term = head
                .axis(j)
                .and_then(|a| a.bin(x))
                .and_then(|b| head.term(c, j, b));
            *l += term.map_or(log_lambda, f64::from);
        }
    }
    let max = scratch.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (mut known, mut all) = (0.0f64, 0.0f64);
    for (c, &l) in scratch.iter().enumerate() {
        let e = libm::exp(l - max);
        all += e;
        if c < k {
            known += e;
        }
    }
    let epsilon = f64::from(params.epsilon());
    let unknown = if epsilon == 0.0 {
        0.0
    } else {
        let flat = k as f64 * libm::log(1.0 / head.bins() as f64 + f64::from(head.lambda()));
        libm::exp(libm::log(epsilon) + flat - max)
    };
    let q = known / (all + unknown);
    // softmax(z / T), infinite logits as their limit.
    let t = f64::from(params.temperature());
    let zmax = logits
        .iter()
        .map(|&x| f64::from(x) / t)
        .fold(f64::NEG_INFINITY, f64::max);
    if zmax.is_infinite() {
        let n = logits.iter().filter(|&&x| f64::from(x) / t == zmax).count() as f64;
        for (o, &x) in out.iter_mut().zip(logits) {
            let top = f64::from(x) / t == zmax;
            *o = if top {
                f64::from(objectness) * q / n
            } else {
                0.0
            };
        }
        return Some(q);
    }
    let mut sum = 0.0;
    for (o, &x) in out.iter_mut().zip(logits) {
        *o = libm::exp(f64::from(x) / t - zmax);
        sum += *o;
    }
    for o in out.iter_mut() {
        *o = f64::from(objectness) * q * *o / sum;
    }
    Some(q)
}

/// Relative tolerance of an open-head score against [`open_reference`], for one
/// detection with `logits`.
///
/// # Derivation
///
/// The score is `(OS q) p_i`. `q` is a ratio of sums of the same exponentials as the
/// Bayes head's softmax, plus one more (`e^(l_u - m)`, whose argument carries the `f32`
/// rounding of `ln(epsilon)`, of `K ln(1/B + lambda)` and of their sum: at most
/// `(K + 4) u (|l_u| + 1)`), so it is within [`bayes_score_tolerance`] plus that. `p_i`
/// is the temperature layer: each argument `a_i = (z_i - max z) / T` carries the rounding
/// of the subtraction and of the division, `2 u |a_i|` (`u = 2^-24`); an `a_i` below
/// `-104` gives 0 in `f32` and is covered by the absolute slack, so with
/// `A = min(max |a_i|, 104)` over the finite logits each argument is within
/// `d = 4 u (A + 1)` of the exact one; `exp` adds [`FAST_MATH_MAX_REL_ERROR`] and the
/// normalisation `(K + 1) u`: a relative `2 (2 d + e) + (K + 1) u`. The two add up, and
/// the bound doubles the sum for the second-order terms.
#[must_use]
pub fn open_score_tolerance(head: &BayesView<'_>, params: &OpenParams, logits: &[f32]) -> f64 {
    const U: f64 = 1.0 / 16_777_216.0;
    let k = head.logits() as f64;
    let t = f64::from(params.temperature());
    let top = logits
        .iter()
        .map(|&x| f64::from(x))
        .fold(f64::NEG_INFINITY, f64::max);
    let a = logits
        .iter()
        .map(|&x| ((f64::from(x) - top) / t).abs())
        .filter(|a| a.is_finite())
        .fold(0.0f64, f64::max)
        .min(104.0);
    let d = 4.0 * U * (a + 1.0);
    let e = f64::from(FAST_MATH_MAX_REL_ERROR);
    let softmax = 2.0 * (2.0 * d + e) + (k + 1.0) * U;
    let lu = f64::from(params.log_unknown());
    let unknown = if lu.is_finite() {
        2.0 * (k + 4.0) * U * (lu.abs() + 1.0)
    } else {
        0.0
    };
    (2.0 * (bayes_score_tolerance(head) + unknown + softmax)).max(SUM_RELATIVE_TOLERANCE)
}

/// Whether open-head `scores` are within [`open_score_tolerance`] (relative, plus the
/// absolute slack of subnormal values) of the `f64` reference `want`
/// ([`open_reference`]); the index of the first that is not.
#[must_use]
pub fn open_mismatch(
    head: &BayesView<'_>,
    params: &OpenParams,
    logits: &[f32],
    scores: &[f32],
    want: &[f64],
    objectness: f32,
) -> Option<usize> {
    let relative = open_score_tolerance(head, params, logits);
    let slack = f64::from(objectness) * f64::from(f32::MIN_POSITIVE) + 4.0 * SUBNORMAL_STEP;
    if scores.len() != want.len() {
        return Some(scores.len().min(want.len()));
    }
    scores
        .iter()
        .zip(want)
        .position(|(&s, &w)| !((f64::from(s) - w).abs() <= relative * w + slack))
}

/// DESIGN §1.8, the decision: the open head's decided class (DESIGN §1.7, through
/// [`decide`](crate::decide)) is the detector's, the largest logit, the lower index
/// among equal ones.
///
/// # Errors
///
/// [`Violation::ClassCount`] when the lengths differ; [`Violation::NotDetectorDecision`]
/// when the decided class is another.
pub fn check_open_decision(scores: &[f32], logits: &[f32]) -> Result<(), Violation> {
    if scores.len() != logits.len() {
        return Err(Violation::ClassCount {
            expected: logits.len(),
            found: scores.len(),
        });
    }
    let mut best: Option<(usize, f32)> = None;
    for (i, &x) in logits.iter().enumerate() {
        if !x.is_nan() && best.is_none_or(|(_, b)| x > b) {
            best = Some((i, x));
        }
    }
    let decided = crate::decide(scores, logits);
    match best {
        Some((expected, _)) if decided != expected => Err(Violation::NotDetectorDecision {
            expected,
            found: decided,
        }),
        _ => Ok(()),
    }
}
