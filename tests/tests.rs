//! The integration tests: one binary (`autotests = false`), one module per area.

// Reading CSV files and NPY directories: valid inputs and every malformed case (DESIGN §2).
#[cfg(feature = "std")]
mod host_data;
// Fitting tables: golden tables from tools/, MATLAB's bin picker, floors and errors (DESIGN §1.1).
#[cfg(feature = "std")]
mod host_fit;
// Host metrics and baselines against the numpy / scikit-learn golden files written by
// tools/metrics_reference.py.
#[cfg(feature = "std")]
mod metrics_golden;
// The `mlmap` binary run as a user runs it: every subcommand, the demo, and every
// bad-input case (exit code, message naming the file and line, no output left behind).
#[cfg(feature = "cli")]
mod cli;
