//! Unit tests of the checkers: every `Violation` produced, valid tables passing.

use std::string::ToString;

use super::*;
use crate::{ClassSpec, EdgeMode, UpperTail};

fn settings(lambda_ml: f32, lambda_map: f32) -> Settings {
    Settings {
        lambda_ml,
        lambda_map,
        edge_mode: EdgeMode::Linspace,
        upper_tail: UpperTail::Zero,
    }
}

fn spec(name: &str) -> ClassSpec<'_, [f32; 2], [f32; 1]> {
    ClassSpec {
        name,
        rows: 10,
        mean: 0.5,
        variance: 0.25,
        ml_range: (0.0, 1.0),
        ml_freqs: [0.25, 0.75],
        map_range: (-1.0, 1.0),
        map_freqs: [1.0],
    }
}

/// Asserts that `got` is `Err(want)` and that its message cites invariant `n` and
/// holds `needle`.
fn fails(got: Result<(), Violation>, want: Violation, n: u8, needle: &str) {
    assert_eq!(got, Err(want));
    let msg = want.to_string();
    let cite = std::format!("DESIGN §1.3 ({n}): ");
    assert!(msg.starts_with(&cite), "{msg}");
    assert!(msg.contains(needle), "{msg}");
}

/// The Bayes head checkers: the shipped head passes, each axis and term violation is
/// reported, and a head checked by hand.
mod bayes;
/// The score checkers: ranges and sums, the exact `OS / K` answer, monotone scores, bad
/// input.
mod scores;
/// The table checkers: valid tables pass; each settings, names, prior and histogram
/// violation is reported.
mod tables;
