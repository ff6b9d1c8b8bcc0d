//! A quantized section whose number of classes and code width are known only at run
//! time (feature `alloc`), for host tools: the same parser, validation and heads as
//! [`QTable`](crate::QTable), with the per-class data located in vectors.

use alloc::vec::Vec;

use crate::diagnostics::error::{Head, InferError};
use crate::heads::open::OpenParams;
use crate::quantized::qtable::{code_range, locate, parse, QClass, QLogit, QTableError, QView};
use crate::storage::view::{BayesBackend, OpenBackend};

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
/// q.score_into(Head::Map, &codes, 0.9, &mut out)?;
/// // The f32 table on the dequantized logits, bit for bit.
/// let x = codes.map(|q| mlmap::dequantize(q, 0.01, 0));
/// let mut want = [0.0; 3];
/// table.view().score_into(Head::Map, &x, 0.9, &mut want, &mut [0.0; 3])?;
/// assert_eq!(out, want);
/// assert!(q.score_into(Head::Ml, &[40_000, 0, 0], 0.9, &mut out).is_err());
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct DynQTable<'a> {
    pub(crate) meta: crate::quantized::qtable::Meta<'a>,
    pub(crate) classes: Vec<QClass<'a>>,
    pub(crate) logits: Vec<QLogit<'a>>,
}

impl<'a> DynQTable<'a> {
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
        Ok(Self {
            meta,
            classes,
            logits,
        })
    }

    fn view(&self) -> QView<'_, 'a> {
        QView {
            meta: &self.meta,
            classes: &self.classes,
            logits: &self.logits,
        }
    }

    /// Number of classes K.
    pub fn k(&self) -> usize {
        self.classes.len()
    }

    /// Bits per code: 8 or 16.
    pub fn bits(&self) -> u8 {
        self.meta.bits
    }

    /// Whether the section has the Bayes head.
    pub fn has_bayes(&self) -> bool {
        !self.logits.is_empty()
    }

    /// The open head's parameters (DESIGN §1.8), when the section has that head.
    pub fn open_params(&self) -> Option<OpenParams> {
        self.meta.open
    }

    /// Bins of the ML head.
    pub fn bins_ml(&self) -> usize {
        usize::from(self.meta.bins_ml)
    }

    /// Bins per logit and categories of the Bayes head (`(0, 0)` without it).
    pub fn bayes_shape(&self) -> (usize, usize) {
        (
            usize::from(self.meta.bins_bayes),
            usize::from(self.meta.categories),
        )
    }

    /// The checksum of the table the section was computed from.
    pub fn table_crc(&self) -> u32 {
        self.meta.table_crc
    }

    /// Length of the section in bytes, trailer included.
    pub fn section_len(&self) -> usize {
        self.meta.len
    }

    /// The quantization of class `c`: `(scale, zero_point)`.
    pub fn params(&self, c: usize) -> Option<(f32, i32)> {
        self.classes.get(c).map(|q| (q.scale, q.zero_point))
    }

    /// The windows of codes stored for class (or logit) `c`, as `(first code, count)`:
    /// ML, MAP, and Bayes (`None` without that head).
    pub fn windows(&self, c: usize) -> Option<[Option<(i32, usize)>; 3]> {
        let q = self.classes.get(c)?;
        let wide = |bins: u16| crate::quantized::qtable::index_width(bins);
        let bayes = self
            .logits
            .get(c)
            .map(|l| (l.start, l.index.len() / wide(self.meta.bins_bayes)));
        Some([
            Some((q.ml_start, q.ml_index.len() / wide(self.meta.bins_ml))),
            Some((q.map_start, q.map_masses.len())),
            bayes,
        ])
    }

    /// Scores one detection with `head` (the Bayes and open heads' `exp` with the backend
    /// of [`Table::bayes`](crate::Table::bayes) and [`Table::open`](crate::Table::open)):
    /// `codes` and `out` hold K values.
    ///
    /// # Errors
    ///
    /// [`InferError::Length`] when `codes` or `out` do not have K entries;
    /// [`InferError::CodeRange`] for a code outside the section's code range;
    /// [`InferError::Objectness`]; [`InferError::NoBayesHead`];
    /// [`InferError::NoOpenHead`].
    pub fn score_into(
        &self,
        head: Head,
        codes: &[i32],
        objectness: f32,
        out: &mut [f32],
    ) -> Result<(), InferError> {
        if codes.len() != self.k() {
            return Err(InferError::Length);
        }
        let (lo, hi) = code_range(self.meta.bits);
        if let Some(c) = codes.iter().position(|q| !(lo..=hi).contains(q)) {
            return Err(InferError::CodeRange {
                class: u16::try_from(c).unwrap_or(u16::MAX),
            });
        }
        let codes = codes.iter().copied();
        let view = self.view();
        match head {
            Head::Ml | Head::Map => {
                let mut scratch = alloc::vec![0.0f32; self.k()];
                view.masses_into(head, codes, objectness, out, &mut scratch)
            }
            Head::Bayes => {
                let mut scratch = alloc::vec![0.0f32; usize::from(self.meta.categories)];
                view.bayes_into::<BayesBackend>(codes, objectness, out, &mut scratch)
            }
            Head::Open => {
                let mut scratch = alloc::vec![0.0f32; usize::from(self.meta.categories)];
                let mut x = alloc::vec![0.0f32; self.k()];
                view.open_into::<OpenBackend>(codes, objectness, out, &mut scratch, &mut x)
            }
        }
    }
}
