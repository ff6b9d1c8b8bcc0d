//! The one body parser of the `.mlmap` format: postcard's deserializer driven field by
//! field into the storage a [`BodySink`] lends, so that a fixed-size table decodes in
//! place and every kind of table decodes through the same code.

use core::fmt;

use serde::de::{DeserializeSeed, Deserializer, Error as _, SeqAccess, Visitor};
use serde::Deserialize;

use super::{Settings, SettingsWire};
use crate::diagnostics::error::{BodyPart, DecodeError, Head};
use crate::heads::recal::Knot;
use crate::math::histogram::Axis;

#[cfg(test)]
use super::BodyWire;

/// Parses a version-1 body into settings and the class sequence `C` with serde's derived
/// decoder; every byte must be used. Only a test oracle: tables decode through
/// [`parse_body_into`].
#[cfg(test)]
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
    /// Where the Bayes head's sequences go (row counts, axes, log-terms); a longer
    /// sequence is malformed. Only called for a table with a Bayes head.
    fn bayes(&mut self) -> BayesSlots<'_>;
    /// Where the knots of the recalibration map in slot `slot` (ML, MAP, Bayes, open)
    /// go; knots beyond its length are counted, not stored.
    fn recal(&mut self, slot: usize) -> &mut [Knot];
    /// Whether the elements of every sequence beyond the room the sink lends are counted
    /// rather than refused: a sink that only measures a table (lends no room at all).
    /// Every sink that stores a table answers `false`.
    fn counts_only(&self) -> bool {
        false
    }
    /// The parser is about to read `part` (a no-op but for the sink that locates where a
    /// malformed body stops following the format, [`locate_malformed`]).
    #[inline(always)]
    fn part(&mut self, _part: BodyPart) {}
}

/// The storage a Bayes head is parsed into (axes get their `lo` and `hi` only).
pub(crate) struct BayesSlots<'s> {
    pub(crate) rows: &'s mut [u64],
    pub(crate) axes: &'s mut [Axis],
    pub(crate) terms: &'s mut [f32],
    /// Room for the objectness feature's axis (0 or 1 entries) and terms.
    pub(crate) objectness_axis: &'s mut [Axis],
    pub(crate) objectness_terms: &'s mut [f32],
}

/// What a body held besides the classes' storage: the settings, the number of classes,
/// with a Bayes head its lambda and the lengths of its three sequences, and with an
/// open head (version 3) its temperature and epsilon as stored (not validated).
pub(crate) struct Parsed {
    pub(crate) settings: Settings,
    pub(crate) classes: usize,
    pub(crate) bayes: Option<(f32, [usize; 3])>,
    pub(crate) open: Option<(f32, f32)>,
    /// Knots of each head's recalibration map as stored (0: none), version 4.
    pub(crate) maps: [usize; 4],
    /// The objectness feature's number of terms as stored, when the table has it
    /// (version 4).
    pub(crate) objectness: Option<usize>,
}

/// What the header announced about the body's optional parts.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Parts {
    /// A Bayes section follows the classes.
    pub(crate) bayes: bool,
    /// The open head's parameters always follow the Bayes section (version 3).
    pub(crate) open: bool,
    /// Version 4: the open head's parameters as an option after the Bayes section (when
    /// there is one), then the recalibration maps.
    pub(crate) maps: bool,
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

