//! Format version 2, the Bayes head (DESIGN §1.6, docs/FORMAT.md): byte-exact round
//! trips, the reference encoder, shape mismatches and one error per broken invariant.

use super::*;

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
    let v1 = include_bytes!("../golden/train_linspace.mlmap");
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
        Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("../golden/train_linspace.mlmap")),
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
