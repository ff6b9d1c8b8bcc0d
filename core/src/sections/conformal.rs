//! Conformal class sets (docs/DESIGN.md §8): class-conditional split conformal on the
//! scores of one head.
//!
//! For each class `c`, the threshold `t_c` is the `r_c`-th smallest score of class `c`
//! over the `n_c` calibration rows labelled `c`, with `r_c = floor((n_c + 1) alpha)`;
//! when `r_c = 0` (too few rows for the level) it is `-inf`. A detection's set is
//! `{c : s_c >= t_c}`, written as a bitmask: K comparisons, no allocation. With the open
//! head (or a table with a background category) an empty set says "not a known
//! object".
//!
//! The thresholds, `alpha`, the head and every `n_c` are stored in the table file's
//! conformal section (`MLMS`, docs/FORMAT.md), written by `mlmap conformal`.

use crate::diagnostics::error::{Head, InferError};
use crate::sections::{self, Missing, Reader, Writer, TRAILER_LEN};
use crate::storage::view::TableView;

/// The four bytes a conformal section starts with.
pub const CONFORMAL_MAGIC: [u8; 4] = sections::CONFORMAL;

/// The conformal section's format version this build reads and writes.
pub const CONFORMAL_VERSION: u8 = 1;

/// Bytes of the section's fixed header.
const HEADER_LEN: usize = 20;

/// Bytes of a conformal section for `k` classes.
pub const fn conformal_section_len(k: usize) -> usize {
    HEADER_LEN + 8 * k + TRAILER_LEN
}

/// Words of a set's bitmask for `k` classes (32 classes per word, class `c` in bit
/// `c % 32` of word `c / 32`).
pub const fn set_words(k: usize) -> usize {
    k.div_ceil(32)
}

/// The code of a head in the section.
const fn head_code(head: Head) -> u8 {
    match head {
        Head::Ml => 0,
        Head::Map => 1,
        Head::Bayes => 2,
        Head::Open => 3,
    }
}

const fn head_of(code: u8) -> Option<Head> {
    match code {
        0 => Some(Head::Ml),
        1 => Some(Head::Map),
        2 => Some(Head::Bayes),
        3 => Some(Head::Open),
        _ => None,
    }
}

/// The rank `r = floor((n + 1) alpha)` of a class's threshold among its `n` calibration
/// scores (1 is the smallest; 0: no threshold, `-inf`), computed in `f64` from the
/// stored `f32` alpha so that every reader agrees.
pub fn threshold_rank(n: u32, alpha: f32) -> u32 {
    let r = (f64::from(n) + 1.0) * f64::from(alpha);
    // `as` truncates toward 0, which is floor for r >= 0; it saturates, and r <= n.
    if r >= 0.0 {
        r as u32
    } else {
        0
    }
}

/// Why a conformal section was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConformalError {
    /// The bytes hold no conformal section (magic `MLMS`).
    Absent,
    /// The section's CRC does not match its contents.
    Corrupted,
    /// A section version this build does not read.
    UnsupportedVersion {
        /// The version found.
        found: u8,
    },
    /// The section's bytes do not follow the layout (an unknown head code, a reserved
    /// field that is not 0, a length other than its K implies).
    Malformed,
    /// The section thresholds a head the table does not have.
    MissingHead {
        /// The head.
        head: Head,
    },
    /// The section is for another number of classes than the table.
    ShapeMismatch {
        /// The table's K.
        expected: u16,
        /// The section's K.
        found: u16,
    },
    /// The section follows another table than the one it was written for.
    TableMismatch,
    /// `alpha` is not in `(0, 1)`.
    Alpha,
    /// A threshold is NaN, outside `[0, 1]`, or `-inf` where the class's calibration
    /// rows give a rank (or finite where they give none).
    Threshold {
        /// The class.
        class: u16,
    },
    /// The output buffer has another length than the section's (encoding).
    BufferTooSmall,
}

