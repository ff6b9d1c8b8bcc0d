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

use crate::error::{DecodeError, EncodeError, Head, TableError};
use crate::gaussian::{Gaussian, GaussianError};
use crate::histogram::{Axis, EdgeMode, Histogram, HistogramError, UpperTail};
use crate::name::{ClassName, NameError, NAME_MAX};
use crate::recal::{Knot, Maps};
use crate::view::TableView;

mod parse;

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
            edge_mode: match s.edge_mode {
                EdgeMode::Linspace => 0,
                EdgeMode::Matlab => 1,
            },
            upper_tail: match s.upper_tail {
                UpperTail::Zero => 0,
                UpperTail::Clamp => 1,
            },
            lambda_ml: s.lambda_ml,
            lambda_map: s.lambda_map,
        }
    }

    fn to_settings(&self) -> Result<Settings, DecodeError> {
        let edge_mode = match self.edge_mode {
            0 => EdgeMode::Linspace,
            1 => EdgeMode::Matlab,
            _ => return Err(DecodeError::Malformed),
        };
        let upper_tail = match self.upper_tail {
            0 => UpperTail::Zero,
            1 => UpperTail::Clamp,
            _ => return Err(DecodeError::Malformed),
        };
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

/// Serialises the classes `0..k` produced by `class` as one postcard sequence.
struct ClassSeq<F> {
    k: usize,
    class: F,
}

impl<'a, F> Serialize for ClassSeq<F>
where
    F: Fn(usize) -> Option<ClassWire<'a, &'a [f32], &'a [f32]>>,
{
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::{Error, SerializeSeq};
        let mut seq = s.serialize_seq(Some(self.k))?;
        for i in 0..self.k {
            let class = (self.class)(i).ok_or_else(|| S::Error::custom("class out of range"))?;
            seq.serialize_element(&class)?;
        }
        seq.end()
    }
}

/// The message [`encode`] writes before the CRC, for the table `view`: a version-1
/// message without a Bayes head, a version-2 message with one. Postcard writes a tuple
/// as its elements in order, with no length.
struct Message<'v, 'a, F, G>(&'v TableView<'a, F, G>);

impl<F: AsRef<[f32]>, G: AsRef<[f32]>> Serialize for Message<'_, '_, F, G> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        let view = self.0;
        let narrow = |n: usize| u16::try_from(n).unwrap_or(u16::MAX);
        let k = view.k();
        let mut t = s.serialize_tuple(15)?;
        t.serialize_element(&MAGIC)?;
        let bayes = view.bayes();
        let open = bayes.and_then(|b| b.open());
        // Version 4 for a map or the objectness feature.
        let maps = view.maps.any() || bayes.is_some_and(|b| b.objectness.is_some());
        t.serialize_element(&match (maps, bayes.is_some(), open.is_some()) {
            (true, _, _) => FORMAT_VERSION,
            (false, false, _) => VERSION_1,
            (false, true, false) => VERSION_2,
            (false, true, true) => VERSION_3,
        })?;
        t.serialize_element(&narrow(k))?;
        t.serialize_element(&narrow(view.bins_ml()))?;
        t.serialize_element(&narrow(view.bins_map()))?;
        match &bayes {
            Some(b) => {
                t.serialize_element(&narrow(b.bins()))?;
                t.serialize_element(&narrow(b.categories()))?;
            }
            None if maps => t.serialize_element(&(0u16, 0u16))?,
            None => {}
        }
        t.serialize_element(&SettingsWire::from_settings(view.settings()))?;
        t.serialize_element(&ClassSeq {
            k,
            class: |i| {
                let c = view.spec(i)?;
                Some(ClassWire {
                    name: c.name,
                    rows: c.rows,
                    mean: c.mean,
                    variance: c.variance,
                    ml_lo: c.ml_range.0,
                    ml_hi: c.ml_range.1,
                    ml_freqs: c.ml_freqs,
                    map_lo: c.map_range.0,
                    map_hi: c.map_range.1,
                    map_freqs: c.map_freqs,
                })
            },
        })?;
        if let Some(b) = &bayes {
            t.serialize_element(&b.lambda())?;
            t.serialize_element(b.all_rows())?;
            t.serialize_element(&AxesSeq(b.axes()))?;
            t.serialize_element(b.all_terms())?;
        }
        if maps {
            if let Some(b) = &bayes {
                let feature = b
                    .objectness
                    .map(|(a, terms)| ((a.lo, a.hi), FloatsSeq(terms)));
                t.serialize_element(&feature)?;
                t.serialize_element(&open.map(|o| (o.temperature(), o.epsilon())))?;
            }
            t.serialize_element(&MapsSeq(view.maps))?;
        } else if let Some(o) = &open {
            t.serialize_element(&o.temperature())?;
            t.serialize_element(&o.epsilon())?;
        }
        t.end()
    }
}

