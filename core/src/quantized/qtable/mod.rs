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

use crate::diagnostics::error::{Head, InferError};
use crate::heads::bayes;
use crate::heads::layer::{self, Scores};
use crate::heads::open::{self, OpenParams};
use crate::heads::recal::{self, KnotBytes};
use crate::math::histogram::Axis;
use crate::math::Backend;
use crate::sections;
use crate::storage::view::{BayesBackend, OpenBackend};

mod inner;
mod lent;
mod score;
mod section;
pub use inner::{AnyCode, QTableInner};
pub use lent::{LentQTable, EMPTY_QCLASS, EMPTY_QLOGIT};
pub(crate) use score::QView;
pub(crate) use section::{
    f32_at, index_at, index_width, locate, offset, parse, table_part, Meta, QHeader, FLAG_BAYES,
    FLAG_OBJECTNESS, FLAG_OPEN,
};
pub use section::{QClass, QLogit};

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

impl QTableError {
    /// The variant's message: what `Display` says (with the variant's values where it
    /// has any) and what `defmt` prints.
    pub const fn message(self) -> &'static str {
        match self {
            Self::NotQuantized => "input holds no quantized section (magic `MLMQ`)",
            Self::Corrupted => "quantized section checksum does not match its contents",
            Self::UnsupportedVersion { .. } => "quantized section version is not supported",
            Self::ShapeMismatch { .. } => "quantized section shape differs from the expected one",
            Self::TableMismatch => {
                "quantized section was computed from another table than the one it follows"
            }
            Self::Malformed => "quantized section does not follow the format",
            Self::Invalid { .. } => "invalid quantized section",
        }
    }
}

impl core::fmt::Display for QTableError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::NotQuantized | Self::Corrupted | Self::Malformed | Self::TableMismatch => {
                f.write_str(self.message())
            }
            Self::UnsupportedVersion { found } => write!(
                f,
                "quantized section version {found} is not supported (this build reads versions {QUANTIZED_VERSION_1} to {QUANTIZED_VERSION})"
            ),
            Self::ShapeMismatch { expected, found } => write!(
                f,
                "quantized section has {} classes and {}-bit codes; expected {} and {}",
                found.0, found.1, expected.0, expected.1
            ),
            Self::Invalid { field, class } => {
                write!(f, "invalid quantized section: class {class}: {}", field.describe())
            }
        }
    }
}

impl core::error::Error for QTableError {}

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
/// let table = Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("../../../../tables/default.mlmap"))?;
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
///
/// The accessors and the run-time [`score_into`](QTableInner::score_into) are
/// [`QTableInner`]'s, shared with the other storages of a section.
pub type QTable<'a, const K: usize, Q = i8> = QTableInner<'a, [QClass<'a>; K], [QLogit<'a>; K], Q>;

impl<'a, const K: usize, Q: Code> QTableInner<'a, [QClass<'a>; K], [QLogit<'a>; K], Q> {
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
        Ok(Self::new(meta, classes, logits))
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
    /// let q = mlmap::QTable::<3, i8>::from_bytes(include_bytes!("../../../../tables/default_q8.mlmap"))?;
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

    /// The precomputed ML mass of class `c` for code `q` (`L(x) + lambda_ML` of the
    /// dequantized `x`), as the scores use it.
    pub fn ml_mass(&self, c: usize, q: Q) -> Option<f32> {
        Some(self.view().ml_mass(self.classes.get(c)?, q.value()))
    }

    /// The precomputed MAP mass of class `c` for code `q` (`L(x) P(x) + lambda_MAP`).
    pub fn map_mass(&self, c: usize, q: Q) -> Option<f32> {
        Some(self.view().map_mass(self.classes.get(c)?, q.value()))
    }
}
