//! Exact round trips, the reference encoder's bytes, every corruption and truncation
//! rejected, other shapes, magics and versions, and the size bounds.

use super::*;

#[test]
fn round_trip_is_exact() {
    for bytes in [SHIPPED_MLMAP, &mlmap::embedded::BYTES[..]] {
        let t = Shipped::from_bytes(bytes).unwrap();
        let again = encode(&t);
        assert_eq!(again, bytes, "re-encoding is byte-identical");
        assert_eq!(Shipped::from_bytes(&again).unwrap(), t);
    }
    for bytes in [SMALL_MLMAP, SMALL_CLAMP_MLMAP] {
        let t = Small::from_bytes(bytes).unwrap();
        assert_eq!(encode(&t), bytes);
        assert_eq!(Small::from_bytes(&encode(&t)).unwrap(), t);
    }
    // Extreme but valid values survive bit for bit: subnormal and huge frequencies'
    // neighbours, the largest lambda, the variance floor, u64::MAX rows, long names.
    let mut specs = small_specs();
    specs[0].rows = u64::MAX;
    specs[0].name = "a-class-name-of-31-bytes-long!!";
    specs[1].ml_freqs = [f32::from_bits(1), 0.5, 0.5 - f32::from_bits(1), 0.0];
    specs[1].variance = mlmap::VARIANCE_FLOOR as f32;
    specs[2].mean = -3e38;
    specs[2].ml_range = (-1e-30, 1e-30);
    let mut settings = small_settings(UpperTail::Clamp);
    settings.lambda_ml = MAX_LAMBDA;
    settings.lambda_map = f32::from_bits(1);
    settings.edge_mode = mlmap::EdgeMode::Matlab;
    let t = Small::from_parts(settings, specs).unwrap();
    let bytes = encode(&t);
    let back = Small::from_bytes(&bytes).unwrap();
    assert_eq!(back, t);
    assert_eq!(encode(&back), bytes);
    assert_eq!(back.rows().first(), Some(&u64::MAX));
    assert_eq!(back.settings().lambda_map.to_bits(), 1);
}

/// The library's encoder, the reference encoder (`tools/mlmap_ref.py`) and the test's
/// own raw writer produce the same bytes for the hand-checkable table.
#[test]
fn small_table_bytes_equal_the_reference_encoder() {
    let t = Small::from_parts(small_settings(UpperTail::Zero), small_specs()).unwrap();
    assert_eq!(encode(&t), SMALL_MLMAP);
    let clamp = Small::from_parts(small_settings(UpperTail::Clamp), small_specs()).unwrap();
    assert_eq!(encode(&clamp), SMALL_CLAMP_MLMAP);
    assert_eq!(RawTable::small().encode(), SMALL_MLMAP);
    // Decoding the reference's file gives the very table built from parts.
    assert_eq!(small(), t);
    // The files differ only in the tail policy byte (and so in the CRC).
    let differing: Vec<usize> = (0..SMALL_MLMAP.len())
        .filter(|&i| SMALL_MLMAP[i] != SMALL_CLAMP_MLMAP[i])
        .collect();
    let tail_byte = 4 + 4 + 1; // magic, four one-byte varints, edge mode
    assert_eq!(differing[0], tail_byte);
    assert!(differing[1..].iter().all(|&i| i >= SMALL_MLMAP.len() - 4));
}

/// CRC-32 detects every error burst of up to 32 bits, so every single-byte change of a
/// table is rejected: in the magic as `NotATable`, anywhere else as `Corrupted`.
fn assert_every_byte_corruption_rejected<
    const K: usize,
    const BM: usize,
    const BP: usize,
    const BB: usize,
    const C: usize,
