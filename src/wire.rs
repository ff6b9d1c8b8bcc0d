//! The `.mlmap` wire format, version 1 (`docs/FORMAT.md` is the normative description).
//!
//! A table is one postcard message followed by a CRC-32:
//!
//! ```text
//! Header   magic "MLMP" (4 raw bytes), version, K, ML bins, MAP bins (varint u16 each)
//! Settings edge mode (u8), upper tail (u8), lambda ML (f32 LE), lambda MAP (f32 LE)
//! Classes  varint K, then per class: name (varint length + UTF-8), rows (varint u64),
//!          mean, variance, ML lo, ML hi (f32 LE), ML frequencies (varint B + B f32 LE),
//!          MAP lo, MAP hi (f32 LE), MAP frequencies (varint B + B f32 LE)
//! CRC      CRC-32/ISO-HDLC (zlib's crc32) of every byte before it, 4 bytes LE
//! ```
//!
//! This module is shared by the layer, the host table and `build.rs`; it depends on
//! nothing but `core`, serde and postcard, and never allocates: the class sequence type
//! `C` is chosen by the caller (`heapless::Vec` on the device, `Vec` on the host).

use core::fmt;

use serde::de::{DeserializeSeed, Deserializer, Error as _, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};

use crate::error::{DecodeError, EncodeError, Head, TableError};
use crate::gaussian::{Gaussian, GaussianError};
use crate::histogram::{EdgeMode, Histogram, HistogramError, UpperTail};
use crate::name::{ClassName, NAME_MAX};

/// The four bytes every table starts with.
pub const MAGIC: [u8; 4] = *b"MLMP";

/// The format version this build writes and reads.
pub const FORMAT_VERSION: u16 = 1;

/// Largest smoothing lambda a table may hold. Frequencies are at most 1 and priors at
/// most about `4e18`, so with `lambda <= 1e6` no sum of K terms can overflow `f32`.
pub const MAX_LAMBDA: f32 = 1.0e6;

/// The checksum: CRC-32/ISO-HDLC, the CRC of zlib, PNG and Ethernet.
pub(crate) const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// The same checksum computed bit by bit, for checking a table when it is decoded: no
/// 1 KiB lookup table in flash (decoding checks a few hundred bytes once, at start-up).
/// The table-driven [`CRC`] is only linked in by encoding.
const CRC_CHECK: crc::Crc<u32, crc::NoTable> =
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
    /// Class name (see [`ClassName::new`] for the rules).
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
    /// Validates class `i` against every per-class invariant; bin counts must be
    /// `bins_ml` and `bins_map`.
    pub(crate) fn validate(
        self,
        i: usize,
        bins_ml: usize,
        bins_map: usize,
    ) -> Result<ValidClass<F, G>, TableError> {
        let class = u16::try_from(i).map_err(|_| TableError::ClassCount)?;
        let name = ClassName::new(self.name).ok_or(TableError::Name { class })?;
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

/// Checks that no name repeats an earlier one (O(K^2), decode time only).
pub(crate) fn check_unique_names(names: &[ClassName]) -> Result<(), TableError> {
    for (i, n) in names.iter().enumerate() {
        if names.iter().take(i).any(|m| m == n) {
            return Err(TableError::DuplicateName {
                class: u16::try_from(i).unwrap_or(u16::MAX),
            });
        }
    }
    Ok(())
}

/// The fixed part at the start of every table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) struct Header {
    pub(crate) magic: [u8; 4],
    pub(crate) version: u16,
    pub(crate) k: u16,
    pub(crate) bins_ml: u16,
    pub(crate) bins_map: u16,
}

impl Header {
    /// `(K, ML bins, MAP bins)`.
    pub(crate) fn shape(&self) -> (u16, u16, u16) {
        (self.k, self.bins_ml, self.bins_map)
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

// Only the host's `DynTable` decodes through `ClassWire` (and `parse_body`).
#[cfg_attr(not(feature = "std"), allow(dead_code))]
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

/// Everything after the header and before the CRC.
#[derive(Deserialize)]
#[cfg_attr(not(feature = "std"), allow(dead_code))]
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
    let (header, body) =
        postcard::take_from_bytes::<Header>(payload).map_err(|_| DecodeError::Malformed)?;
    if header.version != FORMAT_VERSION {
        return Err(DecodeError::UnsupportedVersion {
            found: header.version,
        });
    }
    Ok((header, body))
}

/// Parses the body into settings and the class sequence `C`; every byte must be used.
#[cfg_attr(not(feature = "std"), allow(dead_code))]
pub(crate) fn parse_body<'a, C: Deserialize<'a>>(
    body: &'a [u8],
) -> Result<(Settings, C), DecodeError> {
    let (wire, rest) =
        postcard::take_from_bytes::<BodyWire<C>>(body).map_err(|_| DecodeError::Malformed)?;
    if !rest.is_empty() {
        return Err(DecodeError::Malformed);
    }
    Ok((wire.settings.to_settings()?, wire.classes))
}

/// Receives the classes of a body as they are parsed, so that a fixed-size table can be
/// decoded straight into its own storage, one field at a time, with no intermediate
/// copy of the classes on the stack.
pub(crate) trait BodySink<'a> {
    /// Most classes the storage holds; a longer sequence is malformed.
    fn capacity(&self) -> usize;
    /// Where class `class`'s frequencies of `head` go; a longer sequence is malformed.
    fn freqs(&mut self, class: usize, head: Head) -> &mut [f32];
    /// Every other field of class `class`, once its frequencies are stored.
    fn class(&mut self, class: usize, fields: ClassFields<'a>);
}

/// The fields of one class besides its frequencies, as parsed (not validated).
pub(crate) struct ClassFields<'a> {
    pub(crate) name: &'a str,
    pub(crate) rows: u64,
    pub(crate) mean: f32,
    pub(crate) variance: f32,
    pub(crate) ml_range: (f32, f32),
    /// Number of ML frequencies the class has (all stored: at most the capacity).
    pub(crate) ml_len: usize,
    pub(crate) map_range: (f32, f32),
    /// Number of MAP frequencies the class has.
    pub(crate) map_len: usize,
}