impl ConformalError {
    /// The variant's message: what `Display` says (with the variant's values where it
    /// has any) and what `defmt` prints.
    pub const fn message(self) -> &'static str {
        match self {
            Self::Absent => "input holds no conformal section (magic `MLMS`)",
            Self::Corrupted => "conformal section checksum does not match its contents",
            Self::UnsupportedVersion { .. } => "conformal section version is not supported",
            Self::Malformed => "conformal section is malformed",
            Self::MissingHead { .. } => "conformal section thresholds a head the table does not have",
            Self::ShapeMismatch { .. } => "conformal section is for another number of classes than the table",
            Self::TableMismatch => "conformal section was written for another table (table CRC differs)",
            Self::Alpha => "conformal alpha must be in (0, 1)",
            Self::Threshold { .. } => "a conformal threshold is NaN, outside [0, 1], or does not match its calibration rows",
            Self::BufferTooSmall => "buffer too small for the conformal section",
        }
    }
}

impl core::fmt::Display for ConformalError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Absent
            | Self::Corrupted
            | Self::Malformed
            | Self::TableMismatch
            | Self::Alpha
            | Self::BufferTooSmall => f.write_str(self.message()),
            Self::UnsupportedVersion { found } => write!(
                f,
                "conformal section version {found} is not supported (this build reads {CONFORMAL_VERSION})"
            ),
            Self::MissingHead { head } => write!(
                f,
                "conformal section thresholds the {head} head, which the table does not have"
            ),
            Self::ShapeMismatch { expected, found } => write!(
                f,
                "conformal section is for {found} classes, the table has {expected}"
            ),
            Self::Threshold { class } => write!(
                f,
                "conformal threshold of class {class} is NaN, outside [0, 1], or does not \
                 match its calibration rows"
            ),
        }
    }
}

impl core::error::Error for ConformalError {}

/// A validated conformal section: the head, `alpha` and one threshold per class.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::{ConformalSpec, Table};
///
/// // A table file with a conformal section (written by `mlmap conformal`).
/// let bytes = include_bytes!("../../../tests/golden/conformal_small.mlmap");
/// let table: Table<3, 22, 17, 22, 4> = Table::from_bytes(bytes)?;
/// let spec = ConformalSpec::from_bytes(bytes, &table.view())?;
/// let view = table.view();
/// let (mut scores, mut scratch) = ([0.0f32; 3], [0.0f32; 4]);
/// let set = spec.set64(&view, &[4.0, -1.0, -2.0], 1.0, &mut scores, &mut scratch)?;
/// // Class c is in the set when bit c is set; every class in it reached its threshold.
/// for c in 0..3 {
///     if set & (1 << c) != 0 {
///         assert!(scores[c] >= spec.threshold(c).unwrap());
///     }
/// }
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy)]
pub struct ConformalSpec<'a> {
    head: Head,
    alpha: f32,
    k: usize,
    /// `(n_c: u32, t_c: f32)` per class, little-endian.
    classes: &'a [u8],
}

