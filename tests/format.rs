//! The `.mlmap` file (DESIGN §3, docs/FORMAT.md): exact round trips, agreement with the
//! reference encoder, and rejection of every corrupted, truncated or invalid file with
//! the matching error.

use mlmap::{
    CharKind, DecodeError, EncodeError, Head, NameError, Table, TableError, UpperTail, MAX_LAMBDA,
    MAX_LAMBDA_BAYES, NAME_MAX,
};

use crate::support::{
    fix_crc, log_term, shipped, small, small_bayes, small_bayes_nobg, small_settings, small_specs,
    with_crc, RawBayes, RawTable, Shipped, Small, SmallBayes, SmallBayesNoBg, SHIPPED_MLMAP,
    SMALL_BAYES_MLMAP, SMALL_BAYES_NOBG_MLMAP, SMALL_CLAMP_MLMAP, SMALL_MLMAP,
};

fn encode<const K: usize, const BM: usize, const BP: usize, const BB: usize, const C: usize>(
    t: &Table<K, BM, BP, BB, C>,
) -> Vec<u8> {
    let mut buf = vec![0u8; Table::<K, BM, BP, BB, C>::MAX_ENCODED_LEN];
    let len = t
        .to_slice(&mut buf)
        .expect("MAX_ENCODED_LEN suffices")
        .len();
    buf.truncate(len);
    buf
}

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

/// Breaks one field of the small table (keeping the CRC right) and expects `want`.
fn assert_broken(what: &str, change: impl FnOnce(&mut RawTable), want: DecodeError) {
    let mut raw = RawTable::small();
    change(&mut raw);
    let bytes = raw.encode();
    assert_eq!(Small::from_bytes(&bytes), Err(want), "{what}");
    #[cfg(feature = "std")]
    {
        // The host decoder agrees on every invariant (it has no shape to mismatch).
        let dyn_got = mlmap::host::DynTable::from_bytes(&bytes).err();
        if matches!(want, DecodeError::Invalid(TableError::BinCount { .. })) {
            assert!(dyn_got.is_some(), "DynTable: {what}");
        } else {
            assert_eq!(dyn_got, Some(want), "DynTable: {what}");
        }
    }
}

