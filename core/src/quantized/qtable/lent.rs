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
pub type LentQTable<'s, 'a> = QTableInner<'a, &'s [QClass<'a>], &'s [QLogit<'a>]>;

/// A placeholder class record for storage [`LentQTable::from_bytes`] fills.
pub const EMPTY_QCLASS: QClass<'static> = QClass::EMPTY;
/// A placeholder logit record for storage [`LentQTable::from_bytes`] fills.
pub const EMPTY_QLOGIT: QLogit<'static> = QLogit::EMPTY;

impl<'s, 'a> QTableInner<'a, &'s [QClass<'a>], &'s [QLogit<'a>]> {
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
        Ok(Self::new(meta, classes, logits))
    }
}