>(
    bytes: &[u8],
    masks: impl Iterator<Item = u8> + Clone,
) -> usize {
    let mut buf = bytes.to_vec();
    let mut n = 0;
    for pos in 0..bytes.len() {
        for mask in masks.clone() {
            buf[pos] ^= mask;
            let got = Table::<K, BM, BP, BB, C>::from_bytes(&buf);
            let want = if pos < 4 {
                DecodeError::NotATable
            } else {
                DecodeError::Corrupted
            };
            assert_eq!(got.err(), Some(want), "byte {pos} ^ {mask:#04x}");
            #[cfg(feature = "std")]
            assert_eq!(
                mlmap::host::DynTable::from_bytes(&buf).err(),
                Some(want),
                "DynTable: byte {pos} ^ {mask:#04x}"
            );
            buf[pos] ^= mask;
            n += 1;
        }
    }
    assert_eq!(buf, bytes);
    n
}

#[test]
fn every_single_byte_corruption_is_rejected() {
    let n = assert_every_byte_corruption_rejected::<3, 4, 2, 0, 0>(SMALL_MLMAP, 1..=255u8);
    assert_eq!(n, SMALL_MLMAP.len() * 255);
    // Version 3: the shipped table (every head, the open head's parameters included).
    assert_eq!(SHIPPED_MLMAP[4], 3, "the shipped table is a version-3 file");
    let n = assert_every_byte_corruption_rejected::<3, 22, 17, 22, 4>(SHIPPED_MLMAP, 1..=255u8);
    assert_eq!(n, SHIPPED_MLMAP.len() * 255);
    // The small Bayes tables: every bit of every byte, and every byte inverted (all 255
    // values run above; these only add the Bayes section's bytes in other shapes).
    let masks = (0..8).map(|b| 1u8 << b).chain([0xff]);
    let n =
        assert_every_byte_corruption_rejected::<3, 4, 2, 4, 4>(SMALL_BAYES_MLMAP, masks.clone());
    assert_eq!(n, SMALL_BAYES_MLMAP.len() * 9);
    let n = assert_every_byte_corruption_rejected::<3, 4, 2, 4, 3>(SMALL_BAYES_NOBG_MLMAP, masks);
    assert_eq!(n, SMALL_BAYES_NOBG_MLMAP.len() * 9);
}

#[test]
fn truncation_at_every_length_is_rejected() {
    for bytes in [SMALL_MLMAP, SHIPPED_MLMAP, SMALL_BAYES_MLMAP] {
        for len in 0..bytes.len() {
            let got = Shipped::from_bytes(&bytes[..len]).err();
            let got_small = Small::from_bytes(&bytes[..len]).err();
            for got in [got, got_small] {
                match got {
                    Some(DecodeError::Truncated | DecodeError::Corrupted) => {}
                    other => panic!("{len} bytes: {other:?}"),
                }
            }
            if len < 4 {
                // A prefix of the magic is not a different file, only a short one.
                assert_eq!(got_small, Some(DecodeError::Truncated), "{len} bytes");
            }
        }
        // Cut short and given a valid checksum again: the body no longer parses.
        for len in 4..bytes.len() - 4 {
            let cut = with_crc(&bytes[..len]);
            let got = Small::from_bytes(&cut).err();
            assert!(
                matches!(
                    got,
                    Some(
                        DecodeError::Truncated
                            | DecodeError::Malformed
                            | DecodeError::ShapeMismatch { .. }
                            | DecodeError::BayesShapeMismatch { .. }
                    )
                ),
                "{len} bytes + CRC: {got:?}"
            );
        }
    }
}

