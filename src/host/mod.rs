//! Host-side tools (feature `std`): datasets, fitting, baselines, metrics, tuning.
//!
//! Everything here runs on a workstation in `f64`, may allocate, and never panics on
//! bad input: errors name the file, line and column involved. Scores of the ML and MAP
//! heads always come from the layer itself (through [`DynTable`]), so the host reports
//! exactly what the device computes.

pub use mlmap_core::{BayesSpec, DynTable};

pub mod baselines;
pub mod dataset;
pub mod export;
pub mod fit;
pub mod metrics;
pub mod tune;

#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod plots;
