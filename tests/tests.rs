//! The integration tests: one binary (`autotests = false`), one module per area.

/// Tolerances, golden files of the numpy reference, and a raw `.mlmap` writer.
mod support;

/// The layer against the numpy goldens, error cases, the batch API, ties, the exact
/// `OS / K` answer, the embedded table, `DynTable` agreement and the fast-math bound.
mod layer;

/// The `.mlmap` format: exact round trips, the reference encoder's bytes, every
/// corruption and truncation rejected, one error per broken invariant, size bounds.
mod format;

/// One proptest property per invariant of DESIGN §1.3, on random tables of three shapes.
mod invariants;
