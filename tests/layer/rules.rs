//! Errors, the batch API, ties, the exact `OS / K` answer out of support, the embedded
//! table and the auto traits.

use super::*;

#[test]
fn error_cases() {
    let t = shipped();
    let nan_payloads = [
        f32::NAN,
        -f32::NAN,
        f32::from_bits(0x7fc0_0001),
        f32::from_bits(0x7f80_0001), // signalling
        f32::from_bits(0xffff_ffff),
    ];
    for nan in nan_payloads {
        for class in 0..3u16 {
            let mut x = [1.0f32, -2.0, 0.5];
            x[usize::from(class)] = nan;
            let want = Err(InferError::NanLogit { class });
            assert_eq!(t.ml(&x, 0.5), want, "{x:?}");
            assert_eq!(t.map(&x, 0.5), want, "{x:?}");
            assert_eq!(t.bayes(&x, 0.5), want, "{x:?}");
            // Also with every other logit outside its axis.
            let mut far = [1e30f32; 3];
            far[usize::from(class)] = nan;
            assert_eq!(t.bayes(&far, 0.5), want, "{far:?}");
        }
        // The first NaN is reported.
        let want = Err(InferError::NanLogit { class: 1 });
        assert_eq!(t.ml(&[0.0, nan, nan], 1.0), want);
        assert_eq!(t.map(&[0.0, nan, nan], 1.0), want);
        assert_eq!(t.bayes(&[0.0, nan, nan], 1.0), want);
    }
    let bad_objectness = [
        f32::NAN,
        -f32::NAN,
        -0.1,
        1.1,
        1.0f32.next_up(),
        -f32::from_bits(1),
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
    ];
    for os in bad_objectness {
        assert_eq!(
            t.ml(&[1.0, -2.0, 0.5], os),
            Err(InferError::Objectness),
            "{os}"
        );
        assert_eq!(
            t.map(&[1.0, -2.0, 0.5], os),
            Err(InferError::Objectness),
            "{os}"
        );
        assert_eq!(
            t.bayes(&[1.0, -2.0, 0.5], os),
            Err(InferError::Objectness),
            "{os}"
        );
    }
    // Both wrong: an error either way, never scores.
    assert!(t.ml(&[f32::NAN; 3], f32::NAN).is_err());
    assert!(t.map(&[f32::NAN; 3], 2.0).is_err());
    assert!(t.bayes(&[f32::NAN; 3], -1.0).is_err());
    // The edges of [0, 1] themselves are valid, -0.0 included.
    for os in [0.0, -0.0, 1.0, f32::from_bits(1), 1.0f32.next_down()] {
        assert!(t.ml(&[1.0, -2.0, 0.5], os).is_ok(), "{os}");
        assert!(t.map(&[1.0, -2.0, 0.5], os).is_ok(), "{os}");
        assert!(t.bayes(&[1.0, -2.0, 0.5], os).is_ok(), "{os}");
    }
    // A table without a Bayes head says so through the view.
    assert_eq!(
        bayes_of(&small(), &[1.0, -2.0, 0.5], 1.0),
        Err(InferError::NoBayesHead)
    );
}

#[test]
fn batch_matches_single_calls() {
    let t = shipped();
    let rows = [
        [3.0, -2.0, -1.0],
        [0.5, 0.5, f32::INFINITY],
        [-1.0, 2.0, 0.0],
    ];
    let os = [0.9, 0.0, 1.0];
    let mut ml = [SENTINEL; 3];
    let mut map = [SENTINEL; 3];
    let mut bayes = [SENTINEL; 3];
    t.ml_batch(&rows, Some(&os), &mut ml).unwrap();
    t.map_batch(&rows, Some(&os), &mut map).unwrap();
    t.bayes_batch(&rows, Some(&os), &mut bayes).unwrap();
    for r in 0..3 {
        assert_eq!(ml[r], t.ml(&rows[r], os[r]).unwrap().0, "row {r}");
        assert_eq!(map[r], t.map(&rows[r], os[r]).unwrap().0, "row {r}");
        assert_eq!(bayes[r], t.bayes(&rows[r], os[r]).unwrap().0, "row {r}");
    }
    // No objectness: 1.0 for every row.
    t.ml_batch(&rows, None, &mut ml).unwrap();
    t.map_batch(&rows, None, &mut map).unwrap();
    for r in 0..3 {
        assert_eq!(ml[r], t.ml(&rows[r], 1.0).unwrap().0, "row {r}");
        assert_eq!(map[r], t.map(&rows[r], 1.0).unwrap().0, "row {r}");
    }
    // Empty batches are fine.
    t.ml_batch(&[], None, &mut []).unwrap();
    t.map_batch(&[], Some(&[]), &mut []).unwrap();
}

