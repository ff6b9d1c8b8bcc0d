//! Building a quantized section from a table ([`quantize_into`], no_std, no allocation).
//!
//! Every stored value is computed by the `f32` layer's own functions on the dequantized
//! logit of each code: the ML mass and the bin it comes from, the MAP mass (with the
//! `Libm` backend of [`Table::map`](crate::Table::map)), and the Bayes head's bin per
//! logit. So the quantized heads reproduce the `f32` heads bit for bit. The open head
//! (DESIGN §1.8) comes with the Bayes head whenever the table has it: its parameters are
//! copied as the table decoder derived them.

use crate::format::wire::{self, CRC};
use crate::heads::layer;
use crate::heads::recal::Knot;
use crate::math::histogram::Histogram;
use crate::math::Libm;
use crate::quantized::qtable::{
    code_range, dequantize, index_width, QHeader, FLAG_BAYES, FLAG_OBJECTNESS, FLAG_OPEN,
    HEADER_LEN, OPEN_LEN, QUANTIZED_VERSION, QUANTIZED_VERSION_1, QUANTIZED_VERSION_2,
};
use crate::storage::view::TableView;

/// How a detector quantizes its logits: the input of [`quantize_into`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QParams<'p> {
    /// Bits per code: 8 (`i8`) or 16 (`i16`).
    pub bits: u8,
    /// The scale of each class's logits (K values, each finite and > 0).
    pub scales: &'p [f32],
    /// The zero point of each class's logits (K values, each in the code range).
    pub zero_points: &'p [i32],
    /// Whether to include the Bayes head (the table must have one). With it comes the
    /// open head when the table has that too (the section is then version 2). The
    /// table's recalibration maps of the heads the section holds come too (version 3).
    pub bayes: bool,
}

/// Why a quantized section could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum QuantizeError {
    /// `bits` is not 8 or 16.
    Bits,
    /// The scales or zero points are not one per class.
    Length,
    /// The scale of this class is not finite and positive.
    Scale {
        /// Class index.
        class: u16,
    },
    /// The zero point of this class is outside the code range.
    ZeroPoint {
        /// Class index.
        class: u16,
    },
    /// The Bayes head was asked for, and the table has none.
    NoBayesHead,
    /// The output buffer is too small; [`quantized_len`] gives the size needed.
    BufferTooSmall,
    /// The section would exceed `u32::MAX` bytes.
    TooLarge,
}

impl QuantizeError {
    /// The variant's message: what `Display` says (with the variant's values where it
    /// has any) and what `defmt` prints.
    pub const fn message(self) -> &'static str {
        match self {
            Self::Bits => "quantized codes must have 8 or 16 bits",
            Self::Length => "scales and zero points must have one value per class",
            Self::Scale { .. } => "a class's scale is not finite and positive",
            Self::ZeroPoint { .. } => "a class's zero point is outside the code range",
            Self::NoBayesHead => "the table has no Bayes head to quantize",
            Self::BufferTooSmall => "output buffer is too small for the section",
            Self::TooLarge => "the quantized section would exceed 4 GiB",
        }
    }
}

impl core::fmt::Display for QuantizeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Bits
            | Self::Length
            | Self::NoBayesHead
            | Self::BufferTooSmall
            | Self::TooLarge => f.write_str(self.message()),
            Self::Scale { class } => {
                write!(f, "scale of class {class} is not finite and positive")
            }
            Self::ZeroPoint { class } => {
                write!(f, "zero point of class {class} is outside the code range")
            }
        }
    }
}

impl core::error::Error for QuantizeError {}

/// Where the section goes: counted only, or written.
struct Out<'b> {
    buf: Option<&'b mut [u8]>,
    len: usize,
}

impl Out<'_> {
    fn put(&mut self, bytes: &[u8]) -> Result<(), QuantizeError> {
        let end = self
            .len
            .checked_add(bytes.len())
            .ok_or(QuantizeError::TooLarge)?;
        if let Some(buf) = self.buf.as_deref_mut() {
            buf.get_mut(self.len..end)
                .ok_or(QuantizeError::BufferTooSmall)?
                .copy_from_slice(bytes);
        }
        self.len = end;
        Ok(())
    }
}

/// The first and last code for which `keep` holds, as `(start, count)`; `(0, 0)` when
/// it holds for none. Every code between them is inside the window.
fn window(lo: i32, hi: i32, keep: impl Fn(i32) -> bool) -> (i32, u32) {
    let Some(first) = (lo..=hi).find(|&q| keep(q)) else {
        return (0, 0);
    };
    let last = (first..=hi).rev().find(|&q| keep(q)).unwrap_or(first);
    (first, last.abs_diff(first) + 1)
}

