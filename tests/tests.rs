//! The integration tests: one binary (`autotests = false`), one module per area.

/// Tolerances, golden files of the numpy reference, and a raw `.mlmap` writer.
mod support;

/// The layer against the numpy goldens (every front: fixed-size table, `DynTable`, batch),
/// error cases, the batch API, ties, the exact `OS / K` answer, the embedded table and the
/// fast-math bound.
mod layer;

/// The `.mlmap` format: exact round trips, the reference encoder's bytes, every
/// corruption and truncation rejected, one error per broken invariant, size bounds.
mod format;

/// One proptest property per invariant of DESIGN §1.3, on random tables of four shapes,
/// checked by the `mlmap::invariants` checkers that the fuzz targets share.
#[cfg(feature = "invariants")]
mod invariants;

/// The quantized table: its heads against the numpy goldens, bit-for-bit agreement with the
/// f32 heads, size, malformed sections.
#[cfg(feature = "invariants")]
mod quantized;

/// Recalibration maps (DESIGN §1.9): every head after its map against the numpy
/// reference, the version-4 bytes, capacity and rule errors, the map's properties.
#[cfg(feature = "std")]
mod maps;

/// Reading CSV files and NPY directories: valid inputs and every malformed case (DESIGN §2).
#[cfg(feature = "std")]
mod host_data;

/// Fitting tables: golden tables from tools/, MATLAB's bin picker, floors and errors (DESIGN §1.1).
#[cfg(feature = "std")]
mod host_fit;

/// Mergeable fit statistics: shards merged in any order give the bytes of one fit; the
/// exact sums against a big-integer oracle; versioned bytes; in-memory rows.
#[cfg(feature = "std")]
mod host_shards;

/// Host metrics and baselines against the numpy / scikit-learn golden files written by
/// tools/metrics_reference.py.
#[cfg(feature = "std")]
mod metrics_golden;
// The `mlmap` binary run as a user runs it: every subcommand, the demo, and every
// bad-input case (exit code, message naming the file and line, no output left behind).
#[cfg(feature = "cli")]
mod cli;

/// Decisions on ties through the binary: `OS / K` rows go to the class with the largest
/// logit in `apply`'s `*_pred` and in `eval`'s `accuracy` (DESIGN §1.7).
#[cfg(feature = "cli")]
mod cli_decisions;

/// The drift monitor (DESIGN §7) against the numpy reference: training shares, windows,
/// thresholds; the section's checks; counts and PSI properties.
#[cfg(feature = "std")]
mod monitor;

/// The conformal class sets (DESIGN §8) against the numpy reference: thresholds, sets,
/// coverage and the LAC baseline; the section's checks; coverage, monotonicity and
/// empty-set properties.
#[cfg(feature = "std")]
mod conformal;

/// The LiDAR maps (DESIGN §9) against the numpy reference; the filter's properties;
/// the scan, calibration and label readers' errors.
#[cfg(feature = "std")]
mod lidar;