/// Parses the body into `sink` (the one body parser: every table, fixed-size or not,
/// decodes through it); every byte must be used. `parts` says which optional parts the
/// header announced.
pub(crate) fn parse_body_into<'a, S: BodySink<'a>>(
    body: &'a [u8],
    parts: Parts,
    sink: &mut S,
) -> Result<Parsed, DecodeError> {
    let Parts { bayes, open, maps } = parts;
    let malformed = |_| DecodeError::Malformed;
    let mut de = postcard::Deserializer::from_bytes(body);
    // A struct is its fields in order: the settings, then the class sequence.
    sink.part(BodyPart::Settings);
    let settings = SettingsWire::deserialize(&mut de).map_err(malformed)?;
    sink.part(BodyPart::Class { index: 0 });
    let classes = ClassesSeed(&mut *sink)
        .deserialize(&mut de)
        .map_err(malformed)?;
    let bayes = if bayes {
        sink.part(BodyPart::Bayes);
        let lambda = f32::deserialize(&mut de).map_err(malformed)?;
        let count = sink.counts_only();
        let slots = sink.bayes();
        let rows = seq_into(slots.rows, |slot: &mut u64, v: u64| *slot = v)
            .counting(count)
            .deserialize(&mut de)
            .map_err(malformed)?;
        let axes = seq_into(slots.axes, |slot: &mut Axis, (lo, hi): (f32, f32)| {
            (slot.lo, slot.hi) = (lo, hi);
        })
        .counting(count)
        .deserialize(&mut de)
        .map_err(malformed)?;
        let terms = seq_into(slots.terms, store)
            .counting(count)
            .deserialize(&mut de)
            .map_err(malformed)?;
        Some((lambda, [rows, axes, terms]))
    } else {
        None
    };
    // Version 4: the objectness feature, an option after the Bayes section (its axis
    // `(lo, hi)`, then its terms).
    let mut objectness = None;
    if bayes.is_some() && maps {
        sink.part(BodyPart::Objectness);
        let tag = u8::deserialize(&mut de).map_err(malformed)?;
        match tag {
            0 => {}
            1 => {
                let (lo, hi) = <(f32, f32)>::deserialize(&mut de).map_err(malformed)?;
                let slots = sink.bayes();
                if let Some(a) = slots.objectness_axis.first_mut() {
                    (a.lo, a.hi) = (lo, hi);
                }
                let n = CountFloats(slots.objectness_terms)
                    .deserialize(&mut de)
                    .map_err(malformed)?;
                objectness = Some(n);
            }
            _ => return Err(DecodeError::Malformed),
        }
    }
    sink.part(BodyPart::Open);
    let open = if bayes.is_some() && open {
        Some(<(f32, f32)>::deserialize(&mut de).map_err(malformed)?)
    } else if bayes.is_some() && maps {
        Option::<(f32, f32)>::deserialize(&mut de).map_err(malformed)?
    } else {
        None
    };
    let mut counts = [0usize; 4];
    if maps {
        sink.part(BodyPart::Maps);
        MapsSeed {
            sink: &mut *sink,
            counts: &mut counts,
        }
        .deserialize(&mut de)
        .map_err(malformed)?;
    }
    sink.part(BodyPart::Trailing);
    let rest = de.finalize().map_err(malformed)?;
    if !rest.is_empty() {
        return Err(DecodeError::Malformed);
    }
    sink.part(BodyPart::Settings);
    Ok(Parsed {
        settings: settings.to_settings()?,
        classes,
        bayes,
        open,
        maps: counts,
        objectness,
    })
}

/// A sequence of floats stored into a slice while it has room and counted to its end.
struct CountFloats<'s>(&'s mut [f32]);

impl<'de> DeserializeSeed<'de> for CountFloats<'_> {
    type Value = usize;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for CountFloats<'_> {
    type Value = usize;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a sequence of floats")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<usize, A::Error> {
        let mut n = 0usize;
        while let Some(v) = seq.next_element::<f32>()? {
            if let Some(slot) = self.0.get_mut(n) {
                *slot = v;
            }
            n = n.saturating_add(1);
        }
        Ok(n)
    }
}

/// The recalibration maps of a version-4 body: a sequence of records
/// `(head code, knots)`, head codes strictly increasing (0 ML, 1 MAP, 2 Bayes, 3 open),
/// each map's knots a sequence of `(x, y)` pairs.
struct MapsSeed<'s, S> {
    sink: &'s mut S,
    counts: &'s mut [usize; 4],
}

impl<'de, S: BodySink<'de>> DeserializeSeed<'de> for MapsSeed<'_, S> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de, S: BodySink<'de>> Visitor<'de> for MapsSeed<'_, S> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a sequence of recalibration maps")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let mut next_slot = 0usize;
        let mut records = 0usize;
        loop {
            let seed = MapSeed {
                sink: &mut *self.sink,
                counts: &mut *self.counts,
                min_slot: next_slot,
            };
            match seq.next_element_seed(seed)? {
                Some(slot) => {
                    next_slot = slot + 1;
                    records += 1;
                }
                None => break,
            }
        }
        // No record is valid only for a table with the objectness feature; the
        // decoder's canonical-length check refuses a version-4 table that needs no
        // version 4.
        let _ = records;
        Ok(())
    }
}

/// One map record: its head code (at least `min_slot`), then its knots.
struct MapSeed<'s, S> {
    sink: &'s mut S,
    counts: &'s mut [usize; 4],
    min_slot: usize,
}

