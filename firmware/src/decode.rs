//! Decoding the tables from their bytes, as firmware reads them from flash: the shipped
//! table from the calibration sector and the small table with an unknown category.

use super::*;

/// Decoding from the calibration sector, and the checks on the table itself.
pub(crate) fn decode(r: &mut Report) -> Option<EmbeddedTable> {
    let sector = calibration_sector();
    let crc = sector
        .get(sector.len().saturating_sub(4)..)
        .and_then(|b| b.try_into().ok())
        .map(u32::from_le_bytes);
    r.check(
        crc == Some(TABLE_CRC),
        "table CRC",
        format_args!(
            "{crc:x?}, but expected.rs was computed for {TABLE_CRC:08x}: rerun \
             python3 tools/firmware_expected.py"
        ),
    );
    let decoded = match EmbeddedTable::from_bytes(sector) {
        Ok(t) => t,
        Err(e) => {
            r.check(false, "decode", format_args!("{e:?}"));
            return None;
        }
    };
    r.check(true, "decode", format_args!(""));
    r.check(
        decoded == TABLE,
        "embeddings agree",
        format_args!("the decoded table differs from mlmap::embedded::TABLE (MLMAP_TABLE set?)"),
    );
    // Encoding into a buffer sized by the constant gives back the file.
    let mut buf = [0u8; EmbeddedTable::MAX_ENCODED_LEN];
    let same = decoded.to_slice(&mut buf).is_ok_and(|b| *b == *sector);
    r.check(
        same,
        "encode",
        format_args!("to_slice does not reproduce the file"),
    );
    // A damaged sector is refused, never used.
    let mut copy = [0u8; TABLE_FILE.len()];
    copy.copy_from_slice(sector);
    copy[TABLE_FILE.len() / 2] ^= 0x01;
    let damaged = EmbeddedTable::from_bytes(black_box(&copy));
    r.check(
        damaged == Err(DecodeError::Corrupted),
        "damaged sector",
        format_args!("got {:?}, want Err(Corrupted)", damaged.err()),
    );
    Some(decoded)
}

/// The small table with an unknown category, decoded at run time from its bytes; a
/// damaged copy is refused.
pub(crate) fn decode_small(r: &mut Report) -> Option<SmallTable> {
    let bytes: &'static [u8] = black_box(SMALL_FILE);
    let crc = bytes
        .get(bytes.len().saturating_sub(4)..)
        .and_then(|b| b.try_into().ok())
        .map(u32::from_le_bytes);
    r.check(
        crc == Some(SMALL_TABLE_CRC),
        "small table CRC",
        format_args!("{crc:x?}, but expected.rs was computed for {SMALL_TABLE_CRC:08x}"),
    );
    // A flipped bit in epsilon, the last value before the CRC.
    let mut copy = [0u8; SMALL_FILE.len()];
    copy.copy_from_slice(bytes);
    copy[SMALL_FILE.len() - 6] ^= 0x01;
    let damaged = SmallTable::from_bytes(black_box(&copy)).err();
    r.check(
        damaged == Some(DecodeError::Corrupted),
        "damaged small table",
        format_args!("got {damaged:?}, want Corrupted"),
    );
    match SmallTable::from_bytes(bytes) {
        Ok(t) => Some(t),
        Err(e) => {
            r.check(false, "small table decode", format_args!("{e:?}"));
            None
        }
    }
}
