//! The quantized table: the ML, MAP, Bayes and open heads for detectors whose heads emit
//! int8 or int16 logits (docs/FORMAT.md, "The quantized section").
//!
//! A quantized logit `q` of class `c` stands for the dequantized logit
//!
//! ```text
//! x = ((q - zero_point_c) as f32) * scale_c      (one f32 product, rounded to nearest)
//! ```
//!
//! (`q - zero_point_c` is computed exactly in `i32` and is exactly representable in
//! `f32`; [`dequantize`] is that formula). An int8 logit has only 256 values, so every
//! head's per-class work can be done once, for every code, when the section is built
//! ([`quantize_into`](crate::quantize_into)): the ML mass `L(x) + lambda`, the MAP mass
//! `L(x) P(x) + lambda`, and the Bayes head's bin of `x`, each computed by the very
//! functions the `f32` layer runs. Inference is then K lookups and the layer's own
//! normalisation, with no `exp` for ML and MAP: the scores are **bit for bit** those of
//! [`Table::ml`](crate::Table::ml), [`Table::map`](crate::Table::map) (its default
//! `Libm` backend), [`Table::bayes_with`](crate::Table::bayes_with) and
//! [`Table::open_with`](crate::Table::open_with) applied to the dequantized logits.
//!
//! The section stays in its bytes (flash on a device): [`QTable`] is a validated view
//! over them. [`QTable::from_bytes`] checks the checksum and every invariant once;
//! lookups afterwards read little-endian values from the borrowed bytes and cannot fail.
//!
//! Storage, per class (docs/FORMAT.md has the byte layout and the size formula):
//!
//! * ML: a code-to-bin index (one byte per code while the histogram has at most 256
//!   bins) over the window of codes whose mass differs from `lambda_ML`, and the B_ML
//!   masses `frequency + lambda_ML`; outside the window the mass is `lambda_ML`.
//! * MAP: the masses themselves (`f32`) over the window of codes whose mass differs from
//!   `lambda_MAP`; outside it the mass is `lambda_MAP`.
//! * Bayes (optional): per logit a code-to-bin index over the codes inside the logit's
//!   axis, and that logit's rows of log-terms; outside the axis a logit adds
//!   `ln(lambda)`, as in the `f32` head.
//! * Open (optional, with the Bayes head; section version 2): the temperature, `epsilon`
//!   and the unknown category's log-score as the table decoder derived it. The head's
//!   log-scores are the Bayes head's, and its softmax runs on the dequantized logits
//!   (DESIGN §1.8).
//! * Maps (optional; section version 3): the table's recalibration maps (DESIGN §1.9)
//!   for the heads the section holds, applied after each head as the `f32` layer does.
//! * Objectness feature (optional, with the Bayes head; section version 3): its axis
//!   and terms; its bin is looked up at run time from the objectness, as the `f32`
//!   head does.

use crate::bayes;
use crate::error::{Head, InferError};
use crate::histogram::Axis;
use crate::layer::{self, Scores};
use crate::math::Backend;
use crate::open::{self, OpenParams};
use crate::recal::{self, KnotBytes};
use crate::sections;
use crate::view::{BayesBackend, OpenBackend};

/// The four bytes a quantized section starts with.
pub const QUANTIZED_MAGIC: [u8; 4] = *b"MLMQ";

/// The newest quantized-section version: this build writes it for sections with a
/// recalibration map (DESIGN §1.9), and reads it and versions 1 (no open head, no map)
/// and 2 (the open head, no map), which it keeps writing for such sections.
pub const QUANTIZED_VERSION: u8 = 3;

/// The version of sections without the open head and without maps.
pub(crate) const QUANTIZED_VERSION_1: u8 = 1;

/// The version of sections with the open head and without maps.
pub(crate) const QUANTIZED_VERSION_2: u8 = 2;

/// Bytes of the open head's record (version 2): temperature, epsilon, unknown log-score.
pub(crate) const OPEN_LEN: usize = 12;

/// Bytes of the fixed header of a quantized section.
pub(crate) const HEADER_LEN: usize = 32;

/// Bytes of the trailer: the section's length and its CRC-32.
pub(crate) const TRAILER_LEN: usize = 8;

/// Largest magnitude of a Bayes log-term, log prior or `ln(lambda)` in a section: the
/// `f32` head's are within `[ln(1e-45), ln 2]` (terms) and `[-45, 0]` (priors), and the
/// bound keeps every log-score sum finite for any K.
pub const MAX_LOG_TERM: f32 = 128.0;

/// Largest mass a section may hold (as [`scores_from_evidence`](crate::scores_from_evidence)
/// accepts): the `f32` heads' masses are at most `1 + MAX_LAMBDA` (ML) and a few times
/// `1e18` (MAP).
pub const MAX_MASS: f32 = 1e30;

mod sealed {
    pub trait Sealed {}
    impl Sealed for i8 {}
    impl Sealed for i16 {}
}

/// An integer logit type a quantized section can be built for: `i8` or `i16`.
pub trait Code: Copy + sealed::Sealed {
    /// Bits of the code (8 or 16), as stored in the section header.
    const BITS: u8;
    /// The code as an `i32`.
    fn value(self) -> i32;
}

impl Code for i8 {
    const BITS: u8 = 8;
    #[inline(always)]
    fn value(self) -> i32 {
        i32::from(self)
    }
}

impl Code for i16 {
    const BITS: u8 = 16;
    #[inline(always)]
    fn value(self) -> i32 {
        i32::from(self)
    }
}