/// The maps on the wire: a sequence of `(head code, knots)` records, one per head that
/// has a map, in slot order.
struct MapsSeq<'a>(Maps<'a>);

impl Serialize for MapsSeq<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let records = self.0 .0.iter().filter(|k| !k.is_empty()).count();
        let mut seq = s.serialize_seq(Some(records))?;
        for (slot, knots) in self.0 .0.iter().enumerate() {
            if !knots.is_empty() {
                let code = u8::try_from(slot).unwrap_or(u8::MAX);
                seq.serialize_element(&(code, KnotsSeq(knots)))?;
            }
        }
        seq.end()
    }
}

/// A sequence of floats on the wire (the objectness feature's terms).
struct FloatsSeq<'a>(&'a [f32]);

impl Serialize for FloatsSeq<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for v in self.0 {
            seq.serialize_element(v)?;
        }
        seq.end()
    }
}

/// One map's knots on the wire: a sequence of `(x, y)` pairs.
struct KnotsSeq<'a>(&'a [Knot]);

impl Serialize for KnotsSeq<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for k in self.0 {
            seq.serialize_element(&(k.x, k.y))?;
        }
        seq.end()
    }
}

/// The axes of a Bayes head on the wire: a sequence of `(lo, hi)` pairs.
struct AxesSeq<'a>(&'a [Axis]);

impl Serialize for AxesSeq<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let mut seq = s.serialize_seq(Some(self.0.len()))?;
        for a in self.0 {
            seq.serialize_element(&(a.lo, a.hi))?;
        }
        seq.end()
    }
}

/// Encodes a validated table.
pub(crate) fn encode<'b, F: AsRef<[f32]>, G: AsRef<[f32]>>(
    view: &TableView<'_, F, G>,
    buf: &'b mut [u8],
) -> Result<&'b mut [u8], EncodeError> {
    postcard::to_slice_crc32(&Message(view), buf, CRC.digest())
        .map_err(|_| EncodeError::BufferTooSmall)
}

/// The CRC-32 [`encode`] stores in the last four bytes of `view`'s encoding, computed
/// without writing the encoding anywhere (the quantized section records it, to name the
/// table it was computed from).
pub(crate) fn table_crc<F: AsRef<[f32]>, G: AsRef<[f32]>>(view: &TableView<'_, F, G>) -> u32 {
    /// A postcard output that only feeds the checksum.
    struct Digest<'d>(crc::Digest<'d, u32>);
    impl postcard::ser_flavors::Flavor for Digest<'_> {
        type Output = u32;
        fn try_push(&mut self, data: u8) -> postcard::Result<()> {
            self.0.update(&[data]);
            Ok(())
        }
        fn try_extend(&mut self, data: &[u8]) -> postcard::Result<()> {
            self.0.update(data);
            Ok(())
        }
        fn finalize(self) -> postcard::Result<u32> {
            Ok(self.0.finalize())
        }
    }
    // Serialising a validated table into this output cannot fail.
    postcard::serialize_with_flavor(&Message(view), Digest(CRC.digest())).unwrap_or(0)
}

