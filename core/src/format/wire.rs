//! The `.mlmap` wire format, versions 1 to 3 (`docs/FORMAT.md` is the normative
//! description).
//!
//! A table is one postcard message followed by a CRC-32:
//!
//! ```text
//! Header   magic "MLMP" (4 raw bytes), version, K, ML bins, MAP bins (varint u16 each);
//!          version 2 adds Bayes bins and Bayes categories (varint u16 each, both > 0)
//! Settings edge mode (u8), upper tail (u8), lambda ML (f32 LE), lambda MAP (f32 LE)
//! Classes  varint K, then per class: name (varint length + UTF-8), rows (varint u64),
//!          mean, variance, ML lo, ML hi (f32 LE), ML frequencies (varint B + B f32 LE),
//!          MAP lo, MAP hi (f32 LE), MAP frequencies (varint B + B f32 LE)
//! Bayes    version 2 only: lambda (f32 LE), rows per category (varint C + C varint
//!          u64), per logit its lo and hi (varint K + K pairs of f32 LE), the log-terms
//!          (varint K*B*C + K*B*C f32 LE, logit-major: logit, then bin, then category)
//! Feature  version 4 with a Bayes head: the objectness feature, an option (0, or 1
//!          then its axis (lo, hi) and its B*C terms, varint length + f32 LE)
//! Open     version 3: temperature, epsilon (f32 LE each); version 4, with a Bayes
//!          head: an option (0, or 1 then temperature and epsilon)
//! Maps     version 4 only: varint n >= 1, then n records (head code u8, strictly
//!          increasing: 0 ML, 1 MAP, 2 Bayes, 3 open; varint knots + (x, y) f32 LE pairs)
//! CRC      CRC-32/ISO-HDLC (zlib's crc32) of every byte before it, 4 bytes LE
//! ```
//!
//! Version 4's header always holds the Bayes shape, `(0, 0)` without a Bayes head.
//! A table with a recalibration map or the objectness feature is written as version
//! 4; without either, a table
//! without a Bayes head is written as version 1, a table with one as version 2, a table
//! with a Bayes head and the open head's parameters as version 3: each table has exactly
//! one encoding.
//!
//! This module is shared by the layer, the host table and `build.rs`; it depends on
//! nothing but `core`, serde and postcard, and never allocates: the class sequence type
//! `C` is chosen by the caller (`heapless::Vec` on the device, `Vec` on the host).

use serde::{Deserialize, Serialize};

use crate::diagnostics::error::{DecodeError, Head, TableError};
use crate::format::name::{ClassName, NameError};
use crate::math::gaussian::{Gaussian, GaussianError};
use crate::math::histogram::{EdgeMode, Histogram, HistogramError, UpperTail};

mod encode;
mod parse;

pub(crate) use encode::{check_canonical, encode, encoded_len, max_encoded_len, table_crc};
pub use parse::locate_malformed;
#[cfg(test)]
pub(crate) use parse::parse_body;
pub(crate) use parse::{parse_body_into, BayesSlots, BodySink, ClassFields, Parts};

/// The four bytes every table starts with.
pub const MAGIC: [u8; 4] = *b"MLMP";

/// The newest format version: this build writes it for tables with a recalibration map
/// (DESIGN §1.9), and reads it and every older version (a version-1 table has no Bayes
/// head, a version-2 table no open head, a version-3 table no map).
pub const FORMAT_VERSION: u16 = 4;

/// The version of tables without a Bayes head.
const VERSION_1: u16 = 1;
/// The version of tables with a Bayes head and no open head.
const VERSION_2: u16 = 2;
/// The version of tables with the open head and no map.
const VERSION_3: u16 = 3;

/// Largest smoothing lambda a table may hold. Frequencies are at most 1 and priors at
/// most about `4e18`, so with `lambda <= 1e6` no sum of K terms can overflow `f32`.
pub const MAX_LAMBDA: f32 = 1.0e6;

/// The checksum: CRC-32/ISO-HDLC, the CRC of zlib, PNG and Ethernet.
pub(crate) const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// The same checksum computed bit by bit, for checking a table when it is decoded: no
/// 1 KiB lookup table in flash (decoding checks a few hundred bytes once, at start-up).
/// The table-driven [`CRC`] is only linked in by encoding.
pub(crate) const CRC_CHECK: crc::Crc<u32, crc::NoTable> =
    crc::Crc::<u32, crc::NoTable>::new(&crc::CRC_32_ISO_HDLC);

