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

// The module tree follows the architecture (ARCHITECTURE.md): `math` (the numerical
// building blocks), `heads` (the arithmetic of every head), `storage` (where a decoded
// table lives, and the one view it is scored through), `format` (the table format),
// `sections` (what may follow a table), `quantized` (the quantized heads), `lidar` (the
// LiDAR maps) and `diagnostics` (errors and `defmt`). Every public item is re-exported
// here, item by item; `baseline`, `lent` and `lidar` are public modules.
mod diagnostics;
mod format;
mod heads;
pub mod lidar;
mod math;
mod quantized;
mod sections;
mod storage;

pub use math::baseline;
pub use storage::lent;

#[doc(hidden)]
#[cfg(feature = "alloc")]
pub mod __embed_source {
    //! Build-script support: see `format/embed.rs`.
    pub use crate::format::embed_source::{quantized_source, rust_source};
}
#[doc(hidden)]
pub mod __embed {
    //! `const` constructors for build-script output; not part of the API.
    pub use crate::format::embed::{
        axis, class_name, gaussian, histogram, knot, open, part, part4, part8, qclass, qlogit,
        qmeta, qtable, table, QLOGIT_NONE,
    };
}

pub use diagnostics::error::{
    BatchError, BodyPart, DecodeError, EncodeError, Head, InferError, MapError, TableError,
};
pub use format::name::{
    check_class_name, check_class_names, refused_char, CharKind, ClassName, NameError, NAME_MAX,
    NAME_RULE_VERSION,
};
pub use format::wire::{locate_malformed, ClassSpec, Settings, FORMAT_VERSION, MAGIC, MAX_LAMBDA};
pub use heads::bayes::{objectness_logit, BayesBackend, BayesView, MAX_LAMBDA_BAYES};
pub use heads::layer::{argmax, decide, scores_from_evidence, MapBackend, Scores};
pub use heads::open::{OpenBackend, OpenParams, MAX_EPSILON, MAX_TEMPERATURE, MIN_TEMPERATURE};
pub use heads::recal::{Knot, RecalMap, MAX_KNOTS};
pub use math::gaussian::{Gaussian, GaussianError, VARIANCE_FLOOR};
pub use math::histogram::{
    Axis, EdgeMode, Histogram, HistogramError, UpperTail, FREQUENCY_SUM_TOLERANCE,
};
pub use math::{Backend, Libm};
pub use quantized::qtable::{
    code_range, dequantize, AnyCode, Code, QField, QTable, QTableError, QTableInner, MAX_LOG_TERM,
    MAX_MASS, QUANTIZED_MAGIC, QUANTIZED_VERSION,
};
pub use quantized::quantize::{quantize_into, quantized_len, QParams, QuantizeError};
pub use sections::conformal::{
    conformal_section_len, set_words, threshold_rank, write_conformal_section, ConformalError,
    ConformalSpec, CONFORMAL_MAGIC, CONFORMAL_VERSION,
};
pub use sections::monitor::{
    monitor_section_len, write_monitor_section, Accumulators, Alarms, Monitor, MonitorError,
    MonitorParams, MonitorSpec, MonitorState, Thresholds, WindowReport, WindowSummary,
    MONITOR_MAGIC, MONITOR_VERSION, REFERENCE_SUM_TOLERANCE,
};
pub use sections::{section_of, table_of};
pub use storage::bounded::{Bounded, BoundedExtent, BoundedStorage, BoundedTable};
pub use storage::inner::{Items, Storage, TableInner};
pub use storage::table::{ArrayStorage, Table};
pub use storage::view::TableView;

#[cfg(feature = "alloc")]
#[cfg_attr(docsrs, doc(cfg(feature = "alloc")))]
pub use quantized::dyn_qtable::DynQTable;
#[cfg(feature = "alloc")]
#[cfg_attr(docsrs, doc(cfg(feature = "alloc")))]
pub use storage::dyn_table::{BayesSpec, DynTable, VecStorage};

pub use math::fastmath::{
    fast_math_max_score_error, FastMath, FAST_MATH_MAX_REL_ERROR, FAST_MATH_MAX_SCORE_ERROR,
};
#[cfg(feature = "micromath")]
#[cfg_attr(docsrs, doc(cfg(feature = "micromath")))]
pub use math::fastmath::{Micromath, MICROMATH_MAX_SCORE_ERROR};
