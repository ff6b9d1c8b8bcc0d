//! A quantized section validated once and read in place, with its per-class records in
//! storage the caller lends: for a program that sizes its memory to the section it runs
//! (the C API's quantized arena) and keeps the section's bytes where they are (flash).

use super::*;

/// A validated quantized section whose number of classes and code width are known only
/// at run time, borrowed from its bytes (`'a`), with its per-class and per-logit records
/// in storage the caller lends (`'s`): [`LentQTable::classes_of`] sizes that storage,
/// [`LentQTable::from_bytes`] validates the section and fills it.
///
/// Same bytes, same checks and same scores as [`QTable`] (the heads run the same code):
/// [`LentQTable::score_into`] on `i8` codes of an 8-bit section equals `QTable::<K, i8>`,
/// head for head, bit for bit.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::lent::{LentQTable, EMPTY_QCLASS, EMPTY_QLOGIT};
/// use mlmap::{Head, QTable};
///
/// let bytes = include_bytes!("../../../../tables/default_q8.mlmap");
/// let k = LentQTable::classes_of(bytes)?;
/// let (mut classes, mut logits) = ([EMPTY_QCLASS; 4], [EMPTY_QLOGIT; 4]);
/// let q = LentQTable::from_bytes(bytes, &mut classes[..k], &mut logits[..k])?;
/// let (mut out, mut scratch) = ([0.0; 3], [0.0; 7]);
/// q.score_into(Head::Map, &[50i8, -20, 10], 0.9, &mut out, &mut scratch)?;
/// let fixed = QTable::<3, i8>::from_bytes(bytes)?;
/// assert_eq!(out, fixed.map(&[50, -20, 10], 0.9)?.0);
/// // Codes of another width than the section's are refused.
/// assert!(q.score_into(Head::Ml, &[50i16, -20, 10], 0.9, &mut out, &mut scratch).is_err());
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LentQTable<'s, 'a> {
    meta: Meta<'a>,
    classes: &'s [QClass<'a>],
    logits: &'s [QLogit<'a>],
}

/// A placeholder class record for storage [`LentQTable::from_bytes`] fills.
pub const EMPTY_QCLASS: QClass<'static> = QClass::EMPTY;
/// A placeholder logit record for storage [`LentQTable::from_bytes`] fills.
pub const EMPTY_QLOGIT: QLogit<'static> = QLogit::EMPTY;

impl<'s, 'a> LentQTable<'s, 'a> {
    /// The number of classes K of the quantized section in `bytes` (the section alone or
    /// after its table): the class and logit records [`LentQTable::from_bytes`] needs.
    /// Checks the trailer, the magic, the section's CRC-32 and the version first.
    ///
    /// # Errors
    ///
    /// [`QTableError::NotQuantized`], [`QTableError::Corrupted`],
    /// [`QTableError::UnsupportedVersion`], or [`QTableError::Invalid`] with
    /// [`QField::Shape`] for fewer than 2 classes.
    pub fn classes_of(bytes: &[u8]) -> Result<usize, QTableError> {
        let (section, _) = locate(bytes)?;
        let version = section.get(4).copied().unwrap_or(0);
        if !(QUANTIZED_VERSION_1..=QUANTIZED_VERSION).contains(&version) {
            return Err(QTableError::UnsupportedVersion { found: version });
        }
        let k = section
            .get(8..10)
            .and_then(|b| b.try_into().ok())
            .map_or(0, u16::from_le_bytes);
        if k < 2 {
            return Err(QTableError::Invalid {
                field: QField::Shape,
                class: 0,
            });
        }
        Ok(usize::from(k))
    }

