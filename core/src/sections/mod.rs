//! Optional sections appended after a table (docs/FORMAT.md, "Sections after the
//! table"): the quantized heads (`MLMQ`), the drift monitor (`MLMW`, DESIGN §7) and the
//! conformal class sets (`MLMS`, DESIGN §8).
//!
//! Every section starts with its four-byte magic and ends with a trailer of two
//! little-endian `u32`: the section's length (magic to trailer, both included) and the
//! CRC-32 of every byte of the section before that CRC. So a file is
//! `table [section]...`, each section found from the end of the file: the last eight
//! bytes give the last section's length, the bytes before it are the rest of the file,
//! and so on until no known section ends there. Sections may come in any order; a
//! reader asks for one by its magic and ignores the others, and every table decoder
//! reads only what is before the first section ([`table_part`]).
//!
//! The submodules are the sections' own contents: the drift monitor (`monitor`) and the
//! conformal class sets (`conformal`); the quantized heads have their own module tree
//! (`crate::quantized`).

pub mod conformal;
pub mod monitor;

use crate::format::wire::CRC_CHECK;

/// Bytes of a section's trailer: its length and its CRC-32.
pub(crate) const TRAILER_LEN: usize = 8;

/// The magic of the quantized section.
pub(crate) const QUANTIZED: [u8; 4] = crate::quantized::qtable::QUANTIZED_MAGIC;
/// The magic of the monitor section.
pub(crate) const MONITOR: [u8; 4] = *b"MLMW";
/// The magic of the conformal section.
pub(crate) const CONFORMAL: [u8; 4] = *b"MLMS";

/// Every magic a section may start with.
const KNOWN: [[u8; 4]; 3] = [QUANTIZED, MONITOR, CONFORMAL];

/// What ends a byte string.
enum Last<'a> {
    /// No section of a known magic ends here.
    Nothing,
    /// A section whose CRC checks out, and the bytes before it.
    Section {
        magic: [u8; 4],
        section: &'a [u8],
        rest: &'a [u8],
    },
    /// A section of this magic whose CRC does not match.
    Corrupted { magic: [u8; 4] },
}

/// The last section of `bytes`, if one ends there.
fn last(bytes: &[u8]) -> Last<'_> {
    let n = bytes.len();
    let Some(trailer) = n
        .checked_sub(TRAILER_LEN)
        .and_then(|at| bytes.get(at..))
        .and_then(|t| <[u8; TRAILER_LEN]>::try_from(t).ok())
    else {
        return Last::Nothing;
    };
    let [l0, l1, l2, l3, c0, c1, c2, c3] = trailer;
    let len = u32::from_le_bytes([l0, l1, l2, l3]) as usize;
    let crc = u32::from_le_bytes([c0, c1, c2, c3]);
    let Some(start) = n.checked_sub(len).filter(|_| len >= 4 + TRAILER_LEN) else {
        return Last::Nothing;
    };
    let (Some(section), Some(rest)) = (bytes.get(start..), bytes.get(..start)) else {
        return Last::Nothing;
    };
    let Some(magic) = section
        .get(..4)
        .and_then(|m| <[u8; 4]>::try_from(m).ok())
        .filter(|m| KNOWN.contains(m))
    else {
        return Last::Nothing;
    };
    let payload = section.get(..len - 4).unwrap_or_default();
    if CRC_CHECK.checksum(payload) != crc {
        return Last::Corrupted { magic };
    }
    Last::Section {
        magic,
        section,
        rest,
    }
}

/// Why [`find`] found no section.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Missing {
    /// No section of that magic ends the file or follows the table.
    Absent,
    /// A section of that magic is there, but its CRC does not match.
    Corrupted,
}

/// The section of `magic` in `bytes` and the table before every section (empty when
/// `bytes` holds sections only).
pub(crate) fn find(bytes: &[u8], magic: [u8; 4]) -> Result<(&[u8], &[u8]), Missing> {
    let mut rest = bytes;
    let mut found = None;
    loop {
        match last(rest) {
            Last::Section {
                magic: m,
                section,
                rest: before,
            } => {
                if m == magic && found.is_none() {
                    found = Some(section);
                }
                rest = before;
            }
            Last::Corrupted { magic: m } if m == magic && found.is_none() => {
                return Err(Missing::Corrupted)
            }
            Last::Corrupted { .. } | Last::Nothing => break,
        }
    }
    found.map(|s| (s, rest)).ok_or(Missing::Absent)
}

/// The table of a file that may have sections appended: the bytes before the first
/// section whose magic and CRC check out, otherwise all of `bytes`. Every table decoder
/// reads through it, so a file with sections decodes as the table alone.
pub(crate) fn table_part(bytes: &[u8]) -> &[u8] {
    let mut rest = bytes;
    while let Last::Section { rest: before, .. } = last(rest) {
        rest = before;
    }
    if rest.is_empty() {
        bytes
    } else {
        rest
    }
}

/// The section of `magic` among the sections appended to `bytes` (DESIGN §3), its CRC
/// checked; `None` when there is none or its CRC does not match.
pub fn section_of(bytes: &[u8], magic: [u8; 4]) -> Option<&[u8]> {
    find(bytes, magic).ok().map(|(s, _)| s)
}

