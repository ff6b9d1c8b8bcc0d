//! The host side of mlmap: datasets, fitting, baselines, metrics, tuning, evaluation
//! and export, with std.
//!
//! Everything here runs on a workstation in `f64`, may allocate, and never panics on
//! bad input: errors name the file, line and column involved. Scores of the ML and MAP
//! heads always come from the layer itself (`mlmap-core`, through [`DynTable`]), so the
//! host reports exactly what the device computes.
//!
//! The pipelines of the `mlmap` commands live here ([`eval::evaluate`],
//! [`tune::tune`]), so they can be called without the binary; the Python package calls
//! the same code ([`fit::parts`]: a fit over row ranges read at the same time).
//!
//! The crate is the root crate's module `mlmap_core::host` (feature `std`); it depends on
//! `mlmap-core` alone, never on the root crate.
//!
//! # Features
//!
//! * `plots`: SVG plots of tables and calibration ([`plots`]), for the `mlmap` binary.
#![cfg_attr(docsrs, feature(doc_cfg))]
#![forbid(unsafe_code)]
// `!(a < b)` is deliberate throughout: it is true for NaN, which must be rejected.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub use self::error::HostError;
pub use mlmap_core::{BayesSpec, DynQTable, DynTable, VecStorage};

pub mod baselines;
pub mod conformal;
pub mod data;
pub mod dataset;
mod error;
pub mod escape;
pub mod eval;
pub mod export;
pub mod fit;
pub mod lidar;
pub mod metrics;
pub mod monitor;
pub mod names;
pub mod tune;

pub use self::error::fit_message;

/// Helpers of the unit tests.
#[cfg(test)]
pub(crate) mod testing {
    /// A pseudo-random sequence in [0, 1) (64-bit LCG), for reproducible test data.
    pub(crate) fn lcg(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }
}

#[cfg(feature = "plots")]
#[cfg_attr(docsrs, doc(cfg(feature = "plots")))]
pub mod plots;
