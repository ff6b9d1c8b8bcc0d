//! One error per broken invariant, the name rule of old and new tables, other category
//! counts, and malformed bodies located.

use super::*;

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
