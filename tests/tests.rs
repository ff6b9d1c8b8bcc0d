//! The integration tests: one binary (`autotests = false`), one module per area.

// Host metrics and baselines against the numpy / scikit-learn golden files written by
// tools/metrics_reference.py.
#[cfg(feature = "std")]
mod metrics_golden;
