//! Invariants 1 to 4 of DESIGN §1.3 on the scores of one detection.

use super::*;

/// Invariant 1: every score is in `[0, OS]`, and the scores sum to `OS` ([`Sum::Equal`])
/// or to at most `OS` ([`Sum::AtMost`]), within [`SUM_RELATIVE_TOLERANCE`] of `OS` plus
/// `K` times [`SUBNORMAL_STEP`]. The sum is taken in `f64`.
///
/// # Errors
///
/// [`Violation::ScoreOutOfRange`] for the first score that is NaN or outside `[0, OS]`,
/// then [`Violation::SumNotObjectness`] or [`Violation::SumAboveObjectness`].
pub fn check_scores(scores: &[f32], objectness: f32, sum: Sum) -> Result<(), Violation> {
    let mut total = 0.0f64;
    for (class, &score) in scores.iter().enumerate() {
        if !(score >= 0.0 && score <= objectness) {
            return Err(Violation::ScoreOutOfRange {
                class,
                score,
                objectness,
            });
        }
        total += f64::from(score);
    }
    let os = f64::from(objectness);
    let tolerance = SUM_RELATIVE_TOLERANCE * os + scores.len() as f64 * SUBNORMAL_STEP;
    match sum {
        Sum::Equal if !((total - os).abs() <= tolerance) => Err(Violation::SumNotObjectness {
            sum: total,
            objectness,
        }),
        Sum::AtMost if !(total <= os + tolerance) => Err(Violation::SumAboveObjectness {
            sum: total,
            objectness,
        }),
        _ => Ok(()),
    }
}

/// Invariant 2: every score is exactly `OS / K` (computed in `f32`), bit for bit: the
/// answer of the ML and MAP heads when no class has evidence.
///
/// # Errors
///
/// [`Violation::NotUnknown`] for the first other score.
pub fn check_unknown(scores: &[f32], objectness: f32) -> Result<(), Violation> {
    let expected = objectness / scores.len() as f32;
    match scores
        .iter()
        .position(|s| s.to_bits() != expected.to_bits())
    {
        Some(class) => Err(Violation::NotUnknown {
            class,
            score: scores.get(class).copied().unwrap_or(f32::NAN),
            expected,
        }),
        None => Ok(()),
    }
}

/// Invariant 3: the score of `class` with more evidence (`after`) is not below its
/// score with less (`before`), everything else being the same.
///
/// # Errors
///
/// [`Violation::ScoreLowered`] when `after < before` or either is NaN.
pub fn check_monotone(class: usize, before: f32, after: f32) -> Result<(), Violation> {
    if after >= before {
        Ok(())
    } else {
        Err(Violation::ScoreLowered {
            class,
            before,
            after,
        })
    }
}

/// The error that invariant 4 demands for these inputs: the first NaN logit, else an
/// objectness that is NaN or outside `[0, 1]`; `None` for valid inputs.
#[must_use]
pub fn expected_error(logits: &[f32], objectness: f32) -> Option<InferError> {
    if let Some(i) = logits.iter().position(|x| x.is_nan()) {
        return Some(InferError::NanLogit {
            class: u16::try_from(i).unwrap_or(u16::MAX),
        });
    }
    if !(0.0..=1.0).contains(&objectness) {
        return Some(InferError::Objectness);
    }
    None
}

/// Invariant 4: `found`, the error (if any) that scoring `logits` with `objectness`
/// returned, is exactly [`expected_error`]`(logits, objectness)`.
///
/// # Errors
///
/// [`Violation::MissingError`] when a bad input was scored, [`Violation::WrongError`]
/// when the error differs or a valid input was refused.
pub fn check_error(
    logits: &[f32],
    objectness: f32,
    found: Option<InferError>,
) -> Result<(), Violation> {
    let expected = expected_error(logits, objectness);
    match (expected, found) {
        (Some(expected), None) => Err(Violation::MissingError { expected }),
        (expected, Some(found)) if expected != Some(found) => {
            Err(Violation::WrongError { expected, found })
        }
        _ => Ok(()),
    }
}