#[test]
fn wrong_shape_is_a_shape_mismatch() {
    assert_eq!(
        Table::<3, 4, 3>::from_bytes(SMALL_MLMAP),
        Err(DecodeError::ShapeMismatch {
            expected: (3, 4, 3),
            found: (3, 4, 2)
        })
    );
    assert_eq!(
        Table::<2, 4, 2>::from_bytes(SMALL_MLMAP),
        Err(DecodeError::ShapeMismatch {
            expected: (2, 4, 2),
            found: (3, 4, 2)
        })
    );
    assert_eq!(
        Table::<3, 22, 17>::from_bytes(SMALL_MLMAP),
        Err(DecodeError::ShapeMismatch {
            expected: (3, 22, 17),
            found: (3, 4, 2)
        })
    );
    assert_eq!(
        Table::<3, 17, 22>::from_bytes(SHIPPED_MLMAP),
        Err(DecodeError::ShapeMismatch {
            expected: (3, 17, 22),
            found: (3, 22, 17)
        })
    );
    // A header that disagrees with its own body: K = 2 declared, 3 classes follow.
    let mut raw = RawTable::small();
    raw.k = 2;
    assert_eq!(
        Table::<2, 4, 2>::from_bytes(&raw.encode()),
        Err(DecodeError::Malformed)
    );
    // K = 3 declared, 2 classes follow.
    let mut raw = RawTable::small();
    raw.class_count = 2;
    raw.classes.pop();
    assert_eq!(
        Small::from_bytes(&raw.encode()),
        Err(DecodeError::Malformed)
    );
}

#[test]
fn wrong_magic_is_not_a_table() {
    for magic in [*b"MLMQ", *b"mlmp", *b"\x89PNG", [0; 4], *b"PMLM"] {
        let mut raw = RawTable::small();
        raw.magic = magic;
        assert_eq!(
            Small::from_bytes(&raw.encode()),
            Err(DecodeError::NotATable),
            "{magic:?}"
        );
    }
    assert_eq!(Small::from_bytes(b"GIF89a"), Err(DecodeError::NotATable));
    assert_eq!(Small::from_bytes(b"X"), Err(DecodeError::NotATable));
    assert_eq!(Small::from_bytes(b""), Err(DecodeError::Truncated));
    assert_eq!(Small::from_bytes(b"MLMP"), Err(DecodeError::Truncated));
}