impl<'a> ConformalSpec<'a> {
    /// Reads the conformal section of `bytes` (the section alone, or a table file with
    /// it among its appended sections) for `table`: checks the magic, the CRC, the
    /// version, the head (known, and one the table has), K against the table's, the
    /// table's CRC when a table precedes the section, alpha, and every threshold
    /// against its rank (`-inf` exactly when `floor((n_c + 1) alpha) = 0`, else in
    /// `[0, 1]`).
    ///
    /// # Errors
    ///
    /// A [`ConformalError`] naming the first failed check.
    ///
    /// # Panics
    ///
    /// Never, whatever the bytes.
    pub fn from_bytes<F: AsRef<[f32]>, G: AsRef<[f32]>>(
        bytes: &'a [u8],
        table: &TableView<'_, F, G>,
    ) -> Result<Self, ConformalError> {
        let (section, before) = sections::find(bytes, CONFORMAL_MAGIC).map_err(|m| match m {
            Missing::Absent => ConformalError::Absent,
            Missing::Corrupted => ConformalError::Corrupted,
        })?;
        let body = section
            .get(..section.len().saturating_sub(TRAILER_LEN))
            .unwrap_or_default();
        let mut r = Reader(body);
        let malformed = ConformalError::Malformed;
        let _magic = r.take(4).ok_or(malformed)?;
        let version = r.u8().ok_or(malformed)?;
        if version != CONFORMAL_VERSION {
            return Err(ConformalError::UnsupportedVersion { found: version });
        }
        let head = head_of(r.u8().ok_or(malformed)?).ok_or(malformed)?;
        let reserved = r.u16().ok_or(malformed)?;
        let k = r.u16().ok_or(malformed)?;
        let reserved2 = r.u16().ok_or(malformed)?;
        let table_crc = r.u32().ok_or(malformed)?;
        let alpha = r.f32().ok_or(malformed)?;
        if reserved != 0 || reserved2 != 0 {
            return Err(malformed);
        }
        if !table.has_head(head) {
            return Err(ConformalError::MissingHead { head });
        }
        let expected = u16::try_from(table.k()).unwrap_or(u16::MAX);
        if k != expected {
            return Err(ConformalError::ShapeMismatch { expected, found: k });
        }
        if sections::table_crc(before).is_some_and(|crc| crc != table_crc) {
            return Err(ConformalError::TableMismatch);
        }
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(ConformalError::Alpha);
        }
        let k = usize::from(k);
        let classes = r.take(8 * k).ok_or(malformed)?;
        if !r.is_empty() {
            return Err(malformed);
        }
        let spec = Self {
            head,
            alpha,
            k,
            classes,
        };
        for c in 0..k {
            let class = u16::try_from(c).unwrap_or(u16::MAX);
            let (n, t) = spec.entry(c).ok_or(malformed)?;
            let ok = if threshold_rank(n, alpha) == 0 {
                t == f32::NEG_INFINITY
            } else {
                (0.0..=1.0).contains(&t)
            };
            if !ok {
                return Err(ConformalError::Threshold { class });
            }
        }
        Ok(spec)
    }

    fn entry(&self, c: usize) -> Option<(u32, f32)> {
        let e = self.classes.get(8 * c..8 * c + 8)?;
        let mut r = Reader(e);
        Some((r.u32()?, r.f32()?))
    }

    /// Number of classes K.
    #[inline]
    pub fn k(&self) -> usize {
        self.k
    }

    /// The head whose scores the sets threshold.
    #[inline]
    pub fn head(&self) -> Head {
        self.head
    }

    /// The miscoverage level `alpha` the thresholds were chosen for.
    #[inline]
    pub fn alpha(&self) -> f32 {
        self.alpha
    }

    /// The threshold `t_c` of class `c` (`-inf`: the class is in every set).
    pub fn threshold(&self, c: usize) -> Option<f32> {
        self.entry(c).map(|(_, t)| t)
    }

    /// The calibration rows `n_c` labelled `c` its threshold was taken over.
    pub fn calibration_rows(&self, c: usize) -> Option<u32> {
        self.entry(c).map(|(n, _)| n)
    }

    /// The set of a detection's K scores of the section's head: bit `c % 32` of
    /// `mask[c / 32]` is 1 when `scores[c] >= t_c`; returns the set's size. `mask`
    /// holds at least [`set_words`]`(K)` words; words past them are left alone.
    ///
    /// # Errors
    ///
    /// [`InferError::Length`] for `scores` of another length or a short `mask`,
    /// [`InferError::NanScore`] for a NaN score; nothing is written then.
    #[inline]
    pub fn set_of(&self, scores: &[f32], mask: &mut [u32]) -> Result<u32, InferError> {
        let words = set_words(self.k);
        let mask = mask.get_mut(..words).ok_or(InferError::Length)?;
        if scores.len() != self.k {
            return Err(InferError::Length);
        }
        if let Some(c) = scores.iter().position(|s| s.is_nan()) {
            return Err(InferError::NanScore {
                class: u16::try_from(c).unwrap_or(u16::MAX),
            });
        }
        mask.fill(0);
        let mut size = 0u32;
        for (c, (&s, e)) in scores.iter().zip(self.classes.chunks_exact(8)).enumerate() {
            let t = e
                .get(4..8)
                .and_then(|b| <[u8; 4]>::try_from(b).ok())
                .map_or(f32::INFINITY, f32::from_le_bytes);
            let inside = s >= t;
            if let Some(w) = mask.get_mut(c / 32) {
                *w |= u32::from(inside) << (c % 32);
            }
            size += u32::from(inside);
        }
        Ok(size)
    }

    /// Scores one detection with the section's head ([`TableView::score_into`], the
    /// device's default backend) into `scores` and writes its set into `mask`; returns
    /// the set's size. `scratch` is as [`TableView::score_into`] needs.
    ///
    /// # Errors
    ///
    /// As [`TableView::score_into`] and [`ConformalSpec::set_of`].
    #[inline]
    pub fn score_set<F: AsRef<[f32]>, G: AsRef<[f32]>>(
        &self,
        table: &TableView<'_, F, G>,
        logits: &[f32],
        objectness: f32,
        scores: &mut [f32],
        scratch: &mut [f32],
        mask: &mut [u32],
    ) -> Result<u32, InferError> {
        if table.k() != self.k || mask.len() < set_words(self.k) {
            return Err(InferError::Length);
        }
        table.score_into(self.head, logits, objectness, scores, scratch)?;
        self.set_of(scores, mask)
    }

    /// As [`ConformalSpec::score_set`] for K at most 64: the set as one `u64`, class `c`
    /// in bit `c`.
    ///
    /// # Errors
    ///
    /// As [`ConformalSpec::score_set`]; [`InferError::Length`] for K above 64.
    #[inline]
    pub fn set64<F: AsRef<[f32]>, G: AsRef<[f32]>>(
        &self,
        table: &TableView<'_, F, G>,
        logits: &[f32],
        objectness: f32,
        scores: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<u64, InferError> {
        let mut mask = [0u32; 2];
        if self.k > 64 {
            return Err(InferError::Length);
        }
        self.score_set(table, logits, objectness, scores, scratch, &mut mask)?;
        let [lo, hi] = mask;
        Ok(u64::from(lo) | (u64::from(hi) << 32))
    }
}