#[test]
fn each_broken_invariant_has_its_error() {
    use DecodeError::Invalid;
    use TableError::*;
    let bad_edges: [(f32, f32); 7] = [
        (1.0, 1.0),
        (2.0, 1.0),
        (f32::NAN, 1.0),
        (0.0, f32::NAN),
        (f32::NEG_INFINITY, 1.0),
        (0.0, f32::INFINITY),
        // One ulp apart: the inner edges (w below one ulp) collapse onto lo or hi.
        (1e6, 1e6f32.next_up()),
    ];
    for class in 0..3u16 {
        let c = usize::from(class);
        for (lo, hi) in bad_edges {
            assert_broken(
                &format!("ML edges {lo} {hi} of class {class}"),
                |r| (r.classes[c].ml_lo, r.classes[c].ml_hi) = (lo, hi),
                Invalid(Edges {
                    head: Head::Ml,
                    class,
                }),
            );
            assert_broken(
                &format!("MAP edges {lo} {hi} of class {class}"),
                |r| (r.classes[c].map_lo, r.classes[c].map_hi) = (lo, hi),
                Invalid(Edges {
                    head: Head::Map,
                    class,
                }),
            );
        }
        let bad_ml_freqs: [[f32; 4]; 6] = [
            [0.1, 0.2, 0.3, 0.3],           // sums to 0.9
            [0.1, 0.2, 0.3, 0.4002],        // 1.0002: outside 1 +- 1e-4
            [-0.1, 0.3, 0.4, 0.4],          // negative
            [f32::NAN, 0.2, 0.4, 0.4],      // NaN
            [f32::INFINITY, 0.0, 0.0, 0.0], // infinite
            [0.0, 0.0, 0.0, 0.0],           // nothing
        ];
        for freqs in bad_ml_freqs {
            assert_broken(
                &format!("ML frequencies {freqs:?} of class {class}"),
                |r| r.classes[c].ml_freqs = freqs.to_vec(),
                Invalid(Frequencies {
                    head: Head::Ml,
                    class,
                }),
            );
        }
        for freqs in [[0.5f32, 0.4], [1.5, -0.5], [f32::NAN, 1.0], [-0.0, 0.9]] {
            assert_broken(
                &format!("MAP frequencies {freqs:?} of class {class}"),
                |r| r.classes[c].map_freqs = freqs.to_vec(),
                Invalid(Frequencies {
                    head: Head::Map,
                    class,
                }),
            );
        }
        // One frequency short of the declared bin count.
        assert_broken(
            &format!("3 ML frequencies in class {class}"),
            |r| r.classes[c].ml_freqs = vec![0.25, 0.25, 0.5],
            Invalid(BinCount {
                head: Head::Ml,
                class,
            }),
        );
        assert_broken(
            &format!("1 MAP frequency in class {class}"),
            |r| r.classes[c].map_freqs = vec![1.0],
            Invalid(BinCount {
                head: Head::Map,
                class,
            }),
        );
        for mean in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_broken(
                &format!("mean {mean} of class {class}"),
                |r| r.classes[c].mean = mean,
                Invalid(Mean { class }),
            );
        }
        for var in [
            0.0,
            -0.0,
            -1.0,
            f32::NAN,
            f32::INFINITY,
            1e-40,
            f32::from_bits(1),
        ] {
            assert_broken(
                &format!("variance {var} of class {class}"),
                |r| r.classes[c].variance = var,
                Invalid(Variance { class }),
            );
        }
        let long = vec![b'x'; NAME_MAX + 1];
        for (name, error) in [
            (&b""[..], NameError::Empty),
            (b"background", NameError::Reserved),
            (&long, NameError::TooLong),
        ] {
            assert_broken(
                &format!("name {:?} of class {class}", String::from_utf8_lossy(name)),
                |r| r.classes[c].name = name.to_vec(),
                Invalid(Name { class, error }),
            );
        }
        // Not UTF-8: the body does not follow the format.
        assert_broken(
            &format!("non-UTF-8 name of class {class}"),
            |r| r.classes[c].name = vec![0xff, 0xfe],
            DecodeError::Malformed,
        );
    }
    for lambda in [
        0.0,
        -0.0,
        -1e-3,
        f32::NAN,
        f32::INFINITY,
        MAX_LAMBDA.next_up(),
        1e7,
    ] {
        assert_broken(
            &format!("ML lambda {lambda}"),
            |r| r.lambda_ml = lambda,
            Invalid(Lambda { head: Head::Ml }),
        );
        assert_broken(
            &format!("MAP lambda {lambda}"),
            |r| r.lambda_map = lambda,
            Invalid(Lambda { head: Head::Map }),
        );
    }
    assert_broken(
        "third name repeats the first",
        |r| r.classes[2].name = b"car".to_vec(),
        Invalid(DuplicateName { class: 2 }),
    );
    assert_broken(
        "second name repeats the first",
        |r| r.classes[1].name = b"car".to_vec(),
        Invalid(DuplicateName { class: 1 }),
    );
    for tag in [2u8, 255] {
        assert_broken(
            "edge mode tag",
            |r| r.edge_mode = tag,
            DecodeError::Malformed,
        );
        assert_broken("tail tag", |r| r.upper_tail = tag, DecodeError::Malformed);
    }
    // The largest valid values are accepted: the broken cases above are not rejected
    // for some unrelated reason.
    let mut raw = RawTable::small();
    raw.lambda_ml = MAX_LAMBDA;
    raw.classes[0].name = vec![b'x'; NAME_MAX];
    raw.classes[0].rows = u64::MAX;
    raw.classes[1].ml_freqs = vec![0.1, 0.2, 0.3, 0.40009];
    raw.edge_mode = 1;
    raw.upper_tail = 1;
    let t = Small::from_bytes(&raw.encode()).unwrap();
    assert_eq!(t.class_name(0).map(str::len), Some(NAME_MAX));
}