/// Found by the `c_api` fuzz target: a header announcing no class and the largest Bayes
/// shape made the host decoder allocate room for the objectness feature's terms (B * C
/// floats, gigabytes) before finding the body empty. Refused without allocating more
/// than the body backs.
#[cfg(feature = "std")]
#[test]
fn a_header_without_classes_allocates_nothing_for_the_bayes_head() {
    // magic, version 2, K = 0, ML and MAP bins 1, Bayes bins and categories 65535
    // (varint FF FF 03 each), settings, no class, CRC.
    let mut b = b"MLMP".to_vec();
    b.extend_from_slice(&[2, 0, 1, 1, 0xff, 0xff, 0x03, 0xff, 0xff, 0x03]);
    b.extend_from_slice(&[0, 0]);
    b.extend_from_slice(&0.01f32.to_le_bytes());
    b.extend_from_slice(&0.01f32.to_le_bytes());
    b.push(0);
    let crc = crate::support::crc32(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    assert!(mlmap::host::DynTable::from_bytes(&b).is_err());
}

#[test]
fn other_versions_are_unsupported() {
    // Version 2 is read, but requires a Bayes section: a version-1 body under a
    // version-2 header is refused.
    let mut raw = RawTable::small();
    raw.version = 2;
    assert!(Small::from_bytes(&raw.encode()).is_err());
    // Version 3 likewise: a Bayes section and the open head's parameters.
    let mut raw = RawTable::small();
    raw.version = 3;
    assert!(Small::from_bytes(&raw.encode()).is_err());
    // Version 4 likewise: its header holds the Bayes shape, and maps follow.
    let mut raw = RawTable::small();
    raw.version = 4;
    assert!(Small::from_bytes(&raw.encode()).is_err());
    for version in [0u64, 5, 127, 300, u64::from(u16::MAX)] {
        let mut raw = RawTable::small();
        raw.version = version;
        assert_eq!(
            Small::from_bytes(&raw.encode()),
            Err(DecodeError::UnsupportedVersion {
                found: version as u16
            }),
            "version {version}"
        );
    }
    // A version that does not even fit the field.
    let mut raw = RawTable::small();
    raw.version = 1 << 16;
    assert_eq!(
        Small::from_bytes(&raw.encode()),
        Err(DecodeError::Malformed)
    );
}

#[test]
fn trailing_bytes_are_rejected() {
    // Inside the checksummed part: the body has bytes left over.
    for extra in [&[0u8][..], &[1, 2, 3], &[0; 64]] {
        let mut raw = RawTable::small();
        raw.trailing = extra.to_vec();
        assert_eq!(
            Small::from_bytes(&raw.encode()),
            Err(DecodeError::Malformed)
        );
    }
    // After the checksum: the last four bytes are no longer the checksum.
    for extra in [&[0u8][..], &[0; 4], &SMALL_MLMAP[SMALL_MLMAP.len() - 4..]] {
        let mut bytes = SMALL_MLMAP.to_vec();
        bytes.extend_from_slice(extra);
        assert_eq!(Small::from_bytes(&bytes), Err(DecodeError::Corrupted));
    }
    // Two tables back to back.
    let twice = [SMALL_MLMAP, SMALL_MLMAP].concat();
    assert_eq!(Small::from_bytes(&twice), Err(DecodeError::Corrupted));
}

fn assert_max_len_bounds<const K: usize, const BM: usize, const BP: usize>() -> usize {
    let t = worst_case::<K, BM, BP>();
    let max = Table::<K, BM, BP>::MAX_ENCODED_LEN;
    let mut buf = vec![0u8; max];
    let len = t
        .to_slice(&mut buf)
        .expect("MAX_ENCODED_LEN suffices")
        .len();
    assert!(len <= max);
    // Exactly `len` bytes suffice, and no shorter buffer does (every length for small
    // tables; a spread of lengths for big ones, the check being quadratic).
    let exact = encode(&t);
    assert_eq!(exact.len(), len);
    let step = (len / 500).max(1);
    for short in (0..len).step_by(step).chain([len - 1]) {
        assert_eq!(
            t.to_slice(&mut buf[..short]).err(),
            Some(EncodeError::BufferTooSmall),
            "{short} bytes"
        );
    }
    assert_eq!(Table::<K, BM, BP>::from_bytes(&exact), Ok(t));
    // The bound is not loose: only the header's varints can be shorter than assumed.
    assert!(
        max - len <= 16,
        "{K}x{BM}x{BP}: max {max}, worst case {len}"
    );
    len
}

#[test]
fn max_encoded_len_bounds_the_worst_case() {
    assert_max_len_bounds::<3, 22, 17>();
    assert_max_len_bounds::<2, 1, 1>();
    assert_max_len_bounds::<5, 7, 30>();
    assert_max_len_bounds::<2, 200, 130>(); // two-byte bin counts
    assert_max_len_bounds::<130, 2, 2>(); // a two-byte class count
}

#[test]
fn shipped_table_size() {
    let t = shipped();
    let len = encode(&t).len();
    eprintln!(
        "tables/default.mlmap (K = 3, 22 / 17 / 22 bins, 4 Bayes categories): {len} bytes encoded, MAX_ENCODED_LEN = {}",
        Shipped::MAX_ENCODED_LEN
    );
    assert_eq!(len, SHIPPED_MLMAP.len());
    // Goal for K = 3 with every head (22 Bayes bins, 4 categories): at most 2 KiB.
    assert!((1500..=2048).contains(&len), "{len} bytes");
    assert!(len <= Shipped::MAX_ENCODED_LEN);
    // A static buffer can be sized at compile time.
    static BUF: [u8; Shipped::MAX_ENCODED_LEN] = [0; Shipped::MAX_ENCODED_LEN];
    assert!(BUF.len() >= len);
}

#[test]
fn crc_can_be_recomputed_by_the_tests() {
    // The helpers the other tests rely on: a fixed CRC makes the original valid again.
    assert_eq!(fix_crc(SMALL_MLMAP), SMALL_MLMAP);
    let mut bytes = SMALL_MLMAP.to_vec();
    *bytes.last_mut().unwrap() ^= 1;
    assert_eq!(Small::from_bytes(&bytes), Err(DecodeError::Corrupted));
    assert_eq!(Small::from_bytes(&fix_crc(&bytes)), Ok(small()));
}