impl<'de, S: BodySink<'de>> DeserializeSeed<'de> for MapSeed<'_, S> {
    type Value = usize;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
        d.deserialize_tuple(2, self)
    }
}

impl<'de, S: BodySink<'de>> Visitor<'de> for MapSeed<'_, S> {
    type Value = usize;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a recalibration map")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<usize, A::Error> {
        let code: u8 = seq
            .next_element()?
            .ok_or_else(|| A::Error::invalid_length(0, &"a map"))?;
        let slot = usize::from(code);
        if slot < self.min_slot || slot >= self.counts.len() {
            return Err(A::Error::custom("map head codes not increasing"));
        }
        let n = seq
            .next_element_seed(CountInto(self.sink.recal(slot)))?
            .ok_or_else(|| A::Error::invalid_length(1, &"a map"))?;
        if let Some(c) = self.counts.get_mut(slot) {
            *c = n;
        }
        Ok(slot)
    }
}

/// A sequence of knots stored into a slice while it has room and counted to its end.
struct CountInto<'s>(&'s mut [Knot]);

impl<'de> DeserializeSeed<'de> for CountInto<'_> {
    type Value = usize;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for CountInto<'_> {
    type Value = usize;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a sequence of knots")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<usize, A::Error> {
        let mut n = 0usize;
        while let Some((x, y)) = seq.next_element::<(f32, f32)>()? {
            if let Some(slot) = self.0.get_mut(n) {
                *slot = Knot { x, y };
            }
            n = n.saturating_add(1);
        }
        Ok(n)
    }
}

/// A sequence of `V`, stored through `set` into the slots of a slice; its value is the
/// length of the sequence. A sequence longer than the slice is an error, unless the
/// sequence is only counted (`counting`: the elements beyond the slice are parsed and
/// counted, not stored).
struct SeqInto<'s, T, V, F>(&'s mut [T], F, bool, core::marker::PhantomData<fn() -> V>);

/// A [`SeqInto`] storing each parsed `V` into a slot of `slots` through `set`.
fn seq_into<T, V, F: FnMut(&mut T, V)>(slots: &mut [T], set: F) -> SeqInto<'_, T, V, F> {
    SeqInto(slots, set, false, core::marker::PhantomData)
}

impl<T, V, F> SeqInto<'_, T, V, F> {
    /// Counts the elements beyond the slice instead of refusing them when `count`.
    fn counting(mut self, count: bool) -> Self {
        self.2 = count;
        self
    }
}

impl<'de, T, V: Deserialize<'de>, F: FnMut(&mut T, V)> DeserializeSeed<'de>
    for SeqInto<'_, T, V, F>
{
    type Value = usize;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<usize, D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de, T, V: Deserialize<'de>, F: FnMut(&mut T, V)> Visitor<'de> for SeqInto<'_, T, V, F> {
    type Value = usize;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a sequence")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<usize, A::Error> {
        let SeqInto(slots, mut set, count, _) = self;
        let mut n = 0usize;
        while let Some(v) = seq.next_element::<V>()? {
            match slots.get_mut(n) {
                Some(slot) => set(slot, v),
                None if count => {}
                None => return Err(A::Error::invalid_length(n + 1, &"a shorter sequence")),
            }
            n = n.saturating_add(1);
        }
        Ok(n)
    }
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
            self.0.part(BodyPart::Class {
                index: u16::try_from(class).unwrap_or(u16::MAX),
            });
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
        self.0.part(BodyPart::Class {
            index: u16::try_from(class).unwrap_or(u16::MAX),
        });
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
        let count = self.sink.counts_only();
        let ml_len = seq
            .next_element_seed(
                seq_into(self.sink.freqs(self.class, Head::Ml), store).counting(count),
            )?
            .ok_or_else(|| A::Error::invalid_length(6, &"a class"))?;
        let map_range = (next(&mut seq)?, next(&mut seq)?);
        let map_len = seq
            .next_element_seed(
                seq_into(self.sink.freqs(self.class, Head::Map), store).counting(count),
            )?
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

/// Stores one parsed `f32`.
fn store(slot: &mut f32, v: f32) {
    *slot = v;
}