/// The smallest and largest code of a `bits`-bit signed integer (8 or 16).
#[inline]
pub const fn code_range(bits: u8) -> (i32, i32) {
    if bits == 8 {
        (i8::MIN as i32, i8::MAX as i32)
    } else {
        (i16::MIN as i32, i16::MAX as i32)
    }
}

/// The dequantized logit of code `q`: `((q - zero_point) as f32) * scale`, the formula
/// every quantized head is exact for. `q - zero_point` is exact in `i32` for any codes
/// and zero points of at most 16 bits, and exactly representable in `f32`; the product
/// is the only rounding.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// assert_eq!(mlmap::dequantize(-3, 0.5, 1), -2.0);
/// ```
#[inline]
pub fn dequantize(q: i32, scale: f32, zero_point: i32) -> f32 {
    (q.wrapping_sub(zero_point)) as f32 * scale
}

/// Why bytes could not become a [`QTable`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum QTableError {
    /// No quantized section: too short, or the bytes its trailer points to do not start
    /// with the magic `MLMQ`.
    NotQuantized,
    /// The section's CRC-32 does not match its contents.
    Corrupted,
    /// The section was written in a format version this build does not read.
    UnsupportedVersion {
        /// Version stored in the section.
        found: u8,
    },
    /// The section has another number of classes or code width than the type it is
    /// read into.
    ShapeMismatch {
        /// `(K, bits)` of the destination type.
        expected: (u16, u8),
        /// `(K, bits)` stored in the section.
        found: (u16, u8),
    },
    /// The section follows a table whose checksum is not the one it was computed from.
    TableMismatch,
    /// The checksum matched, but the section does not follow the format (a length runs
    /// past the end, bytes are left over, a reserved field is not 0).
    Malformed,
    /// A stored value breaks an invariant of the section.
    Invalid {
        /// Which value.
        field: QField,
        /// The class (ML, MAP, scale, zero point), logit (Bayes index and terms) or
        /// category (log prior) it belongs to; 0 for the header's fields.
        class: u16,
    },
}

/// The field of a quantized section that broke an invariant ([`QTableError::Invalid`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum QField {
    /// The code width is not 8 or 16, the class count below 2, a bin count 0, or the
    /// Bayes categories other than K or K + 1.
    Shape,
    /// A lambda of the ML or MAP head is not in `(0, MAX_LAMBDA]`.
    Lambda,
    /// A scale is not finite and positive.
    Scale,
    /// A zero point is outside the code range.
    ZeroPoint,
    /// A window of codes does not lie inside the code range (or an empty one does not
    /// start at 0).
    Window,
    /// A code's bin index is not below the head's bin count.
    Index,
    /// A mass is not finite, positive and at most [`MAX_MASS`].
    Mass,
    /// A Bayes log-term, log prior or `ln(lambda)` is not finite with magnitude at most
    /// [`MAX_LOG_TERM`].
    LogTerm,
    /// The open head's temperature is not in
    /// [`[MIN_TEMPERATURE, MAX_TEMPERATURE]`](crate::MIN_TEMPERATURE).
    Temperature,
    /// The open head's `epsilon` is not 0 and not in
    /// `[f32::MIN_POSITIVE, `[`MAX_EPSILON`](crate::MAX_EPSILON)`]`.
    Epsilon,
    /// The open head's unknown log-score is not `-inf` with `epsilon` 0, or not finite
    /// with `epsilon` > 0.
    LogUnknown,
    /// A recalibration map breaks the rule of DESIGN §1.9, repeats or misorders a head,
    /// or is for a head the section does not hold (`class` is the head's code: 0 ML,
    /// 1 MAP, 2 Bayes, 3 open).
    Map,
    /// The objectness feature's axis is not a valid axis, or a term is not finite and
    /// small (DESIGN §1.6).
    Objectness,
}

impl QField {
    /// A few words naming the field, shared by `Display` and `defmt`.
    pub const fn describe(self) -> &'static str {
        match self {
            Self::Shape => "shape (bits, classes, bins or categories)",
            Self::Lambda => "lambda",
            Self::Scale => "scale (not finite and positive)",
            Self::ZeroPoint => "zero point (outside the code range)",
            Self::Window => "window of codes (outside the code range)",
            Self::Index => "bin index (not below the bin count)",
            Self::Mass => "mass (not finite and positive)",
            Self::LogTerm => "Bayes log-term (not finite and small)",
            Self::Temperature => "open head's temperature (out of range)",
            Self::Epsilon => "open head's epsilon (neither 0 nor in range)",
            Self::LogUnknown => {
                "open head's unknown log-score (not -inf for epsilon 0, or not finite)"
            }
            Self::Map => "recalibration map (knots, head or order)",
            Self::Objectness => "objectness feature (axis or terms)",
        }
    }
}

impl core::fmt::Display for QTableError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::NotQuantized => f.write_str("input holds no quantized section (magic `MLMQ`)"),
            Self::Corrupted => f.write_str("quantized section checksum does not match its contents"),
            Self::UnsupportedVersion { found } => write!(
                f,
                "quantized section version {found} is not supported (this build reads versions {QUANTIZED_VERSION_1} to {QUANTIZED_VERSION})"
            ),
            Self::ShapeMismatch { expected, found } => write!(
                f,
                "quantized section has {} classes and {}-bit codes; expected {} and {}",
                found.0, found.1, expected.0, expected.1
            ),
            Self::TableMismatch => f.write_str(
                "quantized section was computed from another table than the one it follows",
            ),
            Self::Malformed => f.write_str("quantized section does not follow the format"),
            Self::Invalid { field, class } => {
                write!(f, "invalid quantized section: class {class}: {}", field.describe())
            }
        }
    }
}

