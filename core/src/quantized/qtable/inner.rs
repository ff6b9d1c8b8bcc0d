//! One validated quantized section over any storage of its per-class records
//! ([`QTableInner`]): the fixed-size [`QTable`], the host's `DynQTable` and the C API's
//! [`LentQTable`] are this type with arrays, vectors or lent slices, and share its
//! accessors and scoring.

use core::marker::PhantomData;

use super::*;

/// The codes of a section whose code width is known only at run time: the checked
/// [`QTableInner::score_into`] takes `i8` or `i16` codes, and
/// [`QTableInner::score_i32_into`] any `i32` in the section's code range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AnyCode;

/// A validated quantized section, borrowed from its bytes (`'a`), with its per-class
/// records in `C` and its per-logit records (Bayes head) in `L`, each a storage of
/// [`QClass`] and [`QLogit`] records. `Q` is the code type a fixed-size table is built
/// for, or [`AnyCode`].
///
/// Three storages are named:
///
/// * [`QTable<K, Q>`](QTable): arrays of K records, for codes of type `Q` known at
///   compile time (allocation-free; the typed heads [`QTable::ml`] …);
/// * `DynQTable` (feature `alloc`): vectors, for host tools;
/// * [`LentQTable`]: slices the caller lends, for a K known only at run time without
///   allocation (the C API's arena).
///
/// All of them read the section with the same parser, hold the same records and score
/// through the same code, so their scores are equal bit for bit.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::lent::{LentQTable, EMPTY_QCLASS, EMPTY_QLOGIT};
/// use mlmap::{Head, QTable};
///
/// let bytes = include_bytes!("../../../../tables/default_q8.mlmap");
/// let fixed = QTable::<3, i8>::from_bytes(bytes)?;
/// let (mut classes, mut logits) = ([EMPTY_QCLASS; 3], [EMPTY_QLOGIT; 3]);
/// let lent = LentQTable::from_bytes(bytes, &mut classes, &mut logits)?;
/// // One set of accessors, one scoring path.
/// assert_eq!((fixed.k(), fixed.bits()), (lent.k(), lent.bits()));
/// let mut scratch = [0.0; 7];
/// let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
/// fixed.score_into(Head::Bayes, &[50i8, -20, 10], 0.9, &mut a, &mut scratch)?;
/// lent.score_into(Head::Bayes, &[50i8, -20, 10], 0.9, &mut b, &mut scratch)?;
/// assert_eq!(a, b);
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QTableInner<'a, C, L, Q = AnyCode> {
    pub(crate) meta: Meta<'a>,
    pub(crate) classes: C,
    pub(crate) logits: L,
    pub(crate) code: PhantomData<Q>,
}

impl<'a, C, L, Q> QTableInner<'a, C, L, Q> {
    /// A section's records, parsed into `classes` and `logits`.
    #[inline(always)]
    pub(crate) const fn new(meta: Meta<'a>, classes: C, logits: L) -> Self {
        Self {
            meta,
            classes,
            logits,
            code: PhantomData,
        }
    }
}

