//! Writing a table: the postcard message of a validated table, its CRC-32 and the
//! bounds of its length.

use serde::Serialize;

use super::{
    ClassWire, SettingsWire, CRC, CRC_LEN, FORMAT_VERSION, MAGIC, VERSION_1, VERSION_2, VERSION_3,
};
use crate::diagnostics::error::{DecodeError, EncodeError};
use crate::format::name::NAME_MAX;
use crate::heads::recal::{Knot, Maps};
use crate::math::histogram::Axis;
use crate::storage::view::TableView;

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