/// Names that break the rule of DESIGN §6.15 but that a table of format version 1 or 2
/// may hold: such files keep decoding (in a fixed-size and in a host table), while no
/// table holding one can be built, so no new file holds one.
#[test]
fn old_tables_keep_names_new_tables_refuse() {
    use TableError::Name;
    let ch = |ch, at, kind| NameError::Char { ch, at, kind };
    let hostile: [(&str, NameError); 6] = [
        ("a\nb", ch('\n', 1, CharKind::Control)),
        ("\u{1b}[2J", ch('\u{1b}', 0, CharKind::Control)),
        ("nul\0", ch('\0', 3, CharKind::Control)),
        ("rac\u{202E}", ch('\u{202E}', 3, CharKind::Invisible)),
        ("a\u{2029}b", ch('\u{2029}', 1, CharKind::Separator)),
        ("car ", NameError::Padded),
    ];
    for (name, error) in hostile {
        for version_2 in [false, true] {
            let mut raw = if version_2 {
                RawTable::small_bayes()
            } else {
                RawTable::small()
            };
            raw.classes[1].name = name.as_bytes().to_vec();
            let bytes = raw.encode();
            assert_eq!(bytes[4], 1 + u8::from(version_2));
            let decoded = if version_2 {
                SmallBayes::from_bytes(&bytes).map(|t| t.class_name(1).map(str::to_owned))
            } else {
                Small::from_bytes(&bytes).map(|t| t.class_name(1).map(str::to_owned))
            };
            assert_eq!(decoded, Ok(Some(name.to_owned())), "{name:?}");
            #[cfg(feature = "std")]
            {
                let d = mlmap::host::DynTable::from_bytes(&bytes).unwrap();
                assert_eq!(d.class_names().nth(1), Some(name));
                // Re-encoding the decoded table gives the same file back.
                assert_eq!(d.to_vec().unwrap(), bytes);
            }
        }
        let mut specs = small_specs();
        specs[1].name = name;
        assert_eq!(
            Small::from_parts(small_settings(UpperTail::Zero), specs),
            Err(Name { class: 1, error }),
            "{name:?}"
        );
        #[cfg(feature = "std")]
        {
            let classes = small_specs()
                .into_iter()
                .enumerate()
                .map(|(i, c)| mlmap::ClassSpec {
                    name: if i == 1 { name } else { c.name },
                    ml_freqs: c.ml_freqs.to_vec(),
                    map_freqs: c.map_freqs.to_vec(),
                    rows: c.rows,
                    mean: c.mean,
                    variance: c.variance,
                    ml_range: c.ml_range,
                    map_range: c.map_range,
                })
                .collect();
            assert_eq!(
                mlmap::host::DynTable::new(small_settings(UpperTail::Zero), classes).err(),
                Some(Name { class: 1, error }),
                "{name:?}"
            );
        }
    }
}

/// `ClassCount` is the host decoder's: a fixed-size table has its K in its type.
#[cfg(feature = "std")]
#[test]
fn one_class_is_too_few() {
    let mut raw = RawTable::small();
    raw.k = 1;
    raw.class_count = 1;
    raw.classes.truncate(1);
    assert_eq!(
        mlmap::host::DynTable::from_bytes(&raw.encode()),
        Err(DecodeError::Invalid(TableError::ClassCount))
    );
}