impl core::error::Error for QTableError {}

/// One class's ML and MAP data, borrowed from the section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QClass<'a> {
    pub(crate) scale: f32,
    pub(crate) zero_point: i32,
    pub(crate) ml_start: i32,
    /// One index per code of the window (1 or 2 bytes each).
    pub(crate) ml_index: &'a [u8],
    /// B_ML masses, `f32` LE.
    pub(crate) ml_masses: &'a [[u8; 4]],
    pub(crate) map_start: i32,
    /// One mass per code of the window, `f32` LE.
    pub(crate) map_masses: &'a [[u8; 4]],
}

impl QClass<'_> {
    pub(crate) const EMPTY: QClass<'static> = QClass {
        scale: 0.0,
        zero_point: 0,
        ml_start: 0,
        ml_index: &[],
        ml_masses: &[],
        map_start: 0,
        map_masses: &[],
    };
}

/// One logit's Bayes data, borrowed from the section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QLogit<'a> {
    pub(crate) start: i32,
    /// One index per code of the window.
    pub(crate) index: &'a [u8],
    /// B_BAYES rows of C log-terms, `f32` LE.
    pub(crate) terms: &'a [[u8; 4]],
}

impl QLogit<'_> {
    pub(crate) const EMPTY: QLogit<'static> = QLogit {
        start: 0,
        index: &[],
        terms: &[],
    };
}

/// The header fields of a section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Meta<'a> {
    pub(crate) bits: u8,
    pub(crate) k: u16,
    pub(crate) bins_ml: u16,
    pub(crate) bins_bayes: u16,
    pub(crate) categories: u16,
    pub(crate) table_crc: u32,
    pub(crate) lambda_ml: f32,
    pub(crate) lambda_map: f32,
    pub(crate) log_lambda: f32,
    /// C log priors, `f32` LE (empty without a Bayes head).
    pub(crate) log_prior: &'a [[u8; 4]],
    /// The open head's parameters (version 2), `None` without that head.
    pub(crate) open: Option<OpenParams>,
    /// The heads' recalibration maps (version 3), ML, MAP, Bayes, open; empty: none.
    pub(crate) maps: [&'a [[u8; 8]]; 4],
    /// The objectness feature (version 3, flag bit 2): its axis and its `B * C` terms.
    pub(crate) objectness: Option<(Axis, &'a [[u8; 4]])>,
    /// Length of the section, trailer included.
    pub(crate) len: usize,
}

/// Reads little-endian fields from the front of a byte slice.
struct Reader<'a>(&'a [u8]);

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], QTableError> {
        if n > self.0.len() {
            return Err(QTableError::Malformed);
        }
        let (head, rest) = self.0.split_at(n);
        self.0 = rest;
        Ok(head)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], QTableError> {
        self.take(N)?.try_into().map_err(|_| QTableError::Malformed)
    }

    fn u8(&mut self) -> Result<u8, QTableError> {
        Ok(u8::from_le_bytes(self.array()?))
    }

    fn u16(&mut self) -> Result<u16, QTableError> {
        Ok(u16::from_le_bytes(self.array()?))
    }

    fn u32(&mut self) -> Result<u32, QTableError> {
        Ok(u32::from_le_bytes(self.array()?))
    }

    fn i32(&mut self) -> Result<i32, QTableError> {
        Ok(i32::from_le_bytes(self.array()?))
    }

    fn f32(&mut self) -> Result<f32, QTableError> {
        Ok(f32::from_le_bytes(self.array()?))
    }

    /// `n` elements of `size` bytes each.
    fn elements(&mut self, n: usize, size: usize) -> Result<&'a [u8], QTableError> {
        self.take(n.checked_mul(size).ok_or(QTableError::Malformed)?)
    }

    /// `n` values of 4 bytes each.
    fn values(&mut self, n: usize) -> Result<&'a [[u8; 4]], QTableError> {
        Ok(self.elements(n, 4)?.as_chunks::<4>().0)
    }
}

/// `f32` number `i` of little-endian values.
#[inline(always)]
pub(crate) fn f32_at(values: &[[u8; 4]], i: usize) -> Option<f32> {
    values.get(i).map(|&b| f32::from_le_bytes(b))
}

/// Index number `i` of a code-to-bin map with entries of one (`wide` false) or two bytes.
#[inline(always)]
fn index_at(bytes: &[u8], wide: bool, i: usize) -> Option<usize> {
    if wide {
        let b = bytes.as_chunks::<2>().0.get(i)?;
        Some(usize::from(u16::from_le_bytes(*b)))
    } else {
        bytes.get(i).map(|&b| usize::from(b))
    }
}

/// Bytes per bin index for a head of `bins` bins.
#[inline]
pub(crate) const fn index_width(bins: u16) -> usize {
    if bins <= 256 {
        1
    } else {
        2
    }
}

/// The window position of code `q` in a window starting at `start`: `q - start`, or,
/// for `q < start`, a number above 2^31 that no window (at most 65,536 codes) reaches.
#[inline(always)]
fn offset(q: i32, start: i32) -> usize {
    q.wrapping_sub(start) as u32 as usize
}

/// Locates the quantized section in `bytes`: the section alone, or a table file with the
/// section appended. Checks the magic and the section's CRC; returns the section and
/// the table before it (empty for a section alone).
///
/// # Errors
///
/// [`QTableError::NotQuantized`] and [`QTableError::Corrupted`].
pub(crate) fn locate(bytes: &[u8]) -> Result<(&[u8], &[u8]), QTableError> {
    let (section, table) = sections::find(bytes, QUANTIZED_MAGIC).map_err(|m| match m {
        sections::Missing::Absent => QTableError::NotQuantized,
        sections::Missing::Corrupted => QTableError::Corrupted,
    })?;
    if section.len() < HEADER_LEN + TRAILER_LEN {
        return Err(QTableError::NotQuantized);
    }
    Ok((section, table))
}