/// The table of a file with appended sections: the bytes every table decoder reads
/// (all of `bytes` when no section ends it).
pub fn table_of(bytes: &[u8]) -> &[u8] {
    table_part(bytes)
}

/// Writes the trailer of a section whose bytes before the trailer are `out[..len - 8]`:
/// the length `len = out.len()` and the CRC-32. `out` is the whole section.
pub(crate) fn seal(out: &mut [u8]) -> Option<()> {
    let len = u32::try_from(out.len()).ok()?;
    let at = out.len().checked_sub(TRAILER_LEN)?;
    out.get_mut(at..at + 4)?.copy_from_slice(&len.to_le_bytes());
    let crc = CRC_CHECK.checksum(out.get(..at + 4)?);
    out.get_mut(at + 4..)?.copy_from_slice(&crc.to_le_bytes());
    Some(())
}

/// The CRC of the table a section follows: the table's last four bytes (its own CRC).
pub(crate) fn table_crc(table: &[u8]) -> Option<u32> {
    let at = table.len().checked_sub(4)?;
    let b = <[u8; 4]>::try_from(table.get(at..)?).ok()?;
    Some(u32::from_le_bytes(b))
}

/// A little-endian reader over a section's bytes; every read fails past the end.
pub(crate) struct Reader<'a>(pub(crate) &'a [u8]);

impl<'a> Reader<'a> {
    pub(crate) fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let (head, tail) = self.0.split_at_checked(n)?;
        self.0 = tail;
        Some(head)
    }
    pub(crate) fn array<const N: usize>(&mut self) -> Option<[u8; N]> {
        self.take(N).and_then(|b| b.try_into().ok())
    }
    pub(crate) fn u8(&mut self) -> Option<u8> {
        self.array::<1>().map(|[b]| b)
    }
    pub(crate) fn u16(&mut self) -> Option<u16> {
        self.array().map(u16::from_le_bytes)
    }
    pub(crate) fn u32(&mut self) -> Option<u32> {
        self.array().map(u32::from_le_bytes)
    }
    pub(crate) fn f32(&mut self) -> Option<f32> {
        self.array().map(f32::from_le_bytes)
    }
    pub(crate) fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// A little-endian writer into a section's buffer; every write fails past the end.
pub(crate) struct Writer<'a> {
    pub(crate) buf: &'a mut [u8],
    pub(crate) at: usize,
}

impl Writer<'_> {
    pub(crate) fn put(&mut self, bytes: &[u8]) -> Option<()> {
        let end = self.at.checked_add(bytes.len())?;
        self.buf.get_mut(self.at..end)?.copy_from_slice(bytes);
        self.at = end;
        Some(())
    }
    pub(crate) fn u8(&mut self, v: u8) -> Option<()> {
        self.put(&[v])
    }
    pub(crate) fn u16(&mut self, v: u16) -> Option<()> {
        self.put(&v.to_le_bytes())
    }
    pub(crate) fn u32(&mut self, v: u32) -> Option<()> {
        self.put(&v.to_le_bytes())
    }
    pub(crate) fn f32(&mut self, v: f32) -> Option<()> {
        self.put(&v.to_le_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn section(magic: [u8; 4], body: &[u8]) -> Vec<u8> {
        let mut s = Vec::from(magic);
        s.extend_from_slice(body);
        s.extend_from_slice(&[0; TRAILER_LEN]);
        seal(&mut s).unwrap();
        s
    }

    #[test]
    fn any_order_and_combination() {
        let table = b"not a table, but ends in four bytes".to_vec();
        let q = section(QUANTIZED, b"q-body");
        let w = section(MONITOR, b"monitor");
        let s = section(CONFORMAL, b"sets");
        for parts in [
            std::vec![&q, &w, &s],
            std::vec![&s, &w],
            std::vec![&w],
            std::vec![&w, &q],
        ] {
            let mut file = table.clone();
            for p in &parts {
                file.extend_from_slice(p);
            }
            assert_eq!(table_part(&file), &table[..]);
            for (magic, want) in [(QUANTIZED, &q), (MONITOR, &w), (CONFORMAL, &s)] {
                let got = find(&file, magic);
                if parts.contains(&want) {
                    assert_eq!(got, Ok((&want[..], &table[..])));
                } else {
                    assert_eq!(got, Err(Missing::Absent));
                }
            }
        }
        // A section alone: no table before it.
        assert_eq!(find(&w, MONITOR), Ok((&w[..], &[][..])));
        assert_eq!(table_part(&w), &w[..]);
    }

    #[test]
    fn corrupted_and_truncated() {
        let table = b"0123456789".to_vec();
        let mut file = table.clone();
        file.extend_from_slice(&section(MONITOR, b"abc"));
        let last = file.len() - 10;
        file[last] ^= 1;
        assert_eq!(find(&file, MONITOR), Err(Missing::Corrupted));
        assert_eq!(table_part(&file), &file[..]);
        for cut in 0..file.len() {
            let _ = find(&file[..cut], MONITOR);
            let _ = table_part(&file[..cut]);
        }
        // A length beyond the file, or too small to hold a magic.
        let mut bad = table.clone();
        bad.extend_from_slice(&u32::MAX.to_le_bytes());
        bad.extend_from_slice(&0u32.to_le_bytes());
        assert_eq!(find(&bad, MONITOR), Err(Missing::Absent));
    }
}