/// A valid table of shape `K, BM, BP` with the longest names and row counts.
fn worst_case<const K: usize, const BM: usize, const BP: usize>() -> Table<K, BM, BP> {
    let names: Vec<String> = (0..K)
        .map(|i| format!("{i:0>width$}", width = NAME_MAX))
        .collect();
    let classes = std::array::from_fn(|i| mlmap::ClassSpec {
        name: names[i].as_str(),
        rows: u64::MAX,
        mean: -1.234_567_8e-20,
        variance: 1e30,
        ml_range: (-3.0e30, 3.0e30),
        ml_freqs: [1.0 / BM as f32; BM],
        map_range: (f32::MIN_POSITIVE, 1.0),
        map_freqs: [1.0 / BP as f32; BP],
    });
    Table::from_parts(small_settings(UpperTail::Clamp), classes).expect("a valid worst case")
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

// ---------------------------------------------------------------------------------------
// Format version 2: the Bayes head (DESIGN §1.6, docs/FORMAT.md).

/// Re-encodes a table through `DynTable` (the host decoder and encoder).
#[cfg(feature = "std")]
fn dyn_round_trip(bytes: &[u8]) -> Vec<u8> {
    mlmap::host::DynTable::from_bytes(bytes)
        .expect("a valid table")
        .to_vec()
        .expect("encodes")
}

#[test]
fn v2_round_trips_are_byte_exact() {
    let t = shipped();
    assert!(t.bayes_head().is_some());
    assert_eq!(encode(&t), SHIPPED_MLMAP);
    let t = small_bayes();
    assert_eq!(encode(&t), SMALL_BAYES_MLMAP);
    assert_eq!(SmallBayes::from_bytes(&encode(&t)).unwrap(), t);
    let t = small_bayes_nobg();
    assert_eq!(encode(&t), SMALL_BAYES_NOBG_MLMAP);
    assert_eq!(SmallBayesNoBg::from_bytes(&encode(&t)).unwrap(), t);
    #[cfg(feature = "std")]
    for bytes in [SHIPPED_MLMAP, SMALL_BAYES_MLMAP, SMALL_BAYES_NOBG_MLMAP] {
        assert_eq!(dyn_round_trip(bytes), bytes);
    }
}

/// The reference encoder (`tools/mlmap_ref.py`), the raw writer of the tests and the
/// library's encoder write the same version-2 bytes for the small Bayes tables.
#[test]
fn small_bayes_bytes_equal_the_reference_encoder() {
    assert_eq!(RawTable::small_bayes().encode(), SMALL_BAYES_MLMAP);
    assert_eq!(
        RawTable::small_bayes_nobg().encode(),
        SMALL_BAYES_NOBG_MLMAP
    );
    // Header: magic, version 2, K 3, ML bins 4, MAP bins 2, Bayes bins 4, categories.
    assert_eq!(SMALL_BAYES_MLMAP[..10], *b"MLMP\x02\x03\x04\x02\x04\x04");
    assert_eq!(
        SMALL_BAYES_NOBG_MLMAP[..10],
        *b"MLMP\x02\x03\x04\x02\x04\x03"
    );
    // The head as decoded: the rows, axes and terms that were written.
    let t = small_bayes();
    let head = t.bayes_head().unwrap();
    assert_eq!(head.all_rows(), [40, 20, 20, 20]);
    assert!(head.has_background());
    assert!(!small_bayes_nobg().bayes_head().unwrap().has_background());
    assert_eq!(
        (head.bins(), head.lambda(), head.categories()),
        (4, 0.01, 4)
    );
    assert_eq!(
        (head.axis(1).unwrap().lo(), head.axis(1).unwrap().hi()),
        (-2.0, 2.0)
    );
    assert_eq!(head.axis(0).unwrap().edge(1), -2.0);
    let terms_3_2: Vec<f32> = (0..4).map(|b| head.term(3, 2, b).unwrap()).collect();
    assert_eq!(
        terms_3_2,
        &RawTable::small_bayes().bayes.unwrap().terms[44..48]
    );
    assert_eq!(head.term(1, 0, 1).unwrap(), log_term(0.5, 0.01));
    assert_eq!(head.term(4, 0, 0), None);
    assert!((head.log_prior(0).unwrap() - 0.4f32.ln()).abs() < 1e-6);
    // Built from parts on the host: the same bytes.
    #[cfg(feature = "std")]
    {
        use mlmap::host::{BayesSpec, DynTable};
        let raw = RawTable::small_bayes().bayes.unwrap();
        let classes = small_specs()
            .into_iter()
            .map(|c| mlmap::ClassSpec {
                ml_freqs: c.ml_freqs.to_vec(),
                map_freqs: c.map_freqs.to_vec(),
                name: c.name,
                rows: c.rows,
                mean: c.mean,
                variance: c.variance,
                ml_range: c.ml_range,
                map_range: c.map_range,
            })
            .collect();
        let spec = BayesSpec {
            lambda: raw.lambda,
            terms: raw.stored_terms(),
            rows: raw.rows,
            ranges: raw.ranges,
            objectness: None,
        };
        let d = DynTable::new(small_settings(UpperTail::Zero), classes)
            .unwrap()
            .with_bayes(spec)
            .unwrap();
        assert_eq!(d.to_vec().unwrap(), SMALL_BAYES_MLMAP);
    }
}

/// A table without a Bayes head is written as version 1, with one as version 2; a
/// version-1 file still decodes, to a table without the head.
#[test]
fn v1_files_still_decode_without_a_bayes_head() {
    let v1 = include_bytes!("golden/train_linspace.mlmap");
    assert_eq!(v1[4], 1);
    let t = Table::<3, 22, 17>::from_bytes(v1).unwrap();
    assert!(t.bayes_head().is_none());
    assert_eq!(encode(&t), v1);
    assert_eq!(SMALL_MLMAP[4], 1);
    assert!(small().bayes_head().is_none());
    // The shipped table is that fit plus a Bayes head: the ML and MAP heads agree.
    let s = shipped();
    for i in 0..3 {
        assert_eq!(s.spec(i), t.spec(i));
    }
    #[cfg(feature = "std")]
    {
        let d = mlmap::host::DynTable::from_bytes(v1).unwrap();
        assert!(d.bayes_head().is_none());
        assert_eq!(d.to_vec().unwrap(), v1);
        // Dropping the head of the shipped table gives the version-1 file back.
        let without = mlmap::host::DynTable::from_bytes(SHIPPED_MLMAP)
            .unwrap()
            .without_bayes();
        assert_eq!(without.to_vec().unwrap(), v1);
    }
}

#[test]
fn bayes_shape_mismatch_both_ways() {
    use DecodeError::BayesShapeMismatch;
    // A version-2 file into a type without a Bayes head, and the reverse.
    assert_eq!(
        Table::<3, 22, 17>::from_bytes(SHIPPED_MLMAP),
        Err(BayesShapeMismatch {
            expected: (0, 0),
            found: (22, 4)
        })
    );
    assert_eq!(
        Small::from_bytes(SMALL_BAYES_MLMAP),
        Err(BayesShapeMismatch {
            expected: (0, 0),
            found: (4, 4)
        })
    );
    assert_eq!(
        SmallBayes::from_bytes(SMALL_MLMAP),
        Err(BayesShapeMismatch {
            expected: (4, 4),
            found: (0, 0)
        })
    );
    assert_eq!(
        Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("golden/train_linspace.mlmap")),
        Err(BayesShapeMismatch {
            expected: (22, 4),
            found: (0, 0)
        })
    );
    // Other categories or bins.
    assert_eq!(
        SmallBayesNoBg::from_bytes(SMALL_BAYES_MLMAP),
        Err(BayesShapeMismatch {
            expected: (4, 3),
            found: (4, 4)
        })
    );
    assert_eq!(
        SmallBayes::from_bytes(SMALL_BAYES_NOBG_MLMAP),
        Err(BayesShapeMismatch {
            expected: (4, 4),
            found: (4, 3)
        })
    );
    assert_eq!(
        Table::<3, 4, 2, 5, 4>::from_bytes(SMALL_BAYES_MLMAP),
        Err(BayesShapeMismatch {
            expected: (5, 4),
            found: (4, 4)
        })
    );
    // The ML / MAP shape is checked first.
    assert_eq!(
        Table::<3, 4, 3, 4, 4>::from_bytes(SMALL_BAYES_MLMAP),
        Err(DecodeError::ShapeMismatch {
            expected: (3, 4, 3),
            found: (3, 4, 2)
        })
    );
}