/// Writes the window header and one bin index per code of it.
fn put_index(
    out: &mut Out<'_>,
    (start, n): (i32, u32),
    wide: bool,
    bin: impl Fn(i32) -> Option<usize>,
) -> Result<(), QuantizeError> {
    out.put(&start.to_le_bytes())?;
    out.put(&n.to_le_bytes())?;
    for q in (0..n).filter_map(|i| start.checked_add_unsigned(i)) {
        let b = bin(q).unwrap_or(0);
        if wide {
            out.put(&u16::try_from(b).unwrap_or(u16::MAX).to_le_bytes())?;
        } else {
            out.put(&[u8::try_from(b).unwrap_or(u8::MAX)])?;
        }
    }
    Ok(())
}

/// The whole section into `out`.
fn write<F: AsRef<[f32]>, G: AsRef<[f32]>>(
    table: &TableView<'_, F, G>,
    params: &QParams<'_>,
    out: &mut Out<'_>,
) -> Result<(), QuantizeError> {
    let k = table.k();
    if !(params.bits == 8 || params.bits == 16) {
        return Err(QuantizeError::Bits);
    }
    if params.scales.len() != k || params.zero_points.len() != k {
        return Err(QuantizeError::Length);
    }
    let (lo, hi) = code_range(params.bits);
    for (c, (&s, &z)) in params.scales.iter().zip(params.zero_points).enumerate() {
        let class = u16::try_from(c).unwrap_or(u16::MAX);
        if !(s.is_finite() && s > 0.0) {
            return Err(QuantizeError::Scale { class });
        }
        if !(lo..=hi).contains(&z) {
            return Err(QuantizeError::ZeroPoint { class });
        }
    }
    let bayes = match (params.bayes, table.bayes()) {
        (false, _) => None,
        (true, Some(b)) => Some(b),
        (true, None) => return Err(QuantizeError::NoBayesHead),
    };
    let narrow = |n: usize| u16::try_from(n).unwrap_or(u16::MAX);
    let settings = table.settings();
    let bins_ml = narrow(table.bins_ml());
    let (bins_bayes, cats) = bayes.map_or((0, 0), |b| (narrow(b.bins()), narrow(b.categories())));
    // The open head rides with the Bayes head. Version 3 exactly when a map of a head
    // the section holds is there, else version 2 exactly when the open head is, so a
    // section keeps the bytes of the oldest version that holds it.
    let open = bayes.and_then(|b| b.open());
    let maps: [&[Knot]; 4] = core::array::from_fn(|slot| match slot {
        0 | 1 => table.maps.0.get(slot).copied().unwrap_or_default(),
        2 if bayes.is_some() => table.maps.0.get(slot).copied().unwrap_or_default(),
        3 if open.is_some() => table.maps.0.get(slot).copied().unwrap_or_default(),
        _ => &[],
    });
    let records = maps.iter().filter(|m| !m.is_empty()).count();
    let feature = bayes.and_then(|b| b.objectness);
    let version = if records > 0 || feature.is_some() {
        QUANTIZED_VERSION
    } else if open.is_some() {
        QUANTIZED_VERSION_2
    } else {
        QUANTIZED_VERSION_1
    };
    let v3 = version == QUANTIZED_VERSION;
    let flag = |on: bool, f: u8| if on { f } else { 0 };
    let header = QHeader {
        version,
        bits: params.bits,
        flags: flag(bayes.is_some(), FLAG_BAYES)
            | flag(v3 && open.is_some(), FLAG_OPEN)
            | flag(feature.is_some(), FLAG_OBJECTNESS),
        reserved: 0,
        k: narrow(k),
        bins_ml,
        bins_bayes,
        categories: cats,
        table_crc: wire::table_crc(table),
        lambda_ml: settings.lambda_ml,
        lambda_map: settings.lambda_map,
        log_lambda: bayes.map_or(0.0, |b| b.log_lambda),
    };
    out.put(&header.to_bytes())?;
    debug_assert_eq!(out.len, HEADER_LEN);
    let tail = settings.upper_tail;
    let x_of = |c: usize, q: i32| {
        let s = params.scales.get(c).copied().unwrap_or(1.0);
        let z = params.zero_points.get(c).copied().unwrap_or(0);
        dequantize(q, s, z)
    };
    for (c, ((ml, map), g)) in table.ml.iter().zip(table.map).zip(table.priors).enumerate() {
        let x = |q| x_of(c, q);
        out.put(&params.scales.get(c).copied().unwrap_or(0.0).to_le_bytes())?;
        out.put(
            &params
                .zero_points
                .get(c)
                .copied()
                .unwrap_or(0)
                .to_le_bytes(),
        )?;
        // ML: bins over the codes whose mass is not lambda, then the masses per bin.
        let lambda = settings.lambda_ml;
        let ml_mass = |q| layer::ml_mass(ml, lambda, tail, x(q));
        let w = window(lo, hi, |q| ml_mass(q).to_bits() != lambda.to_bits());
        put_index(out, w, index_width(bins_ml) == 2, |q| {
            ml.likelihood_bin(x(q), tail)
        })?;
        put_bin_masses(out, ml, lambda)?;
        // MAP: the masses themselves over the codes whose mass is not lambda.
        let lambda = settings.lambda_map;
        let map_mass = |q| layer::map_mass::<_, Libm>(map, g, lambda, tail, x(q));
        let (start, n) = window(lo, hi, |q| map_mass(q).to_bits() != lambda.to_bits());
        out.put(&start.to_le_bytes())?;
        out.put(&n.to_le_bytes())?;
        for q in (0..n).filter_map(|i| start.checked_add_unsigned(i)) {
            out.put(&map_mass(q).to_le_bytes())?;
        }
    }
    if let Some(b) = bayes {
        let row = b.bins() * b.categories();
        for (j, axis) in b.axes().iter().enumerate() {
            let w = window(lo, hi, |q| axis.bin(x_of(j, q)).is_some());
            put_index(out, w, index_width(bins_bayes) == 2, |q| {
                axis.bin(x_of(j, q))
            })?;
            let terms = b.all_terms().get(j * row..(j + 1) * row).unwrap_or(&[]);
            for t in terms {
                out.put(&t.to_le_bytes())?;
            }
        }
        for c in 0..b.categories() {
            out.put(&b.log_prior(c).unwrap_or(0.0).to_le_bytes())?;
        }
    }
    if let Some(o) = open {
        let before = out.len;
        for v in [o.temperature(), o.epsilon(), o.log_unknown()] {
            out.put(&v.to_le_bytes())?;
        }
        debug_assert_eq!(out.len - before, OPEN_LEN);
    }
    if let Some((axis, terms)) = feature {
        out.put(&axis.lo.to_le_bytes())?;
        out.put(&axis.hi.to_le_bytes())?;
        for t in terms {
            out.put(&t.to_le_bytes())?;
        }
    }
    if v3 {
        // At most 4 records of at most MAX_KNOTS knots: each count fits a byte.
        out.put(&[u8::try_from(records).unwrap_or(0)])?;
        for (code, knots) in maps.iter().enumerate().filter(|(_, m)| !m.is_empty()) {
            out.put(&[
                u8::try_from(code).unwrap_or(0),
                u8::try_from(knots.len()).unwrap_or(0),
            ])?;
            for k in knots.iter() {
                out.put(&k.x.to_le_bytes())?;
                out.put(&k.y.to_le_bytes())?;
            }
        }
    }
    let len = u32::try_from(out.len + 8).map_err(|_| QuantizeError::TooLarge)?;
    out.put(&len.to_le_bytes())?;
    let crc = match out.buf.as_deref() {
        Some(buf) => CRC.checksum(buf.get(..out.len).unwrap_or(&[])),
        None => 0,
    };
    out.put(&crc.to_le_bytes())
}