/// The table of a file that may have sections appended (docs/FORMAT.md): every table
/// decoder reads through it, so a table file with sections decodes as the table alone.
pub(crate) use crate::sections::table_part;

/// Parses and validates a located section (its CRC checked), calling `class` and
/// `logit` with each class's and Bayes logit's data in order.
pub(crate) fn parse<'a>(
    section: &'a [u8],
    table: &[u8],
    mut class: impl FnMut(usize, QClass<'a>),
    mut logit: impl FnMut(usize, QLogit<'a>),
) -> Result<Meta<'a>, QTableError> {
    let invalid = |field, class: usize| QTableError::Invalid {
        field,
        class: u16::try_from(class).unwrap_or(u16::MAX),
    };
    let body_len = section.len().saturating_sub(TRAILER_LEN);
    let mut r = Reader(section.get(..body_len).unwrap_or(&[]));
    let _magic = r.take(4)?;
    let version = r.u8()?;
    if !(QUANTIZED_VERSION_1..=QUANTIZED_VERSION).contains(&version) {
        return Err(QTableError::UnsupportedVersion { found: version });
    }
    let bits = r.u8()?;
    let flags = r.u8()?;
    let reserved = r.u8()?;
    let k = r.u16()?;
    let bins_ml = r.u16()?;
    let bins_bayes = r.u16()?;
    let categories = r.u16()?;
    let table_crc = r.u32()?;
    let lambda_ml = r.f32()?;
    let lambda_map = r.f32()?;
    let log_lambda = r.f32()?;
    // Flags: bit 0 the Bayes head; in version 3, bit 1 the open head (which needs the
    // Bayes head). Version 2 is the version of sections with the open head.
    // Version 3 also has bit 2: the objectness feature (which needs the Bayes head).
    let has_maps = version == QUANTIZED_VERSION;
    let max_flags = if has_maps { 7 } else { 1 };
    let has_open = version == QUANTIZED_VERSION_2 || (has_maps && flags & 2 != 0);
    let has_feature = has_maps && flags & 4 != 0;
    if has_feature && flags & 1 == 0 {
        return Err(QTableError::Malformed);
    }
    if reserved != 0 || flags > max_flags || (has_open && flags & 1 == 0) {
        return Err(QTableError::Malformed);
    }
    if version == QUANTIZED_VERSION_2 && flags != 1 {
        return Err(QTableError::Malformed);
    }
    let has_bayes = flags & 1 == 1;
    if !(bits == 8 || bits == 16) || k < 2 || k == u16::MAX || bins_ml == 0 {
        return Err(invalid(QField::Shape, 0));
    }
    if has_bayes {
        if bins_bayes == 0 || !(categories == k || Some(categories) == k.checked_add(1)) {
            return Err(invalid(QField::Shape, 0));
        }
        if !small_log(log_lambda) {
            return Err(invalid(QField::LogTerm, 0));
        }
    } else if bins_bayes != 0 || categories != 0 || log_lambda.to_bits() != 0 {
        return Err(QTableError::Malformed);
    }
    let lambda_ok = |l: f32| l > 0.0 && l <= crate::MAX_LAMBDA;
    if !(lambda_ok(lambda_ml) && lambda_ok(lambda_map)) {
        return Err(invalid(QField::Lambda, 0));
    }
    // A section appended to a table names that table by its checksum.
    if let Some(stored) = table.len().checked_sub(4).and_then(|at| table.get(at..)) {
        if stored != table_crc.to_le_bytes() {
            return Err(QTableError::TableMismatch);
        }
    }
    let (lo, hi) = code_range(bits);
    let window = |r: &mut Reader<'a>, c: usize| -> Result<(i32, usize), QTableError> {
        let start = r.i32()?;
        let n = r.u32()?;
        let n = usize::try_from(n).map_err(|_| invalid(QField::Window, c))?;
        let fits = if n == 0 {
            start == 0
        } else {
            i64::from(start) >= i64::from(lo) && i64::from(start) + (n as i64) - 1 <= i64::from(hi)
        };
        if !fits {
            return Err(invalid(QField::Window, c));
        }
        Ok((start, n))
    };
    let check_index = |index: &[u8], wide: bool, bins: u16, c: usize| {
        let n = index.len() / if wide { 2 } else { 1 };
        if (0..n).all(|i| index_at(index, wide, i).is_some_and(|b| b < usize::from(bins))) {
            Ok(())
        } else {
            Err(invalid(QField::Index, c))
        }
    };
    let check_masses = |masses: &[[u8; 4]], c: usize| {
        let ok = |m: f32| m > 0.0 && m <= MAX_MASS;
        if masses.iter().all(|&m| ok(f32::from_le_bytes(m))) {
            Ok(())
        } else {
            Err(invalid(QField::Mass, c))
        }
    };
    let wide_ml = index_width(bins_ml) == 2;
    for c in 0..usize::from(k) {
        let scale = r.f32()?;
        let zero_point = r.i32()?;
        if !(scale.is_finite() && scale > 0.0) {
            return Err(invalid(QField::Scale, c));
        }
        if !(lo..=hi).contains(&zero_point) {
            return Err(invalid(QField::ZeroPoint, c));
        }
        let (ml_start, n) = window(&mut r, c)?;
        let ml_index = r.elements(n, index_width(bins_ml))?;
        check_index(ml_index, wide_ml, bins_ml, c)?;
        let ml_masses = r.values(usize::from(bins_ml))?;
        check_masses(ml_masses, c)?;
        let (map_start, n) = window(&mut r, c)?;
        let map_masses = r.values(n)?;
        check_masses(map_masses, c)?;
        class(
            c,
            QClass {
                scale,
                zero_point,
                ml_start,
                ml_index,
                ml_masses,
                map_start,
                map_masses,
            },
        );
    }
    let mut log_prior: &[[u8; 4]] = &[];
    if has_bayes {
        let wide = index_width(bins_bayes) == 2;
        let row = usize::from(bins_bayes) * usize::from(categories);
        for j in 0..usize::from(k) {
            let (start, n) = window(&mut r, j)?;
            let index = r.elements(n, index_width(bins_bayes))?;
            check_index(index, wide, bins_bayes, j)?;
            let terms = r.values(row)?;
            if !terms.iter().all(|&t| small_log(f32::from_le_bytes(t))) {
                return Err(invalid(QField::LogTerm, j));
            }
            logit(
                j,
                QLogit {
                    start,
                    index,
                    terms,
                },
            );
        }
        log_prior = r.values(usize::from(categories))?;
        for (c, &v) in log_prior.iter().enumerate() {
            if !small_log(f32::from_le_bytes(v)) {
                return Err(invalid(QField::LogTerm, c));
            }
        }
    }
    let mut open = None;
    if has_open {
        let (t, e, l) = (r.u32()?, r.u32()?, r.u32()?);
        // The ranges of `OpenParams::new`, checked on the bits (which take less code on
        // a device than the float comparisons): a positive `f32` orders as its bits, and
        // NaN, negative values (-0 included) and infinities fall outside.
        let bits = |v: f32| v.to_bits();
        if !(bits(crate::MIN_TEMPERATURE)..=bits(crate::MAX_TEMPERATURE)).contains(&t) {
            return Err(invalid(QField::Temperature, 0));
        }
        if !(e == 0 || (bits(f32::MIN_POSITIVE)..=bits(crate::MAX_EPSILON)).contains(&e)) {
            return Err(invalid(QField::Epsilon, 0));
        }
        // As `OpenParams::new` derives it: -inf exactly when there is no unknown
        // category, finite otherwise. (Its value is the writer's, as every precomputed
        // value of the section: deriving it here would need `ln` on the device.)
        let finite = l & 0x7f80_0000 != 0x7f80_0000;
        if !(if e == 0 {
            l == bits(f32::NEG_INFINITY)
        } else {
            finite
        }) {
            return Err(invalid(QField::LogUnknown, 0));
        }
        open = Some(OpenParams {
            temperature: f32::from_bits(t),
            epsilon: f32::from_bits(e),
            log_unknown: f32::from_bits(l),
        });
    }
    let mut objectness = None;
    if has_feature {
        let (lo, hi) = (r.f32()?, r.f32()?);
        let axis = Axis::new(lo, hi, usize::from(bins_bayes))
            .map_err(|_| invalid(QField::Objectness, 0))?;
        let terms = r.values(usize::from(bins_bayes) * usize::from(categories))?;
        if !terms.iter().all(|&t| small_log(f32::from_le_bytes(t))) {
            return Err(invalid(QField::Objectness, 0));
        }
        objectness = Some((axis, terms));
    }
    let mut maps: [&'a [[u8; 8]]; 4] = [&[]; 4];
    if has_maps {
        // Records (head code, knot count, knots), head codes increasing: one or more,
        // or none when the section is version 3 for the objectness feature only.
        let records = r.u8()?;
        if records == 0 && !has_feature {
            return Err(QTableError::Malformed);
        }
        let mut next = 0usize;
        for _ in 0..records {
            let code = usize::from(r.u8()?);
            let n = usize::from(r.u8()?);
            let bytes = r.take(8 * n)?;
            let knots = bytes.as_chunks::<8>().0;
            let held = match code {
                0 | 1 => true,
                2 => has_bayes,
                3 => has_open,
                _ => false,
            };
            if code < next || !held || recal::check(&KnotBytes(knots)).is_err() {
                return Err(invalid(QField::Map, code));
            }
            if let Some(slot) = maps.get_mut(code) {
                *slot = knots;
            }
            next = code + 1;
        }
    }
    if !r.0.is_empty() {
        return Err(QTableError::Malformed);
    }
    Ok(Meta {
        bits,
        k,
        bins_ml,
        bins_bayes,
        categories,
        table_crc,
        lambda_ml,
        lambda_map,
        log_lambda,
        log_prior,
        open,
        maps,
        objectness,
        len: section.len(),
    })
}

