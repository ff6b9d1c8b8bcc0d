//! `Table.quantized_scores`: integer logit codes scored through the table file's
//! quantized section (DESIGN §6.19), as `mlmap apply --quantized` scores them.

use mlmap::host::DynQTable;
use mlmap::InferError;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

use crate::arrays::{self, value_error};
use crate::table::{parse_head, PyTable};

#[pymethods]
impl PyTable {
    /// `(N, K)` float32 scores of `head` for integer logit codes, through the table's
    /// quantized section (`mlmap quantize`): `codes` is `(N, K)` int8 (an 8-bit section)
    /// or int16 (a 16-bit one), or any integer array of codes in the section's range;
    /// `objectness` as for `ml`. The scores are those of `mlmap apply --quantized`, bit
    /// for bit. A table without a quantized section, a head the section lacks, a code
    /// outside the section's range or a float array raise `ValueError` (a non-integer
    /// array `TypeError`).
    #[pyo3(signature = (head, codes, objectness=None))]
    fn quantized_scores<'py>(
        &self,
        py: Python<'py>,
        head: &str,
        codes: &Bound<'py, PyAny>,
        objectness: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let head = parse_head(head)?;
        let q = DynQTable::from_bytes(&self.bytes).map_err(|e| {
            value_error(format!(
                "the table has no valid quantized section ({e}); write one with \
                 `mlmap quantize`"
            ))
        })?;
        let np = py.import("numpy")?;
        let a = np.call_method1("asarray", (codes,))?;
        let kind: String = a.getattr("dtype")?.getattr("kind")?.extract()?;
        if kind != "i" && kind != "u" {
            let dtype = a.getattr("dtype")?.str()?.to_string();
            return Err(PyTypeError::new_err(format!(
                "codes: dtype {dtype:?} is not an integer dtype; quantized logits are \
                 int8 or int16 codes ({}-bit section)",
                q.bits()
            )));
        }
        // Every code fits in i32; numpy copies only when the dtype or layout differ.
        let a = np.call_method1("require", (a, "int32", "CA"))?;
        let a = a.cast_into::<PyArray2<i32>>().map_err(|_| {
            value_error("codes: expected a 2-D array (N, K): one row per detection")
        })?;
        let k = q.k();
        let (n, cols) = match a.shape() {
            [n, c] => (*n, *c),
            _ => (0, 0),
        };
        if cols != k {
            return Err(value_error(format!(
                "codes: has {cols} columns; the table has {k} classes"
            )));
        }
        let ro = a.readonly();
        let all = ro
            .as_slice()
            .map_err(|_| value_error("codes: numpy did not give a contiguous copy"))?;
        let os = arrays::objectness(objectness, "objectness", n)?;
        let col = os.column()?;
        let mut out = vec![0f32; n * k];
        let mut scratch = vec![0f32; q.scratch_len()];
        let scored = py.detach(|| -> Result<(), (usize, InferError)> {
            for (row, (c, s)) in all.chunks_exact(k).zip(out.chunks_exact_mut(k)).enumerate() {
                q.score_i32_into(head, c, col.get_f32(row), s, &mut scratch)
                    .map_err(|e| (row, e))?;
            }
            Ok(())
        });
        scored.map_err(|(row, e)| match e {
            InferError::NoBayesHead | InferError::NoOpenHead => value_error(format!(
                "the quantized section has no {head} head: {e}",
                head = mlmap::host::names::Named::name(head)
            )),
            InferError::Objectness => value_error(format!("objectness: row index {row}: {e}")),
            _ => value_error(format!("codes: row index {row}: {e}")),
        })?;
        PyArray1::from_vec(py, out).reshape([n, k])
    }
}
