//! Checkers for the invariants of DESIGN §1.3, written against the public API only.
//!
//! The property tests and the fuzz targets of this crate check every score and every
//! table they meet with these functions, so that both test the very same rules. They are
//! a test aid behind the feature `invariants`, outside the crate's API and its semver
//! promise: a table the layer accepts already satisfies every table invariant. Each checker returns
//! `Ok(())` or the first [`Violation`] it finds, whose message names the invariant (its
//! number in DESIGN §1.3), the class and the values. They never allocate and never panic.
//!
//! | invariant | checker |
//! |---|---|
//! | 1, scores in `[0, OS]` summing to `OS` | [`check_scores`] with [`Sum::Equal`] |
//! | 2, "I don't know" is exactly `OS / K` | [`check_unknown`] |
//! | 3, more evidence never lowers a score | [`check_monotone`] |
//! | 4, bad input is an error | [`check_error`] (and [`expected_error`]) |
//! | 5, table invariants | [`check_table`], `check_dyn_table` (feature `std`), and the parts: [`check_settings`], [`check_names`], [`check_prior`], [`check_histogram`], [`check_bins`] |
//! | §1.6, the Bayes head's table invariants | [`check_bayes`] (called by [`check_table`] and `check_dyn_table`), and the parts: [`check_bayes_axis`], [`check_bayes_terms`] |
//! | §1.6, its scores | [`check_scores`] with [`Sum::Equal`] (no background) or [`Sum::AtMost`] ([`bayes_sum`] picks), [`check_prior_share`] without evidence, [`check_error`] |
//!
//! | §1.8, the open head's scores | [`check_scores`] with [`Sum::AtMost`], [`check_open_decision`], [`open_reference`] within [`open_score_tolerance`] ([`open_mismatch`]), [`check_error`] |
//!
//! The Bayes head's violations cite DESIGN §1.6 instead of §1.3, the open head's §1.8.
//!
//! ```
//! use mlmap::invariants::{
//!     bayes_sum, check_prior_share, check_scores, check_table, check_unknown, Sum,
//! };
//! use mlmap::Table;
//!
//! let table = Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("../../tables/default.mlmap"))?;
//! check_table(&table)?;
//! let scores = table.map(&[5.1, -2.0, -1.3], 0.93)?;
//! check_scores(&scores.0, 0.93, Sum::Equal)?;
//! // Far outside every histogram: the "I don't know" answer.
//! let unknown = table.ml(&[1e30, 1e30, 1e30], 0.93)?;
//! check_unknown(&unknown.0, 0.93)?;
//! // The Bayes head: its sum rule, and the prior's shares without evidence.
//! let head = table.bayes_head().ok_or("the shipped table has a Bayes head")?;
//! let scores = table.bayes(&[5.1, -2.0, -1.3], 0.93)?;
//! check_scores(&scores.0, 0.93, bayes_sum(&head))?;
//! let unknown = table.bayes(&[1e30, 1e30, 1e30], 0.93)?;
//! check_prior_share(&unknown.0, 0.93, &head)?;
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use core::fmt;

use crate::{
    BayesView, Head, Histogram, InferError, Settings, Table, FAST_MATH_MAX_REL_ERROR,
    FREQUENCY_SUM_TOLERANCE, MAX_LAMBDA, MAX_LAMBDA_BAYES, NAME_MAX,
};

/// Relative tolerance of the sum of the scores against `OS` (DESIGN §1.3 (1)).
pub const SUM_RELATIVE_TOLERANCE: f64 = 1e-5;

/// The smallest positive `f32` (a subnormal), `2^-149`. A score below `f32::MIN_POSITIVE`
/// has no relative precision left and carries up to this much absolute rounding, so
/// [`check_scores`] allows `K` times this on top of the relative tolerance (it matters
/// only for `OS` below about `1e-38`).
pub const SUBNORMAL_STEP: f64 = 1.401_298_464_324_817e-45;

/// How the scores of a head must add up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sum {
    /// The scores sum to `OS` within [`SUM_RELATIVE_TOLERANCE`]: the ML and MAP heads,
    /// whose categories are exactly the `K` classes.
    Equal,
    /// The scores sum to at most `OS` (within the same tolerance): a head with a
    /// background category, whose share of `OS` is not a class score.
    AtMost,
}

mod bayes;
mod open;
mod scores;
mod table;
mod violation;

pub use bayes::*;
pub use open::*;
pub use scores::*;
pub use table::*;
pub use violation::*;

#[cfg(test)]
mod tests;
