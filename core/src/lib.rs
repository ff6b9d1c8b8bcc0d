//! The `#![no_std]` core of [mlmap](https://docs.rs/mlmap): validated tables, the
//! `.mlmap` file format, and the arithmetic of every head. It never allocates (the
//! `alloc` feature adds [`DynTable`], for host tools and build scripts) and never panics.
//!
//! Use it through the `mlmap` crate, which re-exports every item here; this crate exists
//! so that `mlmap`'s build script decodes and validates an embedded table with exactly
//! the code the layer runs (docs/DESIGN.md §5).
#![no_std]
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
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

#[cfg(feature = "alloc")]
extern crate alloc;
#[cfg(test)]
extern crate std;

pub mod baseline;
mod bayes;
mod bounded;
mod conformal;
#[cfg(feature = "defmt")]
mod defmt_impls;
#[cfg(feature = "defmt")]
mod defmt_sections;
#[cfg(feature = "defmt")]
mod defmt_storage;
#[cfg(feature = "alloc")]
mod dyn_table;
#[doc(hidden)]
#[cfg(feature = "alloc")]
pub mod __embed_source {
    //! Build-script support: see `embed.rs`.
    pub use crate::embed_source::{quantized_source, rust_source};
}
#[doc(hidden)]
pub mod __embed {
    //! `const` constructors for build-script output; not part of the API.
    pub use crate::embed::{
        axis, class_name, gaussian, histogram, knot, open, part, part4, part8, qclass, qlogit,
        qmeta, qtable, table, QLOGIT_NONE,
    };
}
mod embed;
#[cfg(feature = "alloc")]
mod embed_source;
mod error;
mod fastmath;
mod gaussian;
mod histogram;
mod layer;
pub mod lent;
pub mod lidar;
mod math;
mod monitor;
mod name;
mod open;
mod qtable;
mod qtable_build;
#[cfg(feature = "alloc")]
mod qtable_dyn;
mod recal;
mod sections;
mod table;
mod view;
mod wire;

pub use bayes::{objectness_logit, BayesView, MAX_LAMBDA_BAYES};
pub use bounded::{Bounded, BoundedTable};
pub use conformal::{
    conformal_section_len, set_words, threshold_rank, write_conformal_section, ConformalError,
    ConformalSpec, CONFORMAL_MAGIC, CONFORMAL_VERSION,
};
pub use error::{BatchError, DecodeError, EncodeError, Head, InferError, MapError, TableError};
pub use gaussian::{Gaussian, GaussianError, VARIANCE_FLOOR};
pub use histogram::{
    Axis, EdgeMode, Histogram, HistogramError, UpperTail, FREQUENCY_SUM_TOLERANCE,
};
pub use layer::{argmax, decide, scores_from_evidence, Scores};
pub use math::{Backend, Libm};
pub use monitor::{
    monitor_section_len, write_monitor_section, Accumulators, Alarms, Monitor, MonitorError,
    MonitorParams, MonitorSpec, MonitorState, Thresholds, WindowReport, WindowSummary,
    MONITOR_MAGIC, MONITOR_VERSION, REFERENCE_SUM_TOLERANCE,
};
pub use name::{
    check_class_name, check_class_names, refused_char, CharKind, ClassName, NameError, NAME_MAX,
    NAME_RULE_VERSION,
};
pub use open::{OpenParams, MAX_EPSILON, MAX_TEMPERATURE, MIN_TEMPERATURE};
pub use qtable::{
    code_range, dequantize, Code, QField, QTable, QTableError, MAX_LOG_TERM, MAX_MASS,
    QUANTIZED_MAGIC, QUANTIZED_VERSION,
};
pub use qtable_build::{quantize_into, quantized_len, QParams, QuantizeError};
pub use recal::{Knot, RecalMap, MAX_KNOTS};
pub use sections::{section_of, table_of};
pub use table::Table;
pub use view::TableView;
pub use wire::{ClassSpec, Settings, FORMAT_VERSION, MAGIC, MAX_LAMBDA};

#[cfg(feature = "alloc")]
#[cfg_attr(docsrs, doc(cfg(feature = "alloc")))]
pub use dyn_table::{BayesSpec, DynTable};
#[cfg(feature = "alloc")]
#[cfg_attr(docsrs, doc(cfg(feature = "alloc")))]
pub use qtable_dyn::DynQTable;

pub use fastmath::{
    fast_math_max_score_error, FastMath, FAST_MATH_MAX_REL_ERROR, FAST_MATH_MAX_SCORE_ERROR,
};
#[cfg(feature = "micromath")]
#[cfg_attr(docsrs, doc(cfg(feature = "micromath")))]
pub use fastmath::{Micromath, MICROMATH_MAX_SCORE_ERROR};
