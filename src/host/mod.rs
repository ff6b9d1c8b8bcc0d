//! Host-side tools (feature `std`): datasets, fitting, baselines, metrics, tuning and
//! evaluation.
//!
//! Everything here runs on a workstation in `f64`, may allocate, and never panics on
//! bad input: errors name the file, line and column involved. Scores of the ML and MAP
//! heads always come from the layer itself (through [`DynTable`]), so the host reports
//! exactly what the device computes.
//!
//! The pipelines of the `mlmap` commands live here ([`eval::evaluate`],
//! [`tune::tune`]), so they can be called without the binary.

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

#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod plots;