    /// Reads and validates the quantized section of `bytes` (every check of
    /// [`QTable::from_bytes`] but the type's shape), storing its K class records in
    /// `classes` and, with a Bayes head, its K logit records in `logits`. Both must have
    /// room for K ([`LentQTable::classes_of`]); their surplus is left untouched.
    ///
    /// # Errors
    ///
    /// As [`QTable::from_bytes`]; [`QTableError::ShapeMismatch`] (with `expected` the
    /// room lent) when `classes` or `logits` hold fewer than K records.
    ///
    /// # Panics
    ///
    /// Never, whatever the bytes.
    pub fn from_bytes(
        bytes: &'a [u8],
        classes: &'s mut [QClass<'a>],
        logits: &'s mut [QLogit<'a>],
    ) -> Result<Self, QTableError> {
        let k = Self::classes_of(bytes)?;
        let (section, table) = locate(bytes)?;
        let room = classes.len().min(logits.len());
        if room < k {
            return Err(QTableError::ShapeMismatch {
                expected: (
                    u16::try_from(room).unwrap_or(u16::MAX),
                    section.get(5).copied().unwrap_or(0),
                ),
                found: (
                    u16::try_from(k).unwrap_or(u16::MAX),
                    section.get(5).copied().unwrap_or(0),
                ),
            });
        }
        let (Some(classes), Some(logits)) = (classes.get_mut(..k), logits.get_mut(..k)) else {
            return Err(QTableError::Malformed);
        };
        let meta = parse(
            section,
            table,
            |c, v| {
                if let Some(s) = classes.get_mut(c) {
                    *s = v;
                }
            },
            |j, v| {
                if let Some(s) = logits.get_mut(j) {
                    *s = v;
                }
            },
        )?;
        let logits: &'s [QLogit<'a>] = if meta.categories > 0 { logits } else { &[] };
        Ok(Self {
            meta,
            classes,
            logits,
        })
    }

    #[inline(always)]
    fn view(&self) -> QView<'_, 'a> {
        QView {
            meta: &self.meta,
            classes: self.classes,
            logits: self.logits,
        }
    }

    /// Number of classes K.
    #[inline]
    pub fn k(&self) -> usize {
        self.classes.len()
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

    /// The open head's parameters (DESIGN §1.8), when the section has that head.
    #[inline]
    pub fn open_params(&self) -> Option<OpenParams> {
        self.meta.open
    }

    /// The quantization of class `c`: `(scale, zero_point)`.
    #[inline]
    pub fn params(&self, c: usize) -> Option<(f32, i32)> {
        self.classes.get(c).map(|q| (q.scale, q.zero_point))
    }

    /// The checksum of the table the section was computed from.
    #[inline]
    pub fn table_crc(&self) -> u32 {
        self.meta.table_crc
    }

    /// Length of the section in bytes, trailer included.
    #[inline]
    pub fn section_len(&self) -> usize {
        self.meta.len
    }

    /// Floats of scratch [`LentQTable::score_into`] needs: K plus the Bayes head's
    /// categories (at most `2 K + 1`).
    #[inline]
    pub fn scratch_len(&self) -> usize {
        self.k() + self.categories()
    }

    /// Scores one detection with `head`, as [`QTable`]'s method of that head does (the
    /// Bayes and open heads with their default backend): `codes` and `out` hold K values,
    /// `scratch` at least [`LentQTable::scratch_len`] floats.
    ///
    /// # Errors
    ///
    /// [`InferError::CodeWidth`] when `Q` is not the section's code width;
    /// [`InferError::Length`] when `codes` or `out` do not hold K values or `scratch` is
    /// short; [`InferError::Objectness`]; [`InferError::NoBayesHead`];
    /// [`InferError::NoOpenHead`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn score_into<Q: Code>(
        &self,
        head: Head,
        codes: &[Q],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if Q::BITS != self.meta.bits {
            return Err(InferError::CodeWidth {
                expected: self.meta.bits,
                found: Q::BITS,
            });
        }
        let k = self.k();
        if codes.len() != k || out.len() != k {
            return Err(InferError::Length);
        }
        let view = self.view();
        let values = codes.iter().map(|q| q.value());
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

    /// The dequantized logits of `codes` into `out` (K values each): what the scores
    /// are exact for, and what the tie-safe decision compares (DESIGN §1.7).
    ///
    /// # Errors
    ///
    /// [`InferError::CodeWidth`] when `Q` is not the section's code width;
    /// [`InferError::Length`] when `codes` or `out` do not hold K values.
    #[inline]
    pub fn logits_into<Q: Code>(&self, codes: &[Q], out: &mut [f32]) -> Result<(), InferError> {
        if Q::BITS != self.meta.bits {
            return Err(InferError::CodeWidth {
                expected: self.meta.bits,
                found: Q::BITS,
            });
        }
        if codes.len() != self.k() || out.len() != self.k() {
            return Err(InferError::Length);
        }
        for ((x, q), c) in out.iter_mut().zip(codes).zip(self.classes) {
            *x = dequantize(q.value(), c.scale, c.zero_point);
        }
        Ok(())
    }
}