#[test]
fn batch_row_error_writes_earlier_rows_only() {
    let t = shipped();
    let rows = batch_rows();
    type Run = fn(&Shipped, &[[f32; 3]], Option<&[f32]>, &mut [[f32; 3]]) -> Result<(), BatchError>;
    let heads: [(&str, Run); 3] = [
        ("ML", |t, x, o, out| t.ml_batch(x, o, out)),
        ("MAP", |t, x, o, out| t.map_batch(x, o, out)),
        ("Bayes", |t, x, o, out| t.bayes_batch(x, o, out)),
    ];
    for (head, run) in heads {
        let mut out = [SENTINEL; 4];
        assert_eq!(
            run(&t, &rows, None, &mut out),
            Err(BatchError::Row {
                index: 2,
                error: InferError::NanLogit { class: 1 }
            }),
            "{head}"
        );
        let single = |x: &[f32; 3], os| match head {
            "ML" => t.ml(x, os).unwrap().0,
            "MAP" => t.map(x, os).unwrap().0,
            _ => t.bayes(x, os).unwrap().0,
        };
        assert_eq!(out[0], single(&rows[0], 1.0), "{head}");
        assert_eq!(out[1], single(&rows[1], 1.0), "{head}");
        assert_eq!(out[2], SENTINEL, "{head}: the bad row is untouched");
        assert_eq!(out[3], SENTINEL, "{head}: rows after it are untouched");

        // A bad objectness in row 1 of otherwise valid rows.
        let valid = [rows[0], rows[1], rows[3]];
        let mut out = [SENTINEL; 3];
        assert_eq!(
            run(&t, &valid, Some(&[0.5, 1.5, 0.5]), &mut out),
            Err(BatchError::Row {
                index: 1,
                error: InferError::Objectness
            }),
            "{head}"
        );
        assert_eq!(out[0], single(&valid[0], 0.5), "{head}");
        assert_eq!(out[1..], [SENTINEL; 2], "{head}");

        // Resuming after the bad row, as the docs suggest, scores the rest.
        let mut rest = [SENTINEL; 1];
        run(&t, &rows[3..], None, &mut rest).unwrap();
        assert_eq!(rest[0], single(&rows[3], 1.0), "{head}");
    }
}

#[test]
fn batch_length_mismatch_writes_nothing() {
    let t = shipped();
    let rows = [[3.0, -2.0, -1.0], [0.5, 0.5, 0.5]];
    let cases: [(usize, Option<&[f32]>); 4] = [
        (1, None),
        (3, None),
        (2, Some(&[1.0])),
        (2, Some(&[1.0, 1.0, 1.0])),
    ];
    for (out_len, os) in cases {
        let mut out = vec![SENTINEL; out_len];
        assert_eq!(
            t.ml_batch(&rows, os, &mut out),
            Err(BatchError::LengthMismatch)
        );
        assert_eq!(
            t.map_batch(&rows, os, &mut out),
            Err(BatchError::LengthMismatch)
        );
        assert_eq!(
            t.bayes_batch(&rows, os, &mut out),
            Err(BatchError::LengthMismatch)
        );
        assert!(out.iter().all(|r| *r == SENTINEL), "{out_len} {os:?}");
    }
    // The length check comes before any row check: a NaN row changes nothing.
    let mut out = [SENTINEL; 1];
    assert_eq!(
        t.ml_batch(&[[f32::NAN; 3], [0.0; 3]], None, &mut out),
        Err(BatchError::LengthMismatch)
    );
    assert_eq!(out, [SENTINEL]);
}