impl<'a, C: AsRef<[QClass<'a>]>, L: AsRef<[QLogit<'a>]>, Q> QTableInner<'a, C, L, Q> {
    /// The section with its records located: the one implementation of the heads.
    #[inline(always)]
    pub(crate) fn view(&self) -> QView<'_, 'a> {
        QView {
            meta: &self.meta,
            classes: self.classes.as_ref(),
            logits: if self.meta.categories > 0 {
                self.logits.as_ref()
            } else {
                &[]
            },
        }
    }

    /// Number of classes K.
    #[inline]
    pub fn k(&self) -> usize {
        self.classes.as_ref().len()
    }

    /// Bits per code: 8 or 16.
    #[inline]
    pub fn bits(&self) -> u8 {
        self.meta.bits
    }

    /// Categories of the Bayes head (K or K + 1; 0 without it).
    #[inline]
    pub fn categories(&self) -> usize {
        usize::from(self.meta.categories)
    }

    /// Whether the section has the Bayes head.
    #[inline]
    pub fn has_bayes(&self) -> bool {
        self.meta.categories > 0
    }

    /// The open head's parameters (DESIGN §1.8), when the section has that head: the
    /// table's temperature, `epsilon` and unknown log-score, as the table decoder
    /// derived them.
    #[inline]
    pub fn open_params(&self) -> Option<OpenParams> {
        self.meta.open
    }

    /// Bins of the ML head.
    #[inline]
    pub fn bins_ml(&self) -> usize {
        usize::from(self.meta.bins_ml)
    }

    /// Bins per logit and categories of the Bayes head (`(0, 0)` without it).
    #[inline]
    pub fn bayes_shape(&self) -> (usize, usize) {
        (usize::from(self.meta.bins_bayes), self.categories())
    }

    /// The quantization of class `c`: `(scale, zero_point)`.
    #[inline]
    pub fn params(&self, c: usize) -> Option<(f32, i32)> {
        self.classes
            .as_ref()
            .get(c)
            .map(|q| (q.scale, q.zero_point))
    }

    /// The windows of codes stored for class (or logit) `c`, as `(first code, count)`:
    /// ML, MAP, and Bayes (`None` without that head).
    pub fn windows(&self, c: usize) -> Option<[Option<(i32, usize)>; 3]> {
        let q = self.classes.as_ref().get(c)?;
        let bayes = self
            .view()
            .logits
            .get(c)
            .map(|l| (l.start, l.index.len() / index_width(self.meta.bins_bayes)));
        Some([
            Some((
                q.ml_start,
                q.ml_index.len() / index_width(self.meta.bins_ml),
            )),
            Some((q.map_start, q.map_masses.len())),
            bayes,
        ])
    }

    /// The checksum of the table the section was computed from (its last four bytes).
    #[inline]
    pub fn table_crc(&self) -> u32 {
        self.meta.table_crc
    }

    /// Length of the section in bytes, trailer included.
    #[inline]
    pub fn section_len(&self) -> usize {
        self.meta.len
    }

    /// Floats of scratch [`QTableInner::score_into`] needs: K plus the Bayes head's
    /// categories (at most `2 K + 1`).
    #[inline]
    pub fn scratch_len(&self) -> usize {
        self.k() + self.categories()
    }

    /// Scores one detection with `head` and the head's default backend (as
    /// [`QTable::ml`], [`QTable::map`], [`QTable::bayes`], [`QTable::open`]): `codes` and
    /// `out` hold K values, `scratch` at least [`QTableInner::scratch_len`] floats.
    ///
    /// # Errors
    ///
    /// [`InferError::CodeWidth`] when `T` is not the section's code width;
    /// [`InferError::Length`] when `codes` or `out` do not hold K values or `scratch` is
    /// short; [`InferError::Objectness`]; [`InferError::NoBayesHead`];
    /// [`InferError::NoOpenHead`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn score_into<T: Code>(
        &self,
        head: Head,
        codes: &[T],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if T::BITS != self.meta.bits {
            return Err(InferError::CodeWidth {
                expected: self.meta.bits,
                found: T::BITS,
            });
        }
        if codes.len() != self.k() {
            return Err(InferError::Length);
        }
        let values = codes.iter().map(|q| q.value());
        self.score_values(head, values, objectness, out, scratch)
    }

    /// [`QTableInner::score_into`] for codes given as `i32` (as host tools read them),
    /// each checked against the section's code range.
    ///
    /// # Errors
    ///
    /// [`InferError::Length`] when `codes` does not hold K values;
    /// [`InferError::CodeRange`] for a code outside the section's code range; otherwise
    /// as [`QTableInner::score_into`].
    ///
    /// # Panics
    ///
    /// Never.
    pub fn score_i32_into(
        &self,
        head: Head,
        codes: &[i32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
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
        self.score_values(head, codes.iter().copied(), objectness, out, scratch)
    }

    /// One detection's K codes, in the code range, through `head`.
    #[inline(always)]
    fn score_values(
        &self,
        head: Head,
        values: impl Iterator<Item = i32> + Clone,
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        let k = self.k();
        if out.len() != k {
            return Err(InferError::Length);
        }
        let view = self.view();
        match head {
            Head::Ml | Head::Map => {
                let scratch = scratch.get_mut(..k).ok_or(InferError::Length)?;
                view.masses_into(head, values, objectness, out, scratch)
            }
            Head::Bayes => {
                let cats = scratch
                    .get_mut(..self.categories())
                    .ok_or(InferError::Length)?;
                view.bayes_into::<BayesBackend>(values, objectness, out, cats)
            }
            Head::Open => {
                let (cats, x) = scratch
                    .get_mut(..self.scratch_len())
                    .and_then(|s| s.split_at_mut_checked(self.categories()))
                    .ok_or(InferError::Length)?;
                view.open_into::<OpenBackend>(values, objectness, out, cats, x)
            }
        }
    }

    /// The dequantized logits of `codes` into `out` (K values each; [`dequantize`] with
    /// each class's scale and zero point): what the scores are exact for, and what the
    /// tie-safe decision compares (DESIGN §1.7), since classes may have different scales.
    ///
    /// # Errors
    ///
    /// [`InferError::CodeWidth`] when `T` is not the section's code width;
    /// [`InferError::Length`] when `codes` or `out` do not hold K values.
    #[inline]
    pub fn logits_into<T: Code>(&self, codes: &[T], out: &mut [f32]) -> Result<(), InferError> {
        if T::BITS != self.meta.bits {
            return Err(InferError::CodeWidth {
                expected: self.meta.bits,
                found: T::BITS,
            });
        }
        if codes.len() != self.k() || out.len() != self.k() {
            return Err(InferError::Length);
        }
        for ((x, q), c) in out.iter_mut().zip(codes).zip(self.classes.as_ref()) {
            *x = dequantize(q.value(), c.scale, c.zero_point);
        }
        Ok(())
    }
}