/// Parses the body into `sink`, with exactly the syntax [`parse_body`] accepts (a
/// postcard `BodyWire`); every byte must be used. Returns the validated settings and
/// the number of classes.
pub(crate) fn parse_body_into<'a, S: BodySink<'a>>(
    body: &'a [u8],
    sink: &mut S,
) -> Result<(Settings, usize), DecodeError> {
    let mut de = postcard::Deserializer::from_bytes(body);
    // A struct is its fields in order: the settings, then the class sequence.
    let settings = SettingsWire::deserialize(&mut de).map_err(|_| DecodeError::Malformed)?;
    let count = ClassesSeed(sink)
        .deserialize(&mut de)
        .map_err(|_| DecodeError::Malformed)?;
    let rest = de.finalize().map_err(|_| DecodeError::Malformed)?;
    if !rest.is_empty() {
        return Err(DecodeError::Malformed);
    }
    Ok((settings.to_settings()?, count))
}

/// The class sequence, into a [`BodySink`]; its value is the number of classes.
struct ClassesSeed<'s, S>(&'s mut S);

impl<'de, S: BodySink<'de>> DeserializeSeed<'de> for ClassesSeed<'_, S> {
    type Value = usize;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de, S: BodySink<'de>> Visitor<'de> for ClassesSeed<'_, S> {
    type Value = usize;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a sequence of classes")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<usize, A::Error> {
        let mut class = 0;
        while class < self.0.capacity() {
            let seed = ClassSeed {
                sink: &mut *self.0,
                class,
            };
            match seq.next_element_seed(seed)? {
                Some(()) => class += 1,
                None => return Ok(class),
            }
        }
        // Full: any further class is one too many.
        match seq.size_hint() {
            Some(0) => Ok(class),
            _ => Err(A::Error::invalid_length(class + 1, &self)),
        }
    }
}

/// One class, into a [`BodySink`] (the fields of [`ClassWire`], in order).
struct ClassSeed<'s, S> {
    sink: &'s mut S,
    class: usize,
}

/// The number of fields of [`ClassWire`].
const CLASS_FIELDS: usize = 10;

impl<'de, S: BodySink<'de>> DeserializeSeed<'de> for ClassSeed<'_, S> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        // What the derived `Deserialize` of a struct asks for; postcard reads the
        // fields in order.
        d.deserialize_tuple(CLASS_FIELDS, self)
    }
}

impl<'de, S: BodySink<'de>> Visitor<'de> for ClassSeed<'_, S> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a class")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let mut field = 0;
        let mut next = |seq: &mut A| -> Result<f32, A::Error> {
            field += 1;
            seq.next_element()?
                .ok_or_else(|| A::Error::invalid_length(field, &"a class"))
        };
        let name: &'de str = seq
            .next_element()?
            .ok_or_else(|| A::Error::invalid_length(0, &"a class"))?;
        let rows: u64 = seq
            .next_element()?
            .ok_or_else(|| A::Error::invalid_length(1, &"a class"))?;
        let (mean, variance) = (next(&mut seq)?, next(&mut seq)?);
        let ml_range = (next(&mut seq)?, next(&mut seq)?);
        let ml_len = seq
            .next_element_seed(FreqsSeed(self.sink.freqs(self.class, Head::Ml)))?
            .ok_or_else(|| A::Error::invalid_length(6, &"a class"))?;
        let map_range = (next(&mut seq)?, next(&mut seq)?);
        let map_len = seq
            .next_element_seed(FreqsSeed(self.sink.freqs(self.class, Head::Map)))?
            .ok_or_else(|| A::Error::invalid_length(9, &"a class"))?;
        self.sink.class(
            self.class,
            ClassFields {
                name,
                rows,
                mean,
                variance,
                ml_range,
                ml_len,
                map_range,
                map_len,
            },
        );
        Ok(())
    }
}