#[test]
fn argmax_takes_the_lowest_index_on_ties() {
    assert_eq!(Scores([0.2f32, 0.4, 0.4]).argmax(), 1);
    assert_eq!(Scores([0.5f32, 0.1, 0.5]).argmax(), 0);
    assert_eq!(Scores([0.1f32, 0.3, 0.3, 0.3]).argmax(), 1);
    assert_eq!(Scores([0.0f32; 5]).argmax(), 0);
    assert_eq!(Scores([-0.0f32, 0.0]).argmax(), 0, "-0 and 0 tie");
    assert_eq!(Scores([0.1f32, 0.2, 0.7]).argmax(), 2);
    assert_eq!(Scores([0.25f32, 0.25, 0.5]).confidence(), 0.5);
    // The layer's own ties: "I don't know" is a K-way tie, decided for class 0.
    let t = shipped();
    let unknown = t.ml(&[1e30, -1e30, f32::INFINITY], 0.9).unwrap();
    assert_eq!(unknown.argmax(), 0);
    // Objectness 0 makes every score 0: also class 0.
    assert_eq!(t.map(&[5.0, -2.0, -1.0], 0.0).unwrap().argmax(), 0);
    // Two classes with identical statistics and logits tie at a non-trivial value.
    let mut specs = small_specs();
    specs[2] = specs[0].clone();
    specs[2].name = "van";
    let twins = Small::from_parts(small_settings(UpperTail::Zero), specs).unwrap();
    for head in [
        twins.ml(&[2.5, -5.0, 2.5], 1.0).unwrap(),
        twins.map(&[2.5, -5.0, 2.5], 1.0).unwrap(),
    ] {
        assert!(head.0[0] > 1.0 / 3.0);
        assert_eq!(head.0[0].to_bits(), head.0[2].to_bits());
        assert_eq!(head.argmax(), 0, "{head:?}");
    }
}

/// DESIGN §1.3 invariant 2: logits outside every class's support give exactly
/// `OS / K`, bit for bit, under both heads.
#[test]
fn out_of_support_is_exactly_os_over_k() {
    let shipped = shipped();
    let (small, small_clamp) = (small(), small_clamp());
    let inf = f32::INFINITY;
    let outside_shipped: Vec<[f32; 3]> = {
        let mut v = vec![
            [inf, -inf, inf],
            [-inf; 3],
            [1e30, -1e30, 3e38],
            [f32::MAX, f32::MIN, f32::MAX],
        ];
        // Just outside each class's widest support, below and above.
        let below: [f32; 3] = std::array::from_fn(|i| {
            let lo = shipped.ml_histograms().get(i).unwrap().lo();
            lo.min(shipped.map_histograms().get(i).unwrap().lo())
                .next_down()
        });
        let above: [f32; 3] = std::array::from_fn(|i| {
            let hi = shipped.ml_histograms().get(i).unwrap().hi();
            hi.max(shipped.map_histograms().get(i).unwrap().hi())
                .next_up()
        });
        v.push(below);
        v.push(above);
        v.push([below[0], above[1], below[2]]);
        v
    };
    // Zero tail: above the last edge is outside; clamp: only below the first edge.
    let outside_small = [
        [0.0f32.next_down(), 2.0f32.next_up(), -inf],
        [-1.0, 3.0, 1.0],
        [1e30, -1e30, 50.0],
    ];
    let outside_small_clamp = [[-inf; 3], [-1.0, -3.0, -5.0], [-1e30; 3]];
    let mut checked = 0usize;
    for os in objectness_values() {
        let want = (os / 3.0).to_bits();
        let mut check = |name: &str, ml: Scores<3>, map: Scores<3>| {
            for (head, s) in [("ML", ml), ("MAP", map)] {
                for v in s.0 {
                    assert_eq!(
                        v.to_bits(),
                        want,
                        "{name} {head} OS {os}: {v} is not OS/K = {}",
                        os / 3.0
                    );
                }
            }
            checked += 1;
        };
        for x in &outside_shipped {
            check(
                "shipped",
                shipped.ml(x, os).unwrap(),
                shipped.map(x, os).unwrap(),
            );
        }
        for x in &outside_small {
            check("small", small.ml(x, os).unwrap(), small.map(x, os).unwrap());
        }
        for x in &outside_small_clamp {
            let (ml, map) = (
                small_clamp.ml(x, os).unwrap(),
                small_clamp.map(x, os).unwrap(),
            );
            check("small clamp", ml, map);
        }
    }
    assert!(checked > 10_000);
}