#[test]
fn v2_header_without_a_bayes_head_is_refused() {
    for shape in [(0, 4), (4, 0), (0, 0)] {
        let mut raw = RawTable::small_bayes();
        raw.bayes_shape = Some(shape);
        let bytes = raw.encode();
        assert_eq!(
            Small::from_bytes(&bytes),
            Err(DecodeError::Malformed),
            "{shape:?}"
        );
        assert_eq!(
            SmallBayes::from_bytes(&bytes),
            Err(DecodeError::Malformed),
            "{shape:?}"
        );
        #[cfg(feature = "std")]
        assert_eq!(
            mlmap::host::DynTable::from_bytes(&bytes),
            Err(DecodeError::Malformed),
            "{shape:?}"
        );
        // Even without a Bayes section after the classes.
        raw.bayes = None;
        assert_eq!(
            Small::from_bytes(&raw.encode()),
            Err(DecodeError::Malformed)
        );
    }
    // A version-2 header whose body has no Bayes section: the body ends too early.
    let mut raw = RawTable::small_bayes();
    raw.bayes = None;
    assert_eq!(
        SmallBayes::from_bytes(&raw.encode()),
        Err(DecodeError::Malformed)
    );
    // A version-1 header followed by a Bayes section: bytes left over.
    let mut raw = RawTable::small_bayes();
    raw.version = 1;
    raw.bayes_shape = None;
    assert_eq!(
        Small::from_bytes(&raw.encode()),
        Err(DecodeError::Malformed)
    );
}