/// The masses `frequency + lambda` of every bin of `h`.
fn put_bin_masses<F: AsRef<[f32]>>(
    out: &mut Out<'_>,
    h: &Histogram<F>,
    lambda: f32,
) -> Result<(), QuantizeError> {
    for &f in h.frequencies() {
        out.put(&(f + lambda).to_le_bytes())?;
    }
    Ok(())
}

/// Builds the quantized section of `table` for `params` into `buf` and returns the
/// written prefix; read it with [`QTable::from_bytes`](crate::QTable::from_bytes). Pass
/// it a table's [`view`](crate::Table::view).
///
/// Evaluates every head once per representable code and class (256 or 65,536 codes;
/// the MAP head's Gaussian with `Libm`), so it is a start-up or build-time step.
///
/// # Errors
///
/// A [`QuantizeError`] for bad parameters or a buffer shorter than [`quantized_len`].
///
/// # Panics
///
/// Never.
pub fn quantize_into<'b, F: AsRef<[f32]>, G: AsRef<[f32]>>(
    table: &TableView<'_, F, G>,
    params: &QParams<'_>,
    buf: &'b mut [u8],
) -> Result<&'b [u8], QuantizeError> {
    let mut out = Out {
        buf: Some(buf),
        len: 0,
    };
    write(table, params, &mut out)?;
    let len = out.len;
    Ok(out.buf.and_then(|b| b.get(..len)).unwrap_or(&[]))
}

/// The number of bytes [`quantize_into`] writes for `table` and `params` (docs/FORMAT.md
/// gives the formula).
///
/// # Errors
///
/// As [`quantize_into`], except [`QuantizeError::BufferTooSmall`].
pub fn quantized_len<F: AsRef<[f32]>, G: AsRef<[f32]>>(
    table: &TableView<'_, F, G>,
    params: &QParams<'_>,
) -> Result<usize, QuantizeError> {
    let mut out = Out { buf: None, len: 0 };
    write(table, params, &mut out)?;
    Ok(out.len)
}