/// A sink that stores nothing and remembers the part being read: where a malformed body
/// stops following the format. It counts every sequence, and notes the first class
/// whose histograms hold more frequencies than the header's bins (which a decoder, its
/// storage of the header's shape, refuses as malformed).
struct Locate {
    shape: crate::lent::StorageShape,
    at: BodyPart,
    over: Option<BodyPart>,
}

impl<'a> BodySink<'a> for Locate {
    fn capacity(&self) -> usize {
        self.shape.classes
    }

    fn freqs(&mut self, _: usize, _: Head) -> &mut [f32] {
        &mut []
    }

    fn class(&mut self, class: usize, fields: ClassFields<'a>) {
        if self.over.is_none()
            && (fields.ml_len > self.shape.bins_ml || fields.map_len > self.shape.bins_map)
        {
            self.over = Some(BodyPart::Class {
                index: u16::try_from(class).unwrap_or(u16::MAX),
            });
        }
    }

    fn bayes(&mut self) -> BayesSlots<'_> {
        BayesSlots {
            rows: &mut [],
            axes: &mut [],
            terms: &mut [],
            objectness_axis: &mut [],
            objectness_terms: &mut [],
        }
    }

    fn recal(&mut self, _: usize) -> &mut [Knot] {
        &mut []
    }

    fn counts_only(&self) -> bool {
        true
    }

    fn part(&mut self, part: BodyPart) {
        self.at = part;
    }
}

/// Where the table in `bytes` (a table file, sections appended allowed) stops following
/// the format, when decoding it gives [`DecodeError::Malformed`]: the part of the header
/// or body being read. `None` when every part parses (the bytes decode past the
/// syntax, or break only the shortest-encoding rule, e.g. an overlong varint) or fail
/// an earlier check (magic, CRC-32, version).
///
/// Decoding reports [`DecodeError::Malformed`] without a position, so that the one body
/// parser stays free of bookkeeping; this reads the body once more, storing nothing, to
/// name the part for a diagnostic (the C API's error details, `mlmap inspect`).
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::{locate_malformed, BodyPart};
///
/// let good = include_bytes!("../../../../tables/default.mlmap");
/// assert_eq!(locate_malformed(good), None);
/// // One byte more at the end of the body (the CRC-32 recomputed): trailing bytes.
/// let mut bytes = good[..good.len() - 4].to_vec();
/// bytes.push(0);
/// let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&bytes);
/// bytes.extend_from_slice(&crc.to_le_bytes());
/// assert_eq!(locate_malformed(&bytes), Some(BodyPart::Trailing));
/// ```
pub fn locate_malformed(bytes: &[u8]) -> Option<BodyPart> {
    let (header, body) = match super::open(crate::sections::table_part(bytes)) {
        Ok(h) => h,
        Err(DecodeError::Malformed) => return Some(BodyPart::Header),
        Err(_) => return None,
    };
    let shape = crate::lent::StorageShape {
        classes: usize::from(header.k),
        bins_ml: usize::from(header.bins_ml),
        bins_map: usize::from(header.bins_map),
        bins_bayes: usize::from(header.bins_bayes),
        categories: usize::from(header.categories),
        knots: [0; 4],
        objectness: false,
    };
    if shape.floats().saturating_mul(4) > body.len() {
        return Some(BodyPart::Length);
    }
    let mut sink = Locate {
        shape,
        at: BodyPart::Header,
        over: None,
    };
    let parsed = match parse_body_into(body, header.parts(), &mut sink) {
        Ok(p) => p,
        Err(DecodeError::Malformed) => return Some(sink.at),
        Err(_) => return None,
    };
    if parsed.classes != shape.classes {
        return Some(BodyPart::Class {
            index: u16::try_from(parsed.classes).unwrap_or(u16::MAX),
        });
    }
    if let Some(part) = sink.over {
        return Some(part);
    }
    // Sequences longer than the header's shape: more than a decoder's storage holds.
    let cats = shape.categories;
    let terms = shape
        .classes
        .saturating_mul(shape.bins_bayes)
        .saturating_mul(cats);
    if let Some((_, [rows, axes, t])) = parsed.bayes {
        if rows > cats || axes > shape.classes || t > terms {
            return Some(BodyPart::Bayes);
        }
    }
    if parsed.objectness > Some(shape.bins_bayes.saturating_mul(cats)) {
        return Some(BodyPart::Objectness);
    }
    // Every part parsed: the bytes follow the format, but for the shortest-encoding
    // rule, which only a decoded table can check.
    None
}
