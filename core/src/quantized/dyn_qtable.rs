//! A quantized section whose number of classes and code width are known only at run
//! time (feature `alloc`), for host tools: the same parser, validation and heads as
//! [`QTable`](crate::QTable), with the per-class data located in vectors.

use alloc::vec::Vec;

use crate::quantized::qtable::{locate, parse, QClass, QLogit, QTableError, QTableInner};

/// A validated quantized section with a run-time number of classes and code width.
///
/// Same bytes, same checks and same scores as [`QTable`](crate::QTable); the codes are
/// given as `i32` and checked against the section's code range.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::{quantize_into, DynQTable, DynTable, Head, QParams};
///
/// let table = DynTable::from_bytes(include_bytes!("../../../tables/default.mlmap"))?;
/// let params = QParams { bits: 16, scales: &[0.01; 3], zero_points: &[0; 3], bayes: false };
/// let mut buf = vec![0u8; mlmap::quantized_len(&table.view(), &params)?];
/// let q = DynQTable::from_bytes(quantize_into(&table.view(), &params, &mut buf)?)?;
/// let mut out = [0.0; 3];
/// let codes = [400, -160, 80];
/// let mut scratch = vec![0.0; q.scratch_len()];
/// q.score_i32_into(Head::Map, &codes, 0.9, &mut out, &mut scratch)?;
/// // The f32 table on the dequantized logits, bit for bit.
/// let x = codes.map(|q| mlmap::dequantize(q, 0.01, 0));
/// let mut want = [0.0; 3];
/// table.view().score_into(Head::Map, &x, 0.9, &mut want, &mut [0.0; 3])?;
/// assert_eq!(out, want);
/// assert!(q.score_i32_into(Head::Ml, &[40_000, 0, 0], 0.9, &mut out, &mut scratch).is_err());
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
pub type DynQTable<'a> = QTableInner<'a, Vec<QClass<'a>>, Vec<QLogit<'a>>>;

impl<'a> QTableInner<'a, Vec<QClass<'a>>, Vec<QLogit<'a>>> {
    /// Reads the quantized section of `bytes` (alone, or appended to its table), with
    /// the checks of [`QTable::from_bytes`](crate::QTable::from_bytes) but any K and
    /// code width.
    ///
    /// # Errors
    ///
    /// As [`QTable::from_bytes`](crate::QTable::from_bytes), without
    /// [`QTableError::ShapeMismatch`].
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, QTableError> {
        let (section, table) = locate(bytes)?;
        let (mut classes, mut logits) = (Vec::new(), Vec::new());
        let meta = parse(
            section,
            table,
            |_, c| classes.push(c),
            |_, l| logits.push(l),
        )?;
        Ok(Self::new(meta, classes, logits))
    }
}