/// Length of the trailing checksum.
const CRC_LEN: usize = 4;

/// Shortest possible table: magic, one-byte version and shape, settings, K = 0, CRC.
const MIN_ENCODED_LEN: usize = MAGIC.len() + 4 + 10 + 1 + CRC_LEN;

/// Hyper-parameters and policies of a table (everything but the per-class statistics).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Additive smoothing of the ML head, in `(0, MAX_LAMBDA]`.
    pub lambda_ml: f32,
    /// Additive smoothing of the MAP head, in `(0, MAX_LAMBDA]`.
    pub lambda_map: f32,
    /// How the fit placed the edges (informational).
    pub edge_mode: EdgeMode,
    /// What the likelihood is above the last edge.
    pub upper_tail: UpperTail,
}

impl Settings {
    /// All zeros (invalid), for storage that is filled before use.
    pub(crate) const ZERO: Self = Self {
        lambda_ml: 0.0,
        lambda_map: 0.0,
        edge_mode: EdgeMode::Linspace,
        upper_tail: UpperTail::Zero,
    };

    /// Checks both lambdas.
    pub(crate) fn validate(&self) -> Result<(), TableError> {
        let ok = |l: f32| l > 0.0 && l <= MAX_LAMBDA;
        if !ok(self.lambda_ml) {
            return Err(TableError::Lambda { head: Head::Ml });
        }
        if !ok(self.lambda_map) {
            return Err(TableError::Lambda { head: Head::Map });
        }
        Ok(())
    }
}

/// The statistics of one class, as fitted, before validation.
///
/// `F` and `G` hold the ML and MAP frequencies (`[f32; B]` for a [`Table`](crate::Table),
/// `Vec<f32>` on the host).
#[derive(Debug, Clone, PartialEq)]
pub struct ClassSpec<'a, F, G> {
    /// Class name (see [`check_class_name`](crate::check_class_name) for the rules).
    pub name: &'a str,
    /// Number of training rows the class was fitted from (provenance).
    pub rows: u64,
    /// Mean of the Gaussian prior.
    pub mean: f32,
    /// Variance of the Gaussian prior (> 0).
    pub variance: f32,
    /// First and last edge of the ML histogram.
    pub ml_range: (f32, f32),
    /// Frequencies of the ML histogram.
    pub ml_freqs: F,
    /// First and last edge of the MAP histogram.
    pub map_range: (f32, f32),
    /// Frequencies of the MAP histogram.
    pub map_freqs: G,
}

/// A validated class: name, provenance, prior and both histograms.
pub(crate) struct ValidClass<F, G> {
    pub(crate) name: ClassName,
    pub(crate) rows: u64,
    pub(crate) prior: Gaussian,
    pub(crate) ml: Histogram<F>,
    pub(crate) map: Histogram<G>,
}

impl<'a, F: AsRef<[f32]>, G: AsRef<[f32]>> ClassSpec<'a, F, G> {
    /// Validates class `i` of a table being built against every per-class invariant,
    /// its name against the whole name rule (DESIGN §6.15); bin counts must be
    /// `bins_ml` and `bins_map`. (`DynTable::new`'s; a fixed-size table passes its own
    /// storage to [`ClassSpec::validate_with`].)
    #[cfg(feature = "alloc")]
    pub(crate) fn validate(
        self,
        i: usize,
        bins_ml: usize,
        bins_map: usize,
    ) -> Result<ValidClass<F, G>, TableError> {
        self.validate_with(i, bins_ml, bins_map, ClassName::checked)
    }

    /// As [`validate`](Self::validate) for a class as decoded, whose name only needs
    /// what every format version holds ([`ClassName::stored`]); the decoder checks the
    /// whole name rule separately, by format version.
    pub(crate) fn validate_decoded(
        self,
        i: usize,
        bins_ml: usize,
        bins_map: usize,
    ) -> Result<ValidClass<F, G>, TableError> {
        self.validate_with(i, bins_ml, bins_map, ClassName::stored)
    }

