//! The section's layout read in place: its header ([`Meta`]), each class's ML and MAP
//! data ([`QClass`]) and each logit's Bayes data ([`QLogit`]), located and validated once
//! by [`parse`].

use super::*;

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
pub(super) struct Reader<'a>(&'a [u8]);

/// Flag of a quantized section's header: the section has the Bayes head.
pub(crate) const FLAG_BAYES: u8 = 1;
/// Flag (version 3): the section has the open head (with the Bayes head).
pub(crate) const FLAG_OPEN: u8 = 2;
/// Flag (version 3): the section has the objectness feature (with the Bayes head).
pub(crate) const FLAG_OBJECTNESS: u8 = 4;

/// The fixed header of a quantized section (docs/FORMAT.md, "The quantized section"):
/// the one declaration of its fields and their order, which the writer
/// (`quantize_into`) and the reader (`parse`) share.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct QHeader {
    pub(crate) version: u8,
    pub(crate) bits: u8,
    pub(crate) flags: u8,
    pub(crate) reserved: u8,
    pub(crate) k: u16,
    pub(crate) bins_ml: u16,
    pub(crate) bins_bayes: u16,
    pub(crate) categories: u16,
    pub(crate) table_crc: u32,
    pub(crate) lambda_ml: f32,
    pub(crate) lambda_map: f32,
    pub(crate) log_lambda: f32,
}

impl QHeader {
    /// The header's [`HEADER_LEN`] bytes, the magic first.
    pub(crate) fn to_bytes(self) -> [u8; HEADER_LEN] {
        let mut b = [0u8; HEADER_LEN];
        let fields: [&[u8]; 10] = [
            &QUANTIZED_MAGIC,
            &[self.version, self.bits, self.flags, self.reserved],
            &self.k.to_le_bytes(),
            &self.bins_ml.to_le_bytes(),
            &self.bins_bayes.to_le_bytes(),
            &self.categories.to_le_bytes(),
            &self.table_crc.to_le_bytes(),
            &self.lambda_ml.to_le_bytes(),
            &self.lambda_map.to_le_bytes(),
            &self.log_lambda.to_le_bytes(),
        ];
        let mut at = 0;
        for f in fields {
            if let Some(d) = b.get_mut(at..at + f.len()) {
                d.copy_from_slice(f);
            }
            at += f.len();
        }
        b
    }

    /// Reads the header after the magic (which the section's location checked).
    fn read(r: &mut Reader<'_>) -> Result<Self, QTableError> {
        let _magic = r.take(QUANTIZED_MAGIC.len())?;
        Ok(Self {
            version: r.u8()?,
            bits: r.u8()?,
            flags: r.u8()?,
            reserved: r.u8()?,
            k: r.u16()?,
            bins_ml: r.u16()?,
            bins_bayes: r.u16()?,
            categories: r.u16()?,
            table_crc: r.u32()?,
            lambda_ml: r.f32()?,
            lambda_map: r.f32()?,
            log_lambda: r.f32()?,
        })
    }
}

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
pub(crate) fn index_at(bytes: &[u8], wide: bool, i: usize) -> Option<usize> {
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
pub(crate) fn offset(q: i32, start: i32) -> usize {
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
    let QHeader {
        version,
        bits,
        flags,
        reserved,
        k,
        bins_ml,
        bins_bayes,
        categories,
        table_crc,
        lambda_ml,
        lambda_map,
        log_lambda,
    } = QHeader::read(&mut r)?;
    if !(QUANTIZED_VERSION_1..=QUANTIZED_VERSION).contains(&version) {
        return Err(QTableError::UnsupportedVersion { found: version });
    }
    // Flags: bit 0 the Bayes head; in version 3, bit 1 the open head (which needs the
    // Bayes head). Version 2 is the version of sections with the open head.
    // Version 3 also has bit 2: the objectness feature (which needs the Bayes head).
    let has_maps = version == QUANTIZED_VERSION;
    let max_flags = if has_maps {
        FLAG_BAYES | FLAG_OPEN | FLAG_OBJECTNESS
    } else {
        FLAG_BAYES
    };
    let has_open = version == QUANTIZED_VERSION_2 || (has_maps && flags & FLAG_OPEN != 0);
    let has_feature = has_maps && flags & FLAG_OBJECTNESS != 0;
    if has_feature && flags & FLAG_BAYES == 0 {
        return Err(QTableError::Malformed);
    }
    if reserved != 0 || flags > max_flags || (has_open && flags & FLAG_BAYES == 0) {
        return Err(QTableError::Malformed);
    }
    if version == QUANTIZED_VERSION_2 && flags != FLAG_BAYES {
        return Err(QTableError::Malformed);
    }
    let has_bayes = flags & FLAG_BAYES != 0;
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
pub(super) fn small_log(v: f32) -> bool {
    v.abs() <= MAX_LOG_TERM
}