/// Number of bytes [`encode`] writes for `view`, CRC included.
pub(crate) fn encoded_len<F: AsRef<[f32]>, G: AsRef<[f32]>>(
    view: &TableView<'_, F, G>,
) -> Option<usize> {
    postcard::serialize_with_flavor(&Message(view), postcard::ser_flavors::Size::default())
        .ok()?
        .checked_add(CRC_LEN)
}

/// Checks that a decoded table came from exactly the bytes [`encode`] writes for it:
/// postcard reads a varint written in more bytes than needed (`0x84 0x00` for 4), and
/// such a non-canonical input would decode to a table whose encoding differs. Only the
/// lengths need comparing: every other field has a fixed size and decodes losslessly,
/// an overlong varint only ever adds bytes, and the version is fixed by whether the
/// table has a Bayes head and the open head's parameters, which the header announced. Measures, writes nothing.
pub(crate) fn check_canonical<F: AsRef<[f32]>, G: AsRef<[f32]>>(
    len: usize,
    view: &TableView<'_, F, G>,
) -> Result<(), DecodeError> {
    if encoded_len(view) != Some(len) {
        return Err(DecodeError::Malformed);
    }
    Ok(())
}

/// Bytes a postcard varint needs for `n`.
const fn varint_len(n: usize) -> usize {
    let mut len = 1;
    let mut v = n >> 7;
    while v > 0 {
        len += 1;
        v >>= 7;
    }
    len
}

/// Shortest possible table: magic, one-byte version and shape, settings, K = 0, CRC.
const MIN_ENCODED_LEN: usize = MAGIC.len() + 4 + 10 + 1 + CRC_LEN;

/// Upper bound of the encoded size of a table with `k` classes, the given bin counts,
/// `categories` Bayes categories (0 and 0 without a Bayes head; with one, the open head's
/// parameters are counted too) and maps of at most `knots` knots (0: none) for every
/// head; every name [`NAME_MAX`] bytes, every row count the largest `u64`.
pub(crate) const fn max_encoded_len(
    k: usize,
    bins_ml: usize,
    bins_map: usize,
    bins_bayes: usize,
    categories: usize,
    knots: usize,
    features: usize,
) -> usize {
    let maps = if knots == 0 && features == 0 {
        0
    } else {
        let os_terms = bins_bayes * categories;
        2 * varint_len(u16::MAX as usize) // the Bayes shape, (0, 0) without that head
            + 1 // the open head's option
            + 1 // the number of maps
            + 4 * (1 + varint_len(knots) + 8 * knots)
            + 1 // the objectness feature's option
            + features * (8 + varint_len(os_terms) + 4 * os_terms)
    };
    let bayes = if bins_bayes == 0 {
        0
    } else {
        let terms = categories * k * bins_bayes;
        2 * varint_len(u16::MAX as usize) // Bayes shape in the header
            + 4 // lambda
            + varint_len(categories) + 10 * categories
            + varint_len(k) + 8 * k
            + varint_len(terms) + 4 * terms
            + 4 * 2 // the open head: temperature, epsilon
    };
    let header = MAGIC.len() + 4 * varint_len(u16::MAX as usize);
    let settings = 2 + 4 + 4;
    let per_class = varint_len(NAME_MAX) + NAME_MAX
        + 10 // rows, varint u64
        + 4 * 2 // mean, variance
        + 4 * 2 + varint_len(bins_ml) + 4 * bins_ml
        + 4 * 2 + varint_len(bins_map) + 4 * bins_map;
    header + settings + varint_len(k) + k * per_class + bayes + maps + CRC_LEN
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// The shipped table with the first class's row count rewritten as an overlong
    /// varint (one byte more than needed) and the CRC recomputed.
    fn overlong_rows() -> Vec<u8> {
        let bytes = include_bytes!("../../tests/golden/train_linspace.mlmap");
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
        let bytes = include_bytes!("../../tests/golden/train_linspace.mlmap");
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