    /// [`validate`](Self::validate) with the name stored by `store`.
    pub(crate) fn validate_with(
        self,
        i: usize,
        bins_ml: usize,
        bins_map: usize,
        store: fn(&str) -> Result<ClassName, NameError>,
    ) -> Result<ValidClass<F, G>, TableError> {
        let class = u16::try_from(i).map_err(|_| TableError::ClassCount)?;
        let name = store(self.name).map_err(|error| TableError::Name { class, error })?;
        if self.ml_freqs.as_ref().len() != bins_ml {
            return Err(TableError::BinCount {
                head: Head::Ml,
                class,
            });
        }
        if self.map_freqs.as_ref().len() != bins_map {
            return Err(TableError::BinCount {
                head: Head::Map,
                class,
            });
        }
        let hist_err = |head| {
            move |e| match e {
                HistogramError::Edges => TableError::Edges { head, class },
                HistogramError::Frequencies => TableError::Frequencies { head, class },
            }
        };
        let ml = Histogram::new(self.ml_range.0, self.ml_range.1, self.ml_freqs)
            .map_err(hist_err(Head::Ml))?;
        let map = Histogram::new(self.map_range.0, self.map_range.1, self.map_freqs)
            .map_err(hist_err(Head::Map))?;
        let prior = Gaussian::new(self.mean, self.variance).map_err(|e| match e {
            GaussianError::Mean => TableError::Mean { class },
            GaussianError::Variance => TableError::Variance { class },
        })?;
        Ok(ValidClass {
            name,
            rows: self.rows,
            prior,
            ml,
            map,
        })
    }
}

/// The fixed part at the start of every table, as read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Header {
    pub(crate) version: u16,
    pub(crate) k: u16,
    pub(crate) bins_ml: u16,
    pub(crate) bins_map: u16,
    /// 0 when the table has no Bayes head (version 1).
    pub(crate) bins_bayes: u16,
    /// 0 when the table has no Bayes head (version 1).
    pub(crate) categories: u16,
    /// Whether the open head's parameters follow the Bayes section (version 3).
    pub(crate) open: bool,
    /// Whether the body ends with the open head's option and the maps (version 4).
    pub(crate) maps: bool,
}

impl Header {
    /// `(K, ML bins, MAP bins)`.
    pub(crate) fn shape(&self) -> (u16, u16, u16) {
        (self.k, self.bins_ml, self.bins_map)
    }

    /// `(Bayes bins, Bayes categories)`, `(0, 0)` without a Bayes head.
    pub(crate) fn bayes_shape(&self) -> (u16, u16) {
        (self.bins_bayes, self.categories)
    }

    /// The body's optional parts.
    pub(crate) fn parts(&self) -> Parts {
        Parts {
            bayes: self.bins_bayes > 0,
            open: self.open,
            maps: self.maps,
        }
    }
}

#[derive(Serialize, Deserialize)]
struct SettingsWire {
    edge_mode: u8,
    upper_tail: u8,
    lambda_ml: f32,
    lambda_map: f32,
}

impl SettingsWire {
    fn from_settings(s: &Settings) -> Self {
        Self {
            edge_mode: s.edge_mode.code(),
            upper_tail: s.upper_tail.code(),
            lambda_ml: s.lambda_ml,
            lambda_map: s.lambda_map,
        }
    }

    fn to_settings(&self) -> Result<Settings, DecodeError> {
        let edge_mode = EdgeMode::from_code(self.edge_mode).ok_or(DecodeError::Malformed)?;
        let upper_tail = UpperTail::from_code(self.upper_tail).ok_or(DecodeError::Malformed)?;
        let s = Settings {
            lambda_ml: self.lambda_ml,
            lambda_map: self.lambda_map,
            edge_mode,
            upper_tail,
        };
        s.validate()?;
        Ok(s)
    }
}

/// One class on the wire; `V`, `W` are the frequency sequences.
#[derive(Serialize, Deserialize)]
pub(crate) struct ClassWire<'a, V, W> {
    #[serde(borrow)]
    name: &'a str,
    rows: u64,
    mean: f32,
    variance: f32,
    ml_lo: f32,
    ml_hi: f32,
    ml_freqs: V,
    map_lo: f32,
    map_hi: f32,
    map_freqs: W,
}

// Only a test oracle decodes through `ClassWire` (and `parse_body`).
#[cfg(test)]
impl<'a, V, W> ClassWire<'a, V, W> {
    pub(crate) fn into_spec(self) -> ClassSpec<'a, V, W> {
        ClassSpec {
            name: self.name,
            rows: self.rows,
            mean: self.mean,
            variance: self.variance,
            ml_range: (self.ml_lo, self.ml_hi),
            ml_freqs: self.ml_freqs,
            map_range: (self.map_lo, self.map_hi),
            map_freqs: self.map_freqs,
        }
    }
}