/// DESIGN §1.3 invariant 2 for other K: 1/2 and 1/5 are exact too.
#[test]
fn out_of_support_is_exactly_os_over_k_for_other_k() {
    let class = |name, lo: f32| mlmap::ClassSpec {
        name,
        rows: 10,
        mean: lo + 0.5,
        variance: 0.1,
        ml_range: (lo, lo + 1.0),
        ml_freqs: [1.0],
        map_range: (lo, lo + 1.0),
        map_freqs: [1.0],
    };
    let settings = small_settings(UpperTail::Zero);
    let t2: Table<2, 1, 1> =
        Table::from_parts(settings, [class("a", 0.0), class("b", 1.0)]).unwrap();
    let t5: Table<5, 1, 1> = Table::from_parts(
        settings,
        [
            class("a", 0.0),
            class("b", 1.0),
            class("c", 2.0),
            class("d", 3.0),
            class("e", 4.0),
        ],
    )
    .unwrap();
    for os in objectness_values() {
        for s in [
            t2.ml(&[9.0, -9.0], os).unwrap(),
            t2.map(&[9.0, -9.0], os).unwrap(),
        ] {
            assert_eq!(s.0.map(f32::to_bits), [(os / 2.0).to_bits(); 2], "OS {os}");
        }
        let x = [
            -1.0,
            0.0f32.next_down(),
            3.5,
            f32::NEG_INFINITY,
            5.0f32.next_up(),
        ];
        for s in [t5.ml(&x, os).unwrap(), t5.map(&x, os).unwrap()] {
            assert_eq!(s.0.map(f32::to_bits), [(os / 5.0).to_bits(); 5], "OS {os}");
        }
    }
}

#[test]
fn embedded_table_is_the_decoded_file() {
    use mlmap::embedded;
    let decoded = embedded::EmbeddedTable::from_bytes(&embedded::BYTES).unwrap();
    assert_eq!(embedded::TABLE, decoded);
    // Every derived constant agrees too, so the scores agree bit for bit.
    for x in [[5.1f32, -2.0, -1.3], [0.0, 0.0, 0.0], [-3.0, 4.0, 1.0]] {
        assert_eq!(embedded::TABLE.ml(&x, 0.93), decoded.ml(&x, 0.93));
        assert_eq!(embedded::TABLE.map(&x, 0.93), decoded.map(&x, 0.93));
        assert_eq!(
            bayes_of(&embedded::TABLE, &x, 0.93),
            bayes_of(&decoded, &x, 0.93)
        );
    }
    let shape = (embedded::K, embedded::BINS_ML, embedded::BINS_MAP);
    // The bytes are those of the file the build named.
    let source = std::fs::read(embedded::SOURCE).expect("the embedded table's source file");
    assert_eq!(embedded::BYTES[..], source[..]);
    if std::env::var_os("MLMAP_TABLE").is_none() {
        assert_eq!(shape, (3, 22, 17));
        assert_eq!(embedded::BYTES[..], crate::support::SHIPPED_MLMAP[..]);
    }
}

#[test]
fn autotraits() {
    fn has_autotraits<T: Send + Sync + Unpin>() {}
    has_autotraits::<Table<3, 22, 17, 22, 4>>();
    has_autotraits::<Table<2, 1, 1>>();
    has_autotraits::<Scores<3>>();
    has_autotraits::<mlmap::DecodeError>();
    has_autotraits::<mlmap::EncodeError>();
    has_autotraits::<mlmap::InferError>();
    has_autotraits::<mlmap::BatchError>();
    has_autotraits::<mlmap::TableError>();
    has_autotraits::<mlmap::Histogram<[f32; 4]>>();
    has_autotraits::<mlmap::Gaussian>();
    has_autotraits::<mlmap::Settings>();
    has_autotraits::<mlmap::Libm>();
    has_autotraits::<mlmap::FastMath>();
    #[cfg(feature = "micromath")]
    has_autotraits::<mlmap::Micromath>();
    #[cfg(feature = "std")]
    has_autotraits::<mlmap::host::DynTable>();
}
