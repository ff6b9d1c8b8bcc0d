//! Conformal class sets (DESIGN §8) from Python: `mlmap.conformal_fit` writes the
//! section, `Table.conformal` describes it and `Table.conformal_sets` computes the sets,
//! through the layer's own `ConformalSpec` (the same sets as the device and `mlmap
//! apply`).

use mlmap::host::conformal::{fit, scores, with_conformal};
use mlmap::host::names::Named as _;
use mlmap::host::DynTable;
use mlmap::{set_words, ConformalSpec, Head};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{self, value_error, Rows};
use crate::errors::table_error;
use crate::table::PyTable;

/// The logits `(N, K)` and objectness of a call, in the layer's precision.
fn rows_f32(
    table: &DynTable,
    logits: &Bound<'_, PyAny>,
    objectness: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Vec<f32>, Vec<f32>)> {
    let x = arrays::logits(logits, "logits")?;
    let k = table.k();
    if x.cols != k {
        return Err(value_error(format!(
            "logits: has {} columns; the table has {k} classes",
            x.cols
        )));
    }
    let n = x.rows;
    let os = arrays::objectness(objectness, "objectness", n)?;
    let (rows, col) = (x.rows()?, os.column()?);
    let xs: Vec<f32> = match rows {
        Rows::F32(v) => v.to_vec(),
        Rows::F64(v) => v.iter().map(|&a| a as f32).collect(),
    };
    Ok((xs, (0..n).map(|i| col.get_f32(i)).collect()))
}

pub(crate) fn spec<'a>(bytes: &'a [u8], table: &'a DynTable) -> PyResult<ConformalSpec<'a>> {
    ConformalSpec::from_bytes(bytes, &table.view())
        .map_err(|e| table_error(format!("conformal section: {e}")))
}

#[pymethods]
impl PyTable {
    /// The conformal section (docs/DESIGN.md §8): `{"head", "alpha", "thresholds",
    /// "calibration_rows"}` (a threshold of `-inf`: the class is in every set), or None.
    #[getter]
    fn conformal<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        if mlmap::section_of(&self.bytes, mlmap::CONFORMAL_MAGIC).is_none() {
            return Ok(None);
        }
        let s = spec(&self.bytes, &self.table)?;
        let d = PyDict::new(py);
        d.set_item("head", s.head().name())?;
        d.set_item("alpha", s.alpha())?;
        let k = s.k();
        let t: Vec<f32> = (0..k).map(|c| s.threshold(c).unwrap_or(f32::NAN)).collect();
        let n: Vec<u32> = (0..k).map(|c| s.calibration_rows(c).unwrap_or(0)).collect();
        d.set_item("thresholds", t)?;
        d.set_item("calibration_rows", n)?;
        Ok(Some(d))
    }

    /// The conformal sets of `logits` `(N, K)` (objectness `None`, a number or `(N,)`)
    /// from the table file's conformal section: a boolean `(N, K)` array, `True` where
    /// the class is in the row's set (its score from the section's head at or above its
    /// threshold). An all-`False` row with the open head means "not a known object".
    #[pyo3(signature = (logits, objectness=None))]
    fn conformal_sets<'py>(
        &self,
        py: Python<'py>,
        logits: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<bool>>> {
        if mlmap::section_of(&self.bytes, mlmap::CONFORMAL_MAGIC).is_none() {
            return Err(value_error(
                "the table has no conformal section: fit one with mlmap.conformal_fit",
            ));
        }
        let s = spec(&self.bytes, &self.table)?;
        let (x, os) = rows_f32(&self.table, logits, objectness)?;
        let k = self.table.k();
        let view = self.table.view();
        let mut scratch =
            vec![0.0f32; self.table.bayes_head().map_or(k, |b| b.categories()).max(k)];
        let mut sc = vec![0.0f32; k];
        let mut mask = vec![0u32; set_words(k)];
        let mut out = Vec::with_capacity(os.len());
        for (i, (row, &o)) in x.chunks_exact(k).zip(&os).enumerate() {
            s.score_set(&view, row, o, &mut sc, &mut scratch, &mut mask)
                .map_err(|e| value_error(format!("logits: row index {i}: {e}")))?;
            out.push(
                (0..k)
                    .map(|c| mask.get(c / 32).is_some_and(|w| w >> (c % 32) & 1 == 1))
                    .collect::<Vec<bool>>(),
            );
        }
        if out.is_empty() {
            return Ok(PyArray2::zeros(py, [0, k], false));
        }
        PyArray2::from_vec2(py, &out).map_err(|e| value_error(e.to_string()))
    }
}

/// Fits the thresholds of the conformal sets (docs/DESIGN.md §8) on labelled calibration
/// rows and returns the table file's bytes with its conformal section: what `mlmap
/// conformal` writes for the same rows, alpha and head. `labels` `(N,)` are class
/// indices, `-1` for background (not calibration rows).
#[pyfunction]
#[pyo3(signature = (table, logits, labels, objectness=None, *, alpha, head="map"))]
pub fn conformal_fit(
    table: &Bound<'_, PyAny>,
    logits: &Bound<'_, PyAny>,
    labels: &Bound<'_, PyAny>,
    objectness: Option<&Bound<'_, PyAny>>,
    alpha: f64,
    head: &str,
) -> PyResult<Vec<u8>> {
    let data: Vec<u8> = table.call_method0("to_bytes")?.extract()?;
    let t = DynTable::from_bytes(&data).map_err(|e| table_error(e.to_string()))?;
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(arrays::out_of_range("alpha", &alpha.to_string(), "(0, 1)"));
    }
    let head = Head::from_name(head).map_err(|e| value_error(format!("head: {e}")))?;
    let has = match head {
        Head::Ml | Head::Map => true,
        Head::Bayes => t.bayes_head().is_some(),
        Head::Open => t.open_params().is_some(),
    };
    if !has {
        return Err(value_error(format!("head: the table has no {head} head")));
    }
    let (x, os) = rows_f32(&t, logits, objectness)?;
    let k = t.k();
    let y = arrays::labels(labels, "labels", os.len(), k)?;
    let y: Vec<Option<usize>> = y.iter().map(|&v| usize::try_from(v).ok()).collect();
    let s = scores(&t, head, &x, &os)
        .map_err(|(i, e)| value_error(format!("logits: row index {i}: {e}")))?;
    let f = fit(head, alpha, k, &s, &y);
    let out = with_conformal(&data, &f).map_err(|e| value_error(e.to_string()))?;
    spec(&out, &t)?;
    Ok(out)
}