/// Everything after the header and before the CRC of a version-1 table (a test oracle
/// for [`parse_body_into`]).
#[cfg(test)]
#[derive(Deserialize)]
struct BodyWire<C> {
    settings: SettingsWire,
    classes: C,
}

/// Checks magic, checksum and version; returns the header and the body bytes.
pub(crate) fn open(bytes: &[u8]) -> Result<(Header, &[u8]), DecodeError> {
    let prefix = bytes.get(..MAGIC.len()).unwrap_or(bytes);
    if prefix != MAGIC.get(..prefix.len()).unwrap_or(&MAGIC) {
        return Err(DecodeError::NotATable);
    }
    if bytes.len() < MIN_ENCODED_LEN {
        return Err(DecodeError::Truncated);
    }
    let (payload, stored) = bytes.split_at(bytes.len() - CRC_LEN);
    let mut crc = [0u8; CRC_LEN];
    for (d, s) in crc.iter_mut().zip(stored) {
        *d = *s;
    }
    if CRC_CHECK.checksum(payload) != u32::from_le_bytes(crc) {
        return Err(DecodeError::Corrupted);
    }
    let malformed = |_| DecodeError::Malformed;
    let ((_magic, version), rest) =
        postcard::take_from_bytes::<([u8; 4], u16)>(payload).map_err(malformed)?;
    if !(VERSION_1..=FORMAT_VERSION).contains(&version) {
        return Err(DecodeError::UnsupportedVersion { found: version });
    }
    let ((k, bins_ml, bins_map), mut body) =
        postcard::take_from_bytes::<(u16, u16, u16)>(rest).map_err(malformed)?;
    let mut header = Header {
        version,
        k,
        bins_ml,
        bins_map,
        bins_bayes: 0,
        categories: 0,
        open: version == VERSION_3,
        maps: version == FORMAT_VERSION,
    };
    if version >= VERSION_2 {
        let ((bins, categories), rest) =
            postcard::take_from_bytes::<(u16, u16)>(body).map_err(malformed)?;
        // Versions 2 and 3 are only ever written for a table with a Bayes head; version
        // 4 stores (0, 0) for a table without one.
        let none = bins == 0 && categories == 0;
        if (bins == 0 || categories == 0) && !(none && version == FORMAT_VERSION) {
            return Err(DecodeError::Malformed);
        }
        (header.bins_bayes, header.categories, body) = (bins, categories, rest);
    }
    Ok((header, body))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// The shipped table with the first class's row count rewritten as an overlong
    /// varint (one byte more than needed) and the CRC recomputed.
    fn overlong_rows() -> Vec<u8> {
        let bytes = include_bytes!("../../../tests/golden/train_linspace.mlmap");
        // magic, version/K/bins (one byte each), settings, K, name length, "car", rows.
        let rows_at = 4 + 4 + 10 + 1 + 1 + 3;
        assert_eq!(&bytes[rows_at - 3..rows_at], b"car");
        let len = bytes[rows_at..].iter().position(|b| b & 0x80 == 0).unwrap() + 1;
        let mut out = bytes[..rows_at + len - 1].to_vec();
        out.push(bytes[rows_at + len - 1] | 0x80);
        out.push(0x00);
        out.extend_from_slice(&bytes[rows_at + len..bytes.len() - CRC_LEN]);
        let crc = CRC.checksum(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    /// Found by the `decode` fuzz target: a varint written in more bytes than needed
    /// decoded to a table whose own encoding is different (two files for one table).
    #[test]
    fn non_canonical_varint_is_rejected() {
        let bytes = include_bytes!("../../../tests/golden/train_linspace.mlmap");
        let table = crate::Table::<3, 22, 17>::from_bytes(bytes).unwrap();
        let mut buf = [0u8; crate::Table::<3, 22, 17>::MAX_ENCODED_LEN];
        assert_eq!(table.to_slice(&mut buf).unwrap(), &bytes[..]);
        let overlong = overlong_rows();
        assert_eq!(overlong.len(), bytes.len() + 1);
        assert_eq!(
            crate::Table::<3, 22, 17>::from_bytes(&overlong),
            Err(DecodeError::Malformed)
        );
        #[cfg(feature = "alloc")]
        assert_eq!(
            crate::DynTable::from_bytes(&overlong),
            Err(DecodeError::Malformed)
        );
    }
}