/// Writes a conformal section into `out` (exactly [`conformal_section_len`]`(K)` bytes)
/// for a table whose CRC is `table_crc`: the head, `alpha`, and per class its
/// calibration rows `rows[c]` and threshold `thresholds[c]`. Read back by
/// [`ConformalSpec::from_bytes`], which checks it.
///
/// # Errors
///
/// [`ConformalError::BufferTooSmall`] for a buffer of another length;
/// [`ConformalError::Malformed`] for `rows` and `thresholds` of different lengths or a K
/// beyond `u16`.
pub fn write_conformal_section(
    out: &mut [u8],
    table_crc: u32,
    head: Head,
    alpha: f32,
    rows: &[u32],
    thresholds: &[f32],
) -> Result<(), ConformalError> {
    let k = rows.len();
    if thresholds.len() != k {
        return Err(ConformalError::Malformed);
    }
    let Ok(k16) = u16::try_from(k) else {
        return Err(ConformalError::Malformed);
    };
    if out.len() != conformal_section_len(k) {
        return Err(ConformalError::BufferTooSmall);
    }
    let mut w = Writer { buf: out, at: 0 };
    (|| {
        w.put(&CONFORMAL_MAGIC)?;
        w.u8(CONFORMAL_VERSION)?;
        w.u8(head_code(head))?;
        w.u16(0)?;
        w.u16(k16)?;
        w.u16(0)?;
        w.u32(table_crc)?;
        w.f32(alpha)?;
        for (&n, &t) in rows.iter().zip(thresholds) {
            w.u32(n)?;
            w.f32(t)?;
        }
        Some(())
    })()
    .ok_or(ConformalError::BufferTooSmall)?;
    sections::seal(out).ok_or(ConformalError::BufferTooSmall)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranks() {
        assert_eq!(threshold_rank(0, 0.1), 0);
        assert_eq!(threshold_rank(8, 0.1), 0);
        assert_eq!(threshold_rank(9, 0.1), 1);
        assert_eq!(threshold_rank(99, 0.05), 5);
        assert_eq!(threshold_rank(19, 0.05), 1);
    }

    #[test]
    fn words() {
        assert_eq!(set_words(1), 1);
        assert_eq!(set_words(32), 1);
        assert_eq!(set_words(33), 2);
    }
}