/// Breaks one thing of the small Bayes table (keeping the CRC right) and expects `want`
/// from the fixed-size and the host decoder.
fn assert_bayes_broken(what: &str, change: impl FnOnce(&mut RawTable), want: DecodeError) {
    let mut raw = RawTable::small_bayes();
    change(&mut raw);
    let bytes = raw.encode();
    assert_eq!(SmallBayes::from_bytes(&bytes), Err(want), "{what}");
    #[cfg(feature = "std")]
    assert_eq!(
        mlmap::host::DynTable::from_bytes(&bytes).err(),
        Some(want),
        "DynTable: {what}"
    );
}

/// The small Bayes head (with background) with every term recomputed for `lambda`.
fn small_bayes_with_lambda(lambda: f32) -> RawBayes {
    RawBayes::small(&[40, 20, 20, 20], lambda)
}

fn bayes(raw: &mut RawTable) -> &mut RawBayes {
    raw.bayes.as_mut().expect("a Bayes section")
}

#[test]
fn each_broken_bayes_invariant_has_its_error() {
    use DecodeError::Invalid;
    use TableError::*;
    let head = Head::Bayes;
    // Lambda: in (0, 1].
    for lambda in [
        0.0,
        -0.0,
        -1e-3,
        f32::NAN,
        f32::INFINITY,
        MAX_LAMBDA_BAYES.next_up(),
        2.0,
        MAX_LAMBDA,
    ] {
        assert_bayes_broken(
            &format!("Bayes lambda {lambda}"),
            |r| bayes(r).lambda = lambda,
            Invalid(Lambda { head }),
        );
    }
    // The message names the Bayes head's own limit.
    assert_eq!(Lambda { head }.to_string(), "Bayes lambda is not in (0, 1]");
    assert_eq!(
        Lambda { head: Head::Ml }.to_string(),
        "ML lambda is not in (0, 1000000]"
    );
    // Every category needs rows, and the rows must not overflow.
    for c in 0..4u16 {
        assert_bayes_broken(
            &format!("no rows in category {c}"),
            |r| bayes(r).rows[usize::from(c)] = 0,
            Invalid(CategoryRows { class: c }),
        );
    }
    assert_bayes_broken(
        "rows overflowing u64",
        |r| bayes(r).rows = vec![u64::MAX, 1, 1, 1],
        Invalid(CategoryRows { class: 1 }),
    );
    // Sequences shorter than the header announces: the head's shape is wrong.
    assert_bayes_broken(
        "3 rows for 4 categories",
        |r| {
            bayes(r).rows.pop();
        },
        Invalid(BayesShape),
    );
    assert_bayes_broken(
        "2 axes for 3 logits",
        |r| {
            bayes(r).ranges.pop();
        },
        Invalid(BayesShape),
    );
    assert_bayes_broken(
        "47 terms for 4 x 3 x 4",
        |r| {
            bayes(r).terms.pop();
        },
        Invalid(BayesShape),
    );
    assert_bayes_broken(
        "the terms of 3 categories for 4",
        |r| bayes(r).terms.truncate(36),
        Invalid(BayesShape),
    );
    // Longer than announced: the decoder has nowhere to put them.
    assert_bayes_broken(
        "5 rows for 4 categories",
        |r| bayes(r).rows.push(20),
        DecodeError::Malformed,
    );
    assert_bayes_broken(
        "4 axes for 3 logits",
        |r| bayes(r).ranges.push((0.0, 1.0)),
        DecodeError::Malformed,
    );
    assert_bayes_broken(
        "49 terms",
        |r| bayes(r).terms.push(-1.0),
        DecodeError::Malformed,
    );
    // Edges of each logit's axis.
    let bad_edges: [(f32, f32); 7] = [
        (1.0, 1.0),
        (2.0, 1.0),
        (f32::NAN, 1.0),
        (0.0, f32::NAN),
        (f32::NEG_INFINITY, 1.0),
        (0.0, f32::INFINITY),
        (1e6, 1e6f32.next_up()),
    ];
    for class in 0..3u16 {
        for (lo, hi) in bad_edges {
            assert_bayes_broken(
                &format!("axis {class}: {lo} {hi}"),
                |r| bayes(r).ranges[usize::from(class)] = (lo, hi),
                Invalid(Edges { head, class }),
            );
        }
    }
    // Terms that are not ln(h + lambda) of frequencies h >= 0 summing to 1.
    let lambda = 0.01f32;
    let not_frequencies: [(&str, [f32; 4]); 9] = [
        (
            "frequencies summing to 2",
            [0.5f64; 4].map(|h| log_term(h, lambda)),
        ),
        (
            "frequencies summing to 0.9",
            [0.1, 0.2, 0.3, 0.3].map(|h| log_term(h, lambda)),
        ),
        (
            "frequencies summing to 1.0005",
            [0.1, 0.2, 0.3, 0.4005].map(|h| log_term(h, lambda)),
        ),
        (
            "no frequency at all",
            [0.0f64; 4].map(|h| log_term(h, lambda)),
        ),
        (
            "a negative frequency",
            [
                log_term(0.5, lambda),
                log_term(0.5, lambda),
                lambda.ln() - 1.0,
                lambda.ln(),
            ],
        ),
        ("a NaN term", [f32::NAN, 0.0, 0.0, 0.0]),
        (
            "a +inf term",
            [f32::INFINITY, lambda.ln(), lambda.ln(), lambda.ln()],
        ),
        (
            "a -inf term",
            [f32::NEG_INFINITY, 0.0, lambda.ln(), lambda.ln()],
        ),
        (
            "terms of another lambda",
            [0.1, 0.2, 0.3, 0.4].map(|h| log_term(h, 0.1)),
        ),
    ];
    for c in 0..4u16 {
        for j in [0usize, 2] {
            for (what, terms) in not_frequencies {
                assert_bayes_broken(
                    &format!("category {c}, logit {j}: {what}"),
                    |r| {
                        let start = (usize::from(c) * 3 + j) * 4;
                        bayes(r).terms[start..start + 4].copy_from_slice(&terms);
                    },
                    Invalid(Frequencies { head, class: c }),
                );
            }
        }
    }
    // The limits themselves are valid: the cases above are not refused for another
    // reason.
    let mut raw = RawTable::small_bayes();
    raw.bayes = Some(small_bayes_with_lambda(MAX_LAMBDA_BAYES));
    assert!(SmallBayes::from_bytes(&raw.encode()).is_ok());
    raw.bayes = Some(small_bayes_with_lambda(1e-30));
    assert!(SmallBayes::from_bytes(&raw.encode()).is_ok());
    let mut raw = RawTable::small_bayes();
    bayes(&mut raw).set_freqs(1, 2, [0.1, 0.2, 0.3, 0.40009]);
    bayes(&mut raw).rows = vec![1, 1, 1, u64::MAX - 3];
    assert!(SmallBayes::from_bytes(&raw.encode()).is_ok());
}