/// A frequency sequence, into a slice; its value is the number of frequencies.
struct FreqsSeed<'s>(&'s mut [f32]);

impl<'de> DeserializeSeed<'de> for FreqsSeed<'_> {
    type Value = usize;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for FreqsSeed<'_> {
    type Value = usize;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a sequence of frequencies")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<usize, A::Error> {
        let mut n = 0;
        while let Some(v) = seq.next_element::<f32>()? {
            match self.0.get_mut(n) {
                Some(slot) => *slot = v,
                None => return Err(A::Error::invalid_length(n + 1, &self)),
            }
            n += 1;
        }
        Ok(n)
    }
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

#[derive(Serialize)]
struct MessageRef<C> {
    header: Header,
    settings: SettingsWire,
    classes: C,
}

/// One class on the wire, borrowed from a validated table.
type ClassView<'a> = ClassWire<'a, &'a [f32], &'a [f32]>;

/// The message [`encode`] writes, before the CRC.
fn message<'a, F>(
    shape: (u16, u16, u16),
    settings: &Settings,
    class: F,
) -> MessageRef<ClassSeq<impl Fn(usize) -> Option<ClassView<'a>>>>
where
    F: Fn(usize) -> Option<ClassSpec<'a, &'a [f32], &'a [f32]>>,
{
    MessageRef {
        header: Header {
            magic: MAGIC,
            version: FORMAT_VERSION,
            k: shape.0,
            bins_ml: shape.1,
            bins_map: shape.2,
        },
        settings: SettingsWire::from_settings(settings),
        classes: ClassSeq {
            k: usize::from(shape.0),
            class: move |i| {
                let c = class(i)?;
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
        },
    }
}

/// Encodes a validated table given by its shape, settings and a per-class view.
pub(crate) fn encode<'a, 'b, F>(
    shape: (u16, u16, u16),
    settings: &Settings,
    class: F,
    buf: &'b mut [u8],
) -> Result<&'b mut [u8], EncodeError>
where
    F: Fn(usize) -> Option<ClassSpec<'a, &'a [f32], &'a [f32]>>,
{
    let msg = message(shape, settings, class);
    postcard::to_slice_crc32(&msg, buf, CRC.digest()).map_err(|_| EncodeError::BufferTooSmall)
}

/// Checks that a decoded table came from exactly the bytes [`encode`] writes for it:
/// postcard reads a varint written in more bytes than needed (`0x84 0x00` for 4), and
/// such a non-canonical input would decode to a table whose encoding differs. Only the
/// lengths need comparing: every other field has a fixed size and decodes losslessly,
/// and an overlong varint only ever adds bytes. Measures, writes nothing.
pub(crate) fn check_canonical<'a, F>(
    len: usize,
    shape: (u16, u16, u16),
    settings: &Settings,
    class: F,
) -> Result<(), DecodeError>
where
    F: Fn(usize) -> Option<ClassSpec<'a, &'a [f32], &'a [f32]>>,
{
    let msg = message(shape, settings, class);
    let size = postcard::serialize_with_flavor(&msg, postcard::ser_flavors::Size::default())
        .map_err(|_| DecodeError::Malformed)?;
    if size.checked_add(CRC_LEN) != Some(len) {
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

/// Upper bound of the encoded size of a table with `k` classes and the given bin counts
/// (every name [`NAME_MAX`] bytes, every row count the largest `u64`).
pub const fn max_encoded_len(k: usize, bins_ml: usize, bins_map: usize) -> usize {
    let header = MAGIC.len() + 4 * varint_len(u16::MAX as usize);
    let settings = 2 + 4 + 4;
    let per_class = varint_len(NAME_MAX) + NAME_MAX
        + 10 // rows, varint u64
        + 4 * 2 // mean, variance
        + 4 * 2 + varint_len(bins_ml) + 4 * bins_ml
        + 4 * 2 + varint_len(bins_map) + 4 * bins_map;
    header + settings + varint_len(k) + k * per_class + CRC_LEN
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// The shipped table with the first class's row count rewritten as an overlong
    /// varint (one byte more than needed) and the CRC recomputed.
    fn overlong_rows() -> Vec<u8> {
        let bytes = include_bytes!("../tables/default.mlmap");
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
        let bytes = include_bytes!("../tables/default.mlmap");
        let table = crate::Table::<3, 22, 17>::from_bytes(bytes).unwrap();
        let mut buf = [0u8; crate::Table::<3, 22, 17>::MAX_ENCODED_LEN];
        assert_eq!(table.to_slice(&mut buf).unwrap(), &bytes[..]);
        let overlong = overlong_rows();
        assert_eq!(overlong.len(), bytes.len() + 1);
        assert_eq!(
            crate::Table::<3, 22, 17>::from_bytes(&overlong),
            Err(DecodeError::Malformed)
        );
        #[cfg(feature = "std")]
        assert_eq!(
            crate::host::DynTable::from_bytes(&overlong),
            Err(DecodeError::Malformed)
        );
    }
}
