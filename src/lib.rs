//! ML and MAP prediction layers for object detectors, for firmware: they never
//! allocate, never panic and run in bounded time.
//!
//! A detector's Sigmoid or Softmax layer reports false positives and never-seen objects
//! at 0.95+ confidence. mlmap replaces that layer, after training and without
//! retraining, by the **ML** and **MAP** layers of Melotti et al., "Probabilistic
//! Approach for Road-Users Detection": per-class histograms of training logits as the
//! likelihood, a per-class Gaussian as the prior, additive smoothing, times the
//! objectness. A logit vector unlike anything seen in training gets `OS / K` per class:
//! "I don't know".
//!
//! The library is `#![no_std]` and never uses `alloc`. Tables are fixed-size
//! ([`Table<K, B_ML, B_MAP>`](Table)) and reach the firmware either as bytes decoded at
//! start-up or as constants generated at build time. The promises are checked: panic
//! paths by a link-time test, allocation by `nm`, the invariants of every score by
//! property tests and fuzzing (see the README).
//! The mathematics, invariants, file formats and design decisions: `docs/DESIGN.md`.
//!
//! # Decoding a table at start-up
//!
//! ```
//! use mlmap::Table;
//!
//! // E.g. a calibration flash sector, updatable without reflashing the code.
//! static TABLE_BYTES: &[u8] = include_bytes!("../tables/default.mlmap");
//!
//! let table = Table::<3, 22, 17, 22, 4>::from_bytes(TABLE_BYTES)?; // CRC + invariants checked
//! let scores = table.map(&[5.1, -2.0, -1.3], 0.93)?;
//! let class = table.class_name(scores.argmax());
//! # assert!(class.is_some());
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```
//!
//! # Using the table embedded at build time
//!
//! ```
//! use mlmap::embedded::TABLE;
//!
//! let scores = TABLE.ml(&[5.1, -2.0, -1.3], 0.93)?; // no decoding, no copy
//! assert!((scores.0.iter().sum::<f32>() - 0.93).abs() < 1e-5);
//! # Ok::<(), mlmap::InferError>(())
//! ```
//!
//! # Features
//!
//! * `micromath`: adds the `Micromath` backend, micromath's `exp`
//!   (`table.map_with::<Micromath>(..)`). The faster and more accurate [`FastMath`]
//!   backend, the crate's own `exp`, needs no feature.
//! * `defmt`: `defmt::Format` for every public type.
//! * `std`: the host module [`host`] (fitting, datasets, metrics, [`DynTable`](host::DynTable)).
//! * `cli`: the `mlmap` companion binary.
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

#[cfg(feature = "std")]
extern crate std;

pub use mlmap_core::baseline;
/// LiDAR range-view and reflectance-view maps (docs/DESIGN.md §9).
pub use mlmap_core::lidar;
pub use mlmap_core::{
    argmax, check_class_name, check_class_names, decide, locate_malformed, objectness_logit,
    refused_char, scores_from_evidence, ArrayStorage, Axis, Backend, BatchError, BayesBackend,
    BayesView, BodyPart, Bounded, BoundedExtent, BoundedStorage, BoundedTable, CharKind, ClassName,
    ClassSpec, DecodeError, EdgeMode, EncodeError, Gaussian, GaussianError, Head, Histogram,
    HistogramError, InferError, Items, Knot, Libm, MapBackend, MapError, NameError, OpenBackend,
    OpenParams, RecalMap, Scores, Settings, Storage, Table, TableError, TableInner, TableView,
    UpperTail, FORMAT_VERSION, FREQUENCY_SUM_TOLERANCE, MAGIC, MAX_EPSILON, MAX_KNOTS, MAX_LAMBDA,
    MAX_LAMBDA_BAYES, MAX_TEMPERATURE, MIN_TEMPERATURE, NAME_MAX, NAME_RULE_VERSION,
    VARIANCE_FLOOR,
};

pub mod embedded;
#[cfg(feature = "invariants")]
#[cfg_attr(docsrs, doc(cfg(feature = "invariants")))]
pub mod invariants;

/// Decoding into storage the caller lends, of exactly the table's size (the C API's
/// arena); see [`lent::LentTable`].
pub use mlmap_core::lent;

#[doc(hidden)]
pub use mlmap_core::__embed;

// The quantized table (int8 / int16 logits).
pub use mlmap_core::{
    code_range, dequantize, quantize_into, quantized_len, AnyCode, Code, QField, QParams, QTable,
    QTableError, QTableInner, QuantizeError, MAX_LOG_TERM, MAX_MASS, QUANTIZED_MAGIC,
    QUANTIZED_VERSION,
};

// Runtime safety: the drift monitor (DESIGN §7), the conformal class sets (DESIGN §8)
// and the sections appended to a table.
pub use mlmap_core::{
    conformal_section_len, set_words, threshold_rank, write_conformal_section, ConformalError,
    ConformalSpec, CONFORMAL_MAGIC, CONFORMAL_VERSION,
};
pub use mlmap_core::{
    monitor_section_len, section_of, table_of, write_monitor_section, Accumulators, Alarms,
    Monitor, MonitorError, MonitorParams, MonitorSpec, MonitorState, Thresholds, WindowReport,
    WindowSummary, MONITOR_MAGIC, MONITOR_VERSION, REFERENCE_SUM_TOLERANCE,
};

pub use mlmap_core::{
    fast_math_max_score_error, FastMath, FAST_MATH_MAX_REL_ERROR, FAST_MATH_MAX_SCORE_ERROR,
};
#[cfg(feature = "micromath")]
#[cfg_attr(docsrs, doc(cfg(feature = "micromath")))]
pub use mlmap_core::{Micromath, MICROMATH_MAX_SCORE_ERROR};

/// The host side (feature `std`): datasets, fitting, baselines, metrics, tuning,
/// evaluation and export, in `f64`, allocating, never panicking on bad input. It is the
/// crate `mlmap-host`, built on the same core as the layer, so the scores it reports
/// are the device's; the `mlmap` binary and the Python package both call it.
#[cfg(feature = "std")]
#[cfg_attr(docsrs, doc(cfg(feature = "std")))]
pub use mlmap_host as host;

/// The README's Rust examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