/// Finite with magnitude at most [`MAX_LOG_TERM`].
fn small_log(v: f32) -> bool {
    v.abs() <= MAX_LOG_TERM
}

/// A validated section with its per-class data located: the one implementation of the
/// quantized heads, shared by [`QTable`] and the host's `DynQTable`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct QView<'r, 'a> {
    pub(crate) meta: &'r Meta<'a>,
    pub(crate) classes: &'r [QClass<'a>],
    pub(crate) logits: &'r [QLogit<'a>],
}

impl<'a> QView<'_, 'a> {
    /// The ML mass of class `c`'s code `q` (`lambda_ML` outside its window).
    #[inline(always)]
    fn ml_mass(&self, c: &QClass<'a>, q: i32) -> f32 {
        let wide = self.meta.bins_ml > 256;
        index_at(c.ml_index, wide, offset(q, c.ml_start))
            .and_then(|b| f32_at(c.ml_masses, b))
            .unwrap_or(self.meta.lambda_ml)
    }

    /// The MAP mass of class `c`'s code `q` (`lambda_MAP` outside its window).
    #[inline(always)]
    fn map_mass(&self, c: &QClass<'a>, q: i32) -> f32 {
        f32_at(c.map_masses, offset(q, c.map_start)).unwrap_or(self.meta.lambda_map)
    }

    /// The masses of one head into `out`, then the layer's normalisation. `codes` holds
    /// K codes already in the code range.
    #[inline(always)]
    pub(crate) fn masses_into(
        &self,
        head: Head,
        codes: impl Iterator<Item = i32>,
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if !(0.0..=1.0).contains(&objectness) {
            return Err(InferError::Objectness);
        }
        if out.len() != self.classes.len() || scratch.len() != out.len() {
            return Err(InferError::Length);
        }
        for ((o, c), q) in out.iter_mut().zip(self.classes).zip(codes) {
            *o = match head {
                Head::Map => self.map_mass(c, q),
                _ => self.ml_mass(c, q),
            };
        }
        layer::normalise(out, scratch, objectness);
        self.recalibrate(if head == Head::Map { 1 } else { 0 }, out);
        Ok(())
    }

    /// Applies the map in slot `slot` (0 ML, 1 MAP, 2 Bayes, 3 open), if any, as the
    /// `f32` layer does (DESIGN §1.9).
    #[inline(always)]
    fn recalibrate(&self, slot: usize, out: &mut [f32]) {
        if let Some(knots) = self.meta.maps.get(slot).filter(|k| !k.is_empty()) {
            recal::apply(&KnotBytes(knots), out);
        }
    }

    /// Bayes scores: the log-scores from the stored rows, then the `f32` head's softmax
    /// with backend `M`. `scratch` holds C floats.
    #[inline(always)]
    pub(crate) fn bayes_into<M: Backend>(
        &self,
        codes: impl Iterator<Item = i32>,
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if self.logits.is_empty() {
            return Err(InferError::NoBayesHead);
        }
        self.log_scores_into(codes, objectness, out, scratch)?;
        bayes::softmax::<M>(scratch, objectness, out);
        self.recalibrate(2, out);
        Ok(())
    }

    /// Open-head scores (DESIGN §1.8): the Bayes log-scores from the stored rows, then
    /// the open head's normalisation on the dequantized logits, which `x` (K floats)
    /// receives. `scratch` holds C floats.
    #[inline(always)]
    pub(crate) fn open_into<M: Backend>(
        &self,
        codes: impl Iterator<Item = i32> + Clone,
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
        x: &mut [f32],
    ) -> Result<(), InferError> {
        let params = match (&self.meta.open, self.logits.is_empty()) {
            (Some(p), false) => p,
            _ => return Err(InferError::NoOpenHead),
        };
        if x.len() != out.len() {
            return Err(InferError::Length);
        }
        self.log_scores_into(codes.clone(), objectness, out, scratch)?;
        for ((x, c), q) in x.iter_mut().zip(self.classes).zip(codes) {
            *x = dequantize(q, c.scale, c.zero_point);
        }
        open::score_from_log_scores::<M>(scratch, params, x, objectness, out);
        self.recalibrate(3, out);
        Ok(())
    }

    /// The Bayes log-scores `l[c] = ln pi[c] + sum_j t[c][j][bin_j]` of one detection
    /// into `scratch` (C floats), in the order of the `f32` head (the prior, then each
    /// logit's row, left to right). Checks the objectness and the lengths of `out` and
    /// `scratch` first.
    #[inline(always)]
    fn log_scores_into(
        &self,
        codes: impl Iterator<Item = i32>,
        objectness: f32,
        out: &[f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if !(0.0..=1.0).contains(&objectness) {
            return Err(InferError::Objectness);
        }
        // The length of `scratch` (not the header's field) sizes the rows, so that a
        // caller with a compile-time C gets loops of known length.
        let cats = scratch.len();
        if out.len() != self.classes.len() || cats != usize::from(self.meta.categories) {
            return Err(InferError::Length);
        }
        for (l, &p) in scratch.iter_mut().zip(self.meta.log_prior) {
            *l = f32::from_le_bytes(p);
        }
        let wide = self.meta.bins_bayes > 256;
        for (lg, q) in self.logits.iter().zip(codes) {
            let row = index_at(lg.index, wide, offset(q, lg.start)).and_then(|b| {
                let at = b.checked_mul(cats)?;
                lg.terms.get(at..at.checked_add(cats)?)
            });
            match row {
                Some(row) => {
                    for (l, &t) in scratch.iter_mut().zip(row) {
                        *l += f32::from_le_bytes(t);
                    }
                }
                None => {
                    for l in scratch.iter_mut() {
                        *l += self.meta.log_lambda;
                    }
                }
            }
        }
        // The objectness feature last, as the f32 head adds it.
        if let Some((axis, terms)) = &self.meta.objectness {
            let z = bayes::clamp_to_axis(bayes::objectness_logit(objectness), axis);
            let row = axis.bin(z).and_then(|b| {
                let at = b.checked_mul(cats)?;
                terms.get(at..at.checked_add(cats)?)
            });
            if let Some(row) = row {
                for (l, &t) in scratch.iter_mut().zip(row) {
                    *l += f32::from_le_bytes(t);
                }
            }
        }
        Ok(())
    }
}

