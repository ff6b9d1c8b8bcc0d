//! The score checkers: ranges and sums, the exact `OS / K` answer, monotone scores, bad
//! input.

use super::*;

#[test]
fn scores_in_range_summing_to_objectness_pass() {
    assert_eq!(check_scores(&[0.25, 0.5, 0.15], 0.9, Sum::Equal), Ok(()));
    // 1e-5 relative of 0.9 is 9e-6: a sum 8.1e-6 above passes.
    assert_eq!(check_scores(&[0.45, 0.450_008_1], 0.9, Sum::Equal), Ok(()));
    assert_eq!(check_scores(&[0.2, 0.3], 0.9, Sum::AtMost), Ok(()));
    assert_eq!(check_scores(&[0.0, -0.0], 0.0, Sum::Equal), Ok(()));
    // A subnormal objectness: one rounding step per score is allowed.
    let step = f32::from_bits(1);
    assert_eq!(
        check_scores(&[step, step], f32::from_bits(3), Sum::Equal),
        Ok(())
    );
    assert_eq!(check_scores(&[], 0.5, Sum::AtMost), Ok(()));
}

#[test]
fn each_score_violation_is_reported() {
    fails(
        check_scores(&[0.5, 0.6], 0.5, Sum::Equal),
        Violation::ScoreOutOfRange {
            class: 1,
            score: 0.6,
            objectness: 0.5,
        },
        1,
        "score of class 1 = 6e-1 is outside [0, OS = 5e-1]",
    );
    fails(
        check_scores(&[0.0, -1e-30], 1.0, Sum::AtMost),
        Violation::ScoreOutOfRange {
            class: 1,
            score: -1e-30,
            objectness: 1.0,
        },
        1,
        "class 1",
    );
    let nan = check_scores(&[f32::NAN, 1.0], 1.0, Sum::Equal);
    assert!(
        matches!(nan, Err(Violation::ScoreOutOfRange { class: 0, score, .. }) if score.is_nan()),
        "{nan:?}"
    );
    // 1.8e-5 above 0.9: out of the 9e-6 tolerance.
    fails(
        check_scores(&[0.45, 0.450_018], 0.9, Sum::Equal),
        Violation::SumNotObjectness {
            sum: f64::from(0.45f32) + f64::from(0.450_018f32),
            objectness: 0.9,
        },
        1,
        "not to OS = 9e-1",
    );
    fails(
        check_scores(&[0.2, 0.3], 0.9, Sum::Equal),
        Violation::SumNotObjectness {
            sum: f64::from(0.2f32) + f64::from(0.3f32),
            objectness: 0.9,
        },
        1,
        "the scores sum to 5",
    );
    fails(
        check_scores(&[0.45, 0.46], 0.9, Sum::AtMost),
        Violation::SumAboveObjectness {
            sum: f64::from(0.45f32) + f64::from(0.46f32),
            objectness: 0.9,
        },
        1,
        "above OS = 9e-1",
    );
}

#[test]
fn unknown_must_be_exactly_os_over_k() {
    let third = 0.9f32 / 3.0;
    assert_eq!(check_unknown(&[third; 3], 0.9), Ok(()));
    let quarter = 0.25f32;
    let off = quarter.next_up();
    fails(
        check_unknown(&[quarter, quarter, off, quarter], 1.0),
        Violation::NotUnknown {
            class: 2,
            score: off,
            expected: quarter,
        },
        2,
        "score of class 2 = 2.5000003e-1 is not OS / K = 2.5e-1",
    );
    let off = third.next_up();
    fails(
        check_unknown(&[third, off, third], 0.9),
        Violation::NotUnknown {
            class: 1,
            score: off,
            expected: third,
        },
        2,
        "without evidence, score of class 1",
    );
}

#[test]
fn monotone_allows_equal_and_higher_scores_only() {
    assert_eq!(check_monotone(2, 0.25, 0.25), Ok(()));
    assert_eq!(check_monotone(2, 0.25, 0.5), Ok(()));
    let lower = 0.25f32.next_down();
    fails(
        check_monotone(2, 0.25, lower),
        Violation::ScoreLowered {
            class: 2,
            before: 0.25,
            after: lower,
        },
        3,
        "lowered the score of class 2 from 2.5e-1 to 2.4999999e-1",
    );
    assert!(check_monotone(0, 0.25, f32::NAN).is_err());
    assert!(check_monotone(0, f32::NAN, 0.25).is_err());
}

#[test]
fn bad_input_must_be_the_right_error() {
    let nan_logit = InferError::NanLogit { class: 1 };
    // The first NaN logit comes before a bad objectness.
    assert_eq!(
        expected_error(&[0.0, f32::NAN, f32::NAN], 2.0),
        Some(nan_logit)
    );
    // ±inf logits and a -0 objectness are valid.
    assert_eq!(
        expected_error(&[f32::INFINITY, f32::NEG_INFINITY], -0.0),
        None
    );
    for os in [f32::NAN, -1e-45, 1.0f32.next_up(), f32::INFINITY] {
        assert_eq!(
            expected_error(&[0.0, 1.0], os),
            Some(InferError::Objectness)
        );
    }
    assert_eq!(check_error(&[0.0, 1.0], 1.0, None), Ok(()));
    assert_eq!(check_error(&[0.0, f32::NAN], 1.0, Some(nan_logit)), Ok(()));
    fails(
        check_error(&[0.0, f32::NAN], 1.0, None),
        Violation::MissingError {
            expected: nan_logit,
        },
        4,
        "scored instead of refused",
    );
    fails(
        check_error(&[0.0, f32::NAN], 1.5, Some(InferError::Objectness)),
        Violation::WrongError {
            expected: Some(nan_logit),
            found: InferError::Objectness,
        },
        4,
        "instead of",
    );
    fails(
        check_error(&[0.0, 1.0], 1.0, Some(InferError::Objectness)),
        Violation::WrongError {
            expected: None,
            found: InferError::Objectness,
        },
        4,
        "a valid input was refused",
    );
}
