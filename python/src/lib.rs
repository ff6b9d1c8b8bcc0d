//! `mlmap._mlmap`, the extension module of the Python package `mlmap`: tables, scoring
//! numpy arrays through the layer's `f32` code, evaluation, fitting and the mergeable
//! fit statistics, all on the library `mlmap` (feature `std`).
//!
//! Nothing here may panic on input: every array is checked at the boundary
//! (`arrays`) and every failure is a Python exception (`errors`).

#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod arrays;
mod conformal;
mod errors;
mod evaluate;
mod evaluator;
mod fit;
mod monitor;
mod quantized;
mod score;
mod source;
mod table;

use numpy::PyArray1;
use pyo3::prelude::*;

use crate::arrays::{value_error, Rows};

/// The decided class of every row (DESIGN §1.7): the largest score, an exact tie
/// going to the larger logit, then to the lower index. `scores` and `logits` are
/// `(N, K)` float arrays of any order, stride or alignment, K at least 1; returns
/// `(N,)` int64 class indices. A NaN score or logit is a `ValueError`: a NaN is not
/// comparable, so no class could be said to win (DESIGN §6.20).
#[pyfunction]
fn decide<'py>(
    py: Python<'py>,
    scores: &Bound<'py, PyAny>,
    logits: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let s = arrays::logits(scores, "scores")?;
    let x = arrays::logits(logits, "logits")?;
    if (s.rows, s.cols) != (x.rows, x.cols) {
        return Err(value_error(format!(
            "scores have shape ({}, {}) but logits ({}, {})",
            s.rows, s.cols, x.rows, x.cols
        )));
    }
    let k = s.cols;
    if k == 0 {
        return Err(value_error(format!(
            "scores: shape ({}, 0) has no class to decide between",
            s.rows
        )));
    }
    fn nan_at<T: Copy + PartialOrd>(values: &[T], k: usize, what: &str) -> PyResult<()> {
        // `v != v` only for NaN.
        #[allow(clippy::eq_op)]
        match values.iter().position(|&v| v != v) {
            None => Ok(()),
            Some(p) => Err(value_error(format!(
                "{what}: row index {}: the value of class {} is NaN; a decision needs \
                 comparable values",
                p / k,
                p % k
            ))),
        }
    }
    fn pick<S, L>(s: &[S], x: &[L], k: usize) -> PyResult<Vec<i64>>
    where
        S: Copy + PartialOrd,
        L: Copy + PartialOrd,
    {
        nan_at(s, k, "scores")?;
        nan_at(x, k, "logits")?;
        Ok(s.chunks_exact(k)
            .zip(x.chunks_exact(k))
            .map(|(s, x)| mlmap::decide(s, x) as i64)
            .collect())
    }
    let out = match (s.rows()?, x.rows()?) {
        (Rows::F32(s), Rows::F32(x)) => pick(s, x, k),
        (Rows::F32(s), Rows::F64(x)) => pick(s, x, k),
        (Rows::F64(s), Rows::F32(x)) => pick(s, x, k),
        (Rows::F64(s), Rows::F64(x)) => pick(s, x, k),
    }?;
    Ok(PyArray1::from_vec(py, out))
}

/// The extension module.
#[pymodule]
fn _mlmap(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<table::PyTable>()?;
    m.add_class::<monitor::PyMonitor>()?;
    m.add_function(wrap_pyfunction!(monitor::monitor_fit, m)?)?;
    m.add_function(wrap_pyfunction!(conformal::conformal_fit, m)?)?;
    m.add("TableError", m.py().get_type::<errors::TableError>())?;
    m.add_function(wrap_pyfunction!(evaluate::evaluate, m)?)?;
    m.add_class::<evaluator::PyEvaluator>()?;
    m.add_function(wrap_pyfunction!(decide, m)?)?;
    m.add_class::<fit::PyFitStats>()?;
    m.add_class::<fit::PyFitEdges>()?;
    m.add_class::<fit::PyFitCounts>()?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(fit::finish, m)?)?;
    m.add_function(wrap_pyfunction!(fit::tune, m)?)?;
    m.add("FORMAT_VERSION", mlmap::FORMAT_VERSION)?;
    Ok(())
}