/// Categories other than K or K + 1 cannot even be named by a fixed-size table type
/// (a compile-time error); the host decoder refuses them.
#[cfg(feature = "std")]
#[test]
fn bayes_categories_other_than_k_or_k_plus_1_are_refused() {
    use mlmap::host::DynTable;
    for categories in [1usize, 2, 5, 6] {
        let rows = vec![10u64; categories];
        let mut b = RawBayes::small(&[10, 10, 10, 10], 0.01);
        let terms: Vec<f32> = b
            .terms
            .iter()
            .copied()
            .cycle()
            .take(categories * 12)
            .collect();
        b.rows = rows;
        b.terms = terms;
        let raw = RawTable::small_with(b);
        assert_eq!(raw.bayes_shape, Some((4, categories as u64)));
        assert_eq!(
            DynTable::from_bytes(&raw.encode()),
            Err(DecodeError::Invalid(TableError::BayesShape)),
            "{categories} categories"
        );
    }
}

#[cfg(feature = "std")]
#[test]
fn max_encoded_len_bounds_a_worst_case_bayes_head() {
    use mlmap::host::{BayesSpec, DynTable};
    fn run<const BB: usize, const C: usize>() {
        let t = worst_case::<3, 22, 17>();
        let d = DynTable::from_table(&t);
        let terms = (0..C * 3)
            .flat_map(|_| (0..BB).map(|_| log_term(1.0 / BB as f64, 1e-3)))
            .collect();
        let spec = BayesSpec {
            lambda: 1e-3,
            rows: vec![u64::MAX / C as u64; C],
            ranges: vec![(-3.0e30, 3.0e30); 3],
            terms,
            objectness: None,
        };
        let worst = d.with_bayes(spec).unwrap().with_open(1e-6, 1e30).unwrap();
        let bytes = worst.to_vec().unwrap();
        let max = Table::<3, 22, 17, BB, C>::MAX_ENCODED_LEN;
        assert!(bytes.len() <= max, "{} > {max}", bytes.len());
        // The header's varints and the row counts (9, not 10 bytes) are all the slack.
        assert!(
            max - bytes.len() <= 16 + C,
            "max {max}, worst case {}",
            bytes.len()
        );
        let t = Table::<3, 22, 17, BB, C>::from_bytes(&bytes).unwrap();
        assert_eq!(encode(&t), bytes);
    }
    run::<22, 4>();
    run::<22, 3>();
    run::<1, 3>();
    run::<200, 4>(); // two-byte Bayes bins
}