/// A validated quantized section for `K` classes and codes of type `Q` (`i8` or
/// `i16`), borrowed from its bytes: the ML, MAP and, if the section has it, Bayes heads
/// on integer logits (docs/FORMAT.md, "The quantized section").
///
/// Built once by [`quantize_into`](crate::quantize_into) from a table and the detector's
/// quantization: per class and representable code, the ML mass and the MAP mass (and per
/// logit the Bayes head's bin) of the dequantized logit, computed by the `f32` layer's own
/// functions. Only the codes whose mass differs from lambda are stored (the ML head as a
/// one-byte bin index per code, the MAP head as `f32` masses); inference is K lookups and
/// the layer's normalisation, with no `exp` for ML and MAP.
///
/// The scores equal, bit for bit, the `f32` table's on the dequantized logits
/// `x_c = ((q_c - zero_point_c) as f32) * scale_c`: [`QTable::ml`] those of
/// [`Table::ml`](crate::Table::ml), [`QTable::map`] those of
/// [`Table::map`](crate::Table::map), [`QTable::bayes`] those of
/// [`Table::bayes`](crate::Table::bayes), [`QTable::open`] those of
/// [`Table::open`](crate::Table::open).
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::{quantize_into, QParams, QTable, Table};
///
/// let table = Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("../../tables/default.mlmap"))?;
/// let params = QParams { bits: 8, scales: &[0.08; 3], zero_points: &[0; 3], bayes: true };
/// let mut buf = [0u8; 6144];
/// let bytes = quantize_into(&table.view(), &params, &mut buf)?;
/// let q = QTable::<3, i8>::from_bytes(bytes)?;
///
/// // The f32 layer on the dequantized logits (code 50 is 50 * 0.08 = 4.0), bit for bit.
/// let codes = [50i8, -20, 10];
/// let x = codes.map(|q| mlmap::dequantize(q.into(), 0.08, 0));
/// assert_eq!(q.ml(&codes, 0.9)?, table.ml(&x, 0.9)?);
/// assert_eq!(q.map(&codes, 0.9)?, table.map(&x, 0.9)?);
/// assert_eq!(q.bayes(&codes, 0.9)?, table.bayes(&x, 0.9)?);
/// assert_eq!(q.open(&codes, 0.9)?, table.open(&x, 0.9)?);
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QTable<'a, const K: usize, Q: Code = i8> {
    pub(crate) meta: Meta<'a>,
    pub(crate) classes: [QClass<'a>; K],
    pub(crate) logits: [QLogit<'a>; K],
    pub(crate) code: core::marker::PhantomData<Q>,
}

impl<'a, const K: usize, Q: Code> QTable<'a, K, Q> {
    /// Reads the quantized section of `bytes`: the section alone, or a table file with
    /// the section appended (as `mlmap quantize` writes it). The section is validated
    /// and borrowed; the table before it is not decoded (only its checksum is compared
    /// with the one the section names).
    ///
    /// Checks, in order: the trailer and magic, the section's CRC-32, the version, `K`
    /// and the code width against the type, the header's fields, the table's checksum,
    /// then every class's and logit's values, and that no byte is left over.
    ///
    /// # Errors
    ///
    /// A [`QTableError`] naming the first failed check.
    ///
    /// # Panics
    ///
    /// Never, whatever the bytes.
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, QTableError> {
        let (section, table) = locate(bytes)?;
        // The shape first, so that a section of another type says so.
        let shape = (
            section
                .get(8..10)
                .and_then(|b| b.try_into().ok())
                .map_or(0, u16::from_le_bytes),
            section.get(5).copied().unwrap_or(0),
        );
        let version = section.get(4).copied().unwrap_or(0);
        if (QUANTIZED_VERSION_1..=QUANTIZED_VERSION).contains(&version) {
            let expected = (u16::try_from(K).unwrap_or(u16::MAX), Q::BITS);
            if shape != expected {
                return Err(QTableError::ShapeMismatch {
                    expected,
                    found: shape,
                });
            }
        }
        let mut classes = [QClass::EMPTY; K];
        let mut logits = [QLogit::EMPTY; K];
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
        Ok(Self {
            meta,
            classes,
            logits,
            code: core::marker::PhantomData,
        })
    }

    #[inline(always)]
    fn view(&self) -> QView<'_, 'a> {
        QView {
            meta: &self.meta,
            classes: &self.classes,
            logits: if self.meta.categories > 0 {
                &self.logits
            } else {
                &[]
            },
        }
    }

    /// ML scores of one detection: as [`Table::ml`](crate::Table::ml) on the
    /// dequantized logits, bit for bit.
    ///
    /// # Errors
    ///
    /// [`InferError::Objectness`] for an objectness that is NaN or outside `[0, 1]`.
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn ml(&self, codes: &[Q; K], objectness: f32) -> Result<Scores<K>, InferError> {
        self.masses(Head::Ml, codes, objectness)
    }

    /// MAP scores of one detection: as [`Table::map`](crate::Table::map) (its `Libm`
    /// backend) on the dequantized logits, bit for bit; no `exp` at run time.
    ///
    /// # Errors
    ///
    /// As [`QTable::ml`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn map(&self, codes: &[Q; K], objectness: f32) -> Result<Scores<K>, InferError> {
        self.masses(Head::Map, codes, objectness)
    }

    /// The ML or MAP scores of one detection from the tabulated masses.
    #[inline(always)]
    fn masses(&self, head: Head, codes: &[Q; K], objectness: f32) -> Result<Scores<K>, InferError> {
        let (mut out, mut scratch) = ([0.0; K], [0.0; K]);
        self.view().masses_into(
            head,
            codes.iter().map(|q| q.value()),
            objectness,
            &mut out,
            &mut scratch,
        )?;
        Ok(Scores(out))
    }

    /// Bayes scores of one detection: as [`Table::bayes`](crate::Table::bayes) (its
    /// `FastMath` softmax) on the dequantized logits, bit for bit. The softmax's C - 1
    /// calls of `exp` remain at run time; the bin lookups are tabulated.
    ///
    /// # Errors
    ///
    /// [`InferError::NoBayesHead`] for a section without the Bayes head; otherwise as
    /// [`QTable::ml`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn bayes(&self, codes: &[Q; K], objectness: f32) -> Result<Scores<K>, InferError> {
        self.bayes_with::<BayesBackend>(codes, objectness)
    }

    /// Bayes scores of one detection with the softmax's `exp` from backend `M`: as
    /// [`Table::bayes_with`](crate::Table::bayes_with) on the dequantized logits.
    ///
    /// # Errors
    ///
    /// As [`QTable::bayes`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn bayes_with<M: Backend>(
        &self,
        codes: &[Q; K],
        objectness: f32,
    ) -> Result<Scores<K>, InferError> {
        let mut out = [0.0; K];
        // C is K or K + 1 <= 2K log-scores; each case with a length known at compile
        // time, so that its loops are unrolled as in `Table::bayes`.
        let mut scratch = [[0.0f32; 2]; K];
        let scratch = scratch.as_flattened_mut();
        let codes = codes.iter().map(|q| q.value());
        let view = self.view();
        if usize::from(self.meta.categories) == K {
            let scratch = scratch.get_mut(..K).ok_or(InferError::Length)?;
            view.bayes_into::<M>(codes, objectness, &mut out, scratch)?;
        } else {
            let scratch = scratch.get_mut(..K + 1).ok_or(InferError::Length)?;
            view.bayes_into::<M>(codes, objectness, &mut out, scratch)?;
        }
        Ok(Scores(out))
    }

    /// Open-head scores of one detection (DESIGN §1.8): as
    /// [`Table::open`](crate::Table::open) (its `FastMath` backend) on the dequantized
    /// logits, bit for bit. The log-scores come from the stored rows, as for
    /// [`QTable::bayes`]; the softmax at the temperature runs on the dequantized logits.
    ///
    /// # Errors
    ///
    /// [`InferError::NoOpenHead`] for a section without the open head (a version-1
    /// section); otherwise as [`QTable::ml`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn open(&self, codes: &[Q; K], objectness: f32) -> Result<Scores<K>, InferError> {
        self.open_with::<OpenBackend>(codes, objectness)
    }

    /// Open-head scores of one detection with the `exp` of backend `M`: as
    /// [`Table::open_with`](crate::Table::open_with) on the dequantized logits.
    ///
    /// # Errors
    ///
    /// As [`QTable::open`].
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn open_with<M: Backend>(
        &self,
        codes: &[Q; K],
        objectness: f32,
    ) -> Result<Scores<K>, InferError> {
        let (mut out, mut x) = ([0.0; K], [0.0; K]);
        // As in `bayes_with`: C = K or K + 1 log-scores, each a length known at compile
        // time.
        let mut scratch = [[0.0f32; 2]; K];
        let scratch = scratch.as_flattened_mut();
        let codes = codes.iter().map(|q| q.value());
        let view = self.view();
        if usize::from(self.meta.categories) == K {
            let scratch = scratch.get_mut(..K).ok_or(InferError::Length)?;
            view.open_into::<M>(codes, objectness, &mut out, scratch, &mut x)?;
        } else {
            let scratch = scratch.get_mut(..K + 1).ok_or(InferError::Length)?;
            view.open_into::<M>(codes, objectness, &mut out, scratch, &mut x)?;
        }
        Ok(Scores(out))
    }

    /// The dequantized logits of `codes` ([`dequantize`] with each class's scale and zero
    /// point): what the scores are exact for, and what the tie-safe decision compares
    /// (`scores.decide(&q.logits(&codes))`, DESIGN §1.7), since classes may have
    /// different scales.
    ///
    /// # Examples
    ///
    /// ```
    /// # use mlmap_core as mlmap;
    /// let q = mlmap::QTable::<3, i8>::from_bytes(include_bytes!("../../tables/default_q8.mlmap"))?;
    /// assert_eq!(q.logits(&[50, -25, 0]), [4.0, -2.0, 0.0]);
    /// let never_seen = q.ml(&[-128; 3], 1.0)?; // OS / K each: ties everywhere
    /// assert_eq!(never_seen.decide(&q.logits(&[-128, -100, -128])), 1);
    /// # Ok::<(), Box<dyn core::error::Error>>(())
    /// ```
    #[inline]
    pub fn logits(&self, codes: &[Q; K]) -> [f32; K] {
        let mut x = [0.0; K];
        for ((x, q), c) in x.iter_mut().zip(codes).zip(&self.classes) {
            *x = dequantize(q.value(), c.scale, c.zero_point);
        }
        x
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

    /// The quantization of class `c`: `(scale, zero_point)`.
    #[inline]
    pub fn params(&self, c: usize) -> Option<(f32, i32)> {
        self.classes.get(c).map(|q| (q.scale, q.zero_point))
    }

    /// The precomputed ML mass of class `c` for code `q` (`L(x) + lambda_ML` of the
    /// dequantized `x`), as the scores use it.
    pub fn ml_mass(&self, c: usize, q: Q) -> Option<f32> {
        Some(self.view().ml_mass(self.classes.get(c)?, q.value()))
    }

    /// The precomputed MAP mass of class `c` for code `q` (`L(x) P(x) + lambda_MAP`).
    pub fn map_mass(&self, c: usize, q: Q) -> Option<f32> {
        Some(self.view().map_mass(self.classes.get(c)?, q.value()))
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
}