/// A malformed body is located: the part being read when the bytes stop following the
/// format, for the C API's error details (`mlmap::locate_malformed`).
#[test]
fn malformed_bodies_are_located() {
    use mlmap::{locate_malformed, BodyPart};
    let at = |raw: RawTable| {
        let bytes = raw.encode();
        // Every case is one the decoder calls malformed.
        #[cfg(feature = "std")]
        assert_eq!(
            mlmap::host::DynTable::from_bytes(&bytes).err(),
            Some(DecodeError::Malformed)
        );
        locate_malformed(&bytes)
    };
    // Well-formed bytes, and bytes that fail an earlier check, have no such part.
    assert_eq!(locate_malformed(SMALL_MLMAP), None);
    assert_eq!(locate_malformed(&SMALL_MLMAP[..20]), None);
    assert_eq!(locate_malformed(b"not a table at all"), None);
    let with = |change: &dyn Fn(&mut RawTable)| {
        let mut raw = RawTable::small();
        change(&mut raw);
        at(raw)
    };
    assert_eq!(with(&|r| r.trailing = vec![0]), Some(BodyPart::Trailing));
    assert_eq!(
        with(&|r| r.trailing = vec![1, 2, 3]),
        Some(BodyPart::Trailing)
    );
    assert_eq!(with(&|r| r.edge_mode = 2), Some(BodyPart::Settings));
    assert_eq!(with(&|r| r.upper_tail = 255), Some(BodyPart::Settings));
    for c in 0..3 {
        assert_eq!(
            with(&|r| r.classes[c].name = vec![0xff, 0xfe]),
            Some(BodyPart::Class { index: c as u16 }),
            "class {c}"
        );
    }
    // More classes announced in the body than in the header: a record too many.
    assert_eq!(
        with(&|r| r.class_count = 9),
        Some(BodyPart::Class { index: 3 })
    );
    // A Bayes section with a row count more than its categories.
    let mut raw = RawTable::small_bayes();
    if let Some(b) = raw.bayes.as_mut() {
        b.rows.push(5);
    }
    assert_eq!(at(raw), Some(BodyPart::Bayes));
    // A class with one ML frequency more than the header's bins.
    assert_eq!(
        with(&|r| r.classes[1].ml_freqs.push(0.0)),
        Some(BodyPart::Class { index: 1 })
    );
    // Bytes after a Bayes section.
    let mut raw = RawTable::small_bayes();
    raw.trailing = vec![7];
    assert_eq!(at(raw), Some(BodyPart::Trailing));
}
