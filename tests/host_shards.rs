//! `mlmap::host::fit`'s mergeable statistics: shards merged in any order and grouping
//! (also through their bytes) give the table of one fit over all rows; the exact sums
//! against a big-integer oracle; the versioned bytes refuse what they must; in-memory
//! rows (`Loaded`) fit like files.

use std::path::{Path, PathBuf};

use mlmap::host::data::Loaded;
use mlmap::host::dataset::{DataErrorKind, DataSource, Label, Row};
use mlmap::host::fit::{
    finish, fit, BayesParams, ClassMoments, FitCounts, FitEdges, FitError, FitParams, FitStats,
    TrainingSet, STATS_FORMAT_VERSION,
};
use mlmap::{EdgeMode, UpperTail};
use num_bigint::BigInt;
use proptest::prelude::*;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn train() -> DataSource {
    DataSource::open(&repo("examples/data/train.csv")).unwrap()
}

/// Rows in memory: classes `c0..c{k-1}`, one `(label, logits)` per row.
fn loaded(k: usize, rows: &[(Label, Vec<f64>)]) -> Loaded {
    Loaded {
        classes: (0..k).map(|c| format!("c{c}")).collect(),
        labels: rows.iter().map(|r| r.0).collect(),
        objectness: vec![1.0; rows.len()],
        logits: rows.iter().flat_map(|r| r.1.iter().copied()).collect(),
        locations: Vec::new(),
        has_labels: true,
        first_missing_label: None,
    }
}

fn row(i: usize, (label, logits): &(Label, Vec<f64>)) -> Row<'_> {
    Row {
        index: i as u64,
        line: None,
        id: None,
        label: *label,
        objectness: 1.0,
        logits,
    }
}

/// Merges `parts` in the order `order`, grouped as a left-leaning fold when `tree` is
/// false, else pairwise (a tree), each merged value passed through its bytes.
fn merge_all<T: Clone>(
    mut parts: Vec<T>,
    order: &[usize],
    tree: bool,
    merge: impl Fn(&mut T, &T),
    through_bytes: impl Fn(&T) -> T,
) -> T {
    let mut ordered: Vec<T> = order.iter().map(|&i| parts[i].clone()).collect();
    parts.clear();
    if tree {
        while ordered.len() > 1 {
            let mut next = Vec::new();
            for pair in ordered.chunks(2) {
                let mut a = through_bytes(&pair[0]);
                if let Some(b) = pair.get(1) {
                    merge(&mut a, b);
                }
                next.push(a);
            }
            ordered = next;
        }
        ordered.pop().unwrap()
    } else {
        let mut acc = ordered.remove(0);
        for p in &ordered {
            merge(&mut acc, &through_bytes(p));
        }
        acc
    }
}

/// A labelled row: a class, background or missing label, and K logits of mixed scales
/// (sums in f64 of such values depend on their order).
fn rows_strategy() -> impl Strategy<Value = (usize, Vec<(Label, Vec<f64>)>)> {
    (2usize..5).prop_flat_map(|k| {
        let logit = prop_oneof![
            -8.0f64..8.0,
            (-1.0f64..1.0).prop_map(|x| 1e7 + x),
            (-1.0f64..1.0).prop_map(|x| x * 1e-9),
        ];
        let label = prop_oneof![
            6 => (0..k).prop_map(Label::Class),
            1 => Just(Label::Background),
            1 => Just(Label::Missing),
        ];
        let one = (label, proptest::collection::vec(logit, k));
        (Just(k), proptest::collection::vec(one, 0..120)).prop_map(|(k, mut rows)| {
            // Every class gets at least one row.
            for c in 0..k {
                rows.push((
                    Label::Class(c),
                    (0..k).map(|j| (c * k + j) as f64 * 0.37).collect(),
                ));
            }
            (k, rows)
        })
    })
}

fn params_strategy() -> impl Strategy<Value = FitParams> {
    (
        1usize..30,
        1usize..30,
        prop::bool::ANY,
        prop::bool::ANY,
        prop::option::of(1usize..30),
    )
        .prop_map(|(bins_ml, bins_map, matlab, clamp, bayes)| FitParams {
            bins_ml,
            bins_map,
            edges: if matlab {
                EdgeMode::Matlab
            } else {
                EdgeMode::Linspace
            },
            upper_tail: if clamp {
                UpperTail::Clamp
            } else {
                UpperTail::Zero
            },
            bayes: bayes.map(|bins| BayesParams {
                bins,
                lambda: 0.01,
                objectness: false,
            }),
            ..FitParams::default()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn shards_merged_in_any_order_and_grouping_give_the_bytes_of_one_fit(
        (k, rows) in rows_strategy(),
        params in params_strategy(),
        cuts in proptest::collection::vec(any::<prop::sample::Index>(), 0..6),
        shuffle_a in any::<u64>(),
        shuffle_b in any::<u64>(),
        tree_a in prop::bool::ANY,
        tree_b in prop::bool::ANY,
    ) {
        let all = loaded(k, &rows);
        let whole = fit(&all, &params);
        // Shards: the rows cut at random points (empty shards included).
        let mut bounds: Vec<usize> = cuts.iter().map(|i| i.index(rows.len() + 1)).collect();
        bounds.push(0);
        bounds.push(rows.len());
        bounds.sort_unstable();
        let shards: Vec<&[(Label, Vec<f64>)]> =
            bounds.windows(2).map(|w| &rows[w[0]..w[1]]).collect();
        let order = |seed: u64| {
            let mut o: Vec<usize> = (0..shards.len()).collect();
            let mut s = seed | 1;
            for i in (1..o.len()).rev() {
                s ^= s << 13; s ^= s >> 7; s ^= s << 17;
                o.swap(i, (s % (i as u64 + 1)) as usize);
            }
            o
        };
        let classes = all.classes.clone();
        let stats: Vec<FitStats> = shards
            .iter()
            .map(|sh| {
                let mut s = FitStats::new(&classes);
                sh.iter().enumerate().for_each(|(i, r)| s.push(&row(i, r)));
                s
            })
            .collect();
        let merged = merge_all(
            stats,
            &order(shuffle_a),
            tree_a,
            |a, b| a.merge(b).unwrap(),
            |s| FitStats::from_bytes(&s.to_bytes()).unwrap(),
        );
        // The exact state of the merge is that of one pass.
        let mut one = FitStats::new(&classes);
        rows.iter().enumerate().for_each(|(i, r)| one.push(&row(i, r)));
        prop_assert_eq!(&merged, &one);
        prop_assert_eq!(merged.to_bytes(), one.to_bytes());

        let edges = match (merged.edges(&params), &whole) {
            (Ok(e), Ok(_)) => e,
            (Err(a), Err(b)) => {
                prop_assert_eq!(a.to_string(), b.to_string());
                return Ok(());
            }
            (a, b) => return Err(TestCaseError::fail(format!("{a:?} vs {b:?}"))),
        };
        let edges = FitEdges::from_bytes(&edges.to_bytes()).unwrap();
        let counts: Vec<FitCounts> = shards
            .iter()
            .map(|sh| {
                let mut c = FitCounts::new(&edges);
                for (i, r) in sh.iter().enumerate() {
                    assert!(c.push(&row(i, r)));
                }
                c
            })
            .collect();
        let counts = merge_all(
            counts,
            &order(shuffle_b),
            tree_b,
            |a, b| a.merge(b).unwrap(),
            |c| FitCounts::from_bytes(&c.to_bytes()).unwrap(),
        );
        let table = finish(&merged, &counts).map(|t| t.to_vec().unwrap());
        let whole = whole.map(|t| t.to_vec().unwrap());
        prop_assert_eq!(table, whole);
    }

    #[test]
    fn mean_and_variance_are_the_exact_values_correctly_rounded(
        values in proptest::collection::vec(
            prop_oneof![
                -1e6f64..1e6,
                (-1.0f64..1.0).prop_map(|x| 1e15 + x),
                (-1e-3f64..1e-3).prop_map(|x| x * 1e-200),
                any::<f64>().prop_filter("finite and not too large", |x| x.is_finite() && x.abs() < 1e300),
            ],
            1..60,
        ),
    ) {
        let mut m = ClassMoments::new("x");
        values.iter().for_each(|&x| m.push(x));
        // The oracle: every value as an integer multiple of 2^-1074, by f64 bits.
        let exact = |x: f64| -> BigInt {
            let bits = x.to_bits();
            let e = ((bits >> 52) & 0x7ff) as u32;
            let frac = bits & ((1 << 52) - 1);
            let (m, shift) = if e == 0 { (frac, 0) } else { (frac | 1 << 52, e - 1) };
            let v = BigInt::from(m) << shift;
            if x.is_sign_negative() { -v } else { v }
        };
        let n = values.len() as u64;
        let s1: BigInt = values.iter().map(|&x| exact(x)).sum();
        let s2: BigInt = values.iter().map(|&x| exact(x) * exact(x)).sum();
        // mean = s1 / n (units 2^-1074); check |s1 - n c| <= n ulp(c) / 2 exactly.
        let within_half_ulp = |num: &BigInt, den: &BigInt, units: u32, c: f64| -> bool {
            // c and its ulp as integers in units of 2^-units (c is finite here).
            let c_units = |v: f64| -> BigInt {
                let sc = exact(v); // units 2^-1074
                if units >= 1074 { sc << (units - 1074) } else { sc >> (1074 - units) }
            };
            let ulp = c_units(f64::from_bits(c.abs().to_bits() + 1)) - c_units(c.abs());
            let diff = num - den * c_units(c);
            let diff = if diff < BigInt::from(0) { -diff } else { diff };
            BigInt::from(2) * diff <= den * ulp
        };
        prop_assert!(within_half_ulp(&s1, &BigInt::from(n), 1074, m.mean()), "mean {}", m.mean());
        if n >= 2 {
            // var = (n s2 - s1^2) / (n (n-1)) in units 2^-2148.
            let num = BigInt::from(n) * &s2 - &s1 * &s1;
            let den = BigInt::from(n) * BigInt::from(n - 1);
            let v = m.sample_variance();
            prop_assume!(v > 1e-300 && v < 1e300);
            prop_assert!(within_half_ulp(&num, &den, 2148, v), "variance {v}");
        }
    }
}

#[test]
fn sharded_fit_of_the_training_data_equals_fit_and_in_memory_fits() {
    let src = train();
    let want = fit(&src, &FitParams::default()).unwrap().to_vec().unwrap();
    // The same rows in memory: fit, TrainingSet and the sharded path agree.
    let mem = Loaded::read(&repo("examples/data/train.csv")).unwrap();
    assert_eq!(
        fit(&mem, &FitParams::default()).unwrap().to_vec().unwrap(),
        want
    );
    let set = TrainingSet::read(&mem).unwrap();
    assert_eq!(
        set.fit(&FitParams::default()).unwrap().to_vec().unwrap(),
        want
    );
    assert_eq!(set.path(), Path::new("rows"));
    // Three shards by row index modulo 3.
    let params = FitParams::default();
    let mut shards = vec![FitStats::new(src.classes()).with_params(params).unwrap(); 3];
    src.for_each_row(|r| {
        shards[r.index as usize % 3].push(&r);
        Ok::<(), FitError>(())
    })
    .unwrap();
    let mut stats = shards[2].clone();
    stats.merge(&shards[0]).unwrap();
    stats.merge(&shards[1]).unwrap();
    let edges = stats.edges(&params).unwrap();
    let mut counts = vec![FitCounts::new(&edges); 3];
    src.for_each_row(|r| {
        assert!(counts[r.index as usize % 3].push(&r));
        Ok::<(), FitError>(())
    })
    .unwrap();
    let mut c = counts[1].clone();
    c.merge(&counts[2]).unwrap();
    c.merge(&counts[0]).unwrap();
    assert_eq!(finish(&stats, &c).unwrap().to_vec().unwrap(), want);
    // Counts of two shards only cover other rows.
    let mut partial = counts[0].clone();
    partial.merge(&counts[1]).unwrap();
    assert!(matches!(
        finish(&stats, &partial),
        Err(FitError::RowsDiffer { .. })
    ));
    let msg = finish(&stats, &partial).unwrap_err().to_string();
    assert!(
        msg.contains("the shards of pass (b) are not those of pass (a)"),
        "{msg}"
    );
}

/// Statistics of three rows of classes `a`, `b`.
fn small_stats() -> FitStats {
    let rows = [
        (Label::Class(0), vec![1.0, -2.0]),
        (Label::Class(1), vec![0.5, 3.25]),
        (Label::Background, vec![-1.0, 0.0]),
    ];
    let mut s = FitStats::new(&["a", "b"]);
    rows.iter()
        .enumerate()
        .for_each(|(i, r)| s.push(&row(i, r)));
    s
}

#[test]
fn merging_statistics_of_other_classes_or_settings_is_refused() {
    let mut s = small_stats();
    let other = FitStats::new(&["a", "c"]);
    let e = s.merge(&other).unwrap_err();
    assert!(matches!(e, FitError::ClassesDiffer { .. }));
    assert!(e.to_string().contains("[a, b]") && e.to_string().contains("[a, c]"));
    assert_eq!(s, small_stats(), "nothing changed");

    let p = FitParams::default();
    let q = FitParams { bins_ml: 5, ..p };
    let mut a = small_stats().with_params(p).unwrap();
    let b = small_stats().with_params(q).unwrap();
    assert_eq!(a.merge(&b), Err(FitError::ParamsDiffer));
    assert_eq!(a.merge(&small_stats()), Err(FitError::ParamsDiffer));
    assert_eq!(a.edges(&q), Err(FitError::ParamsDiffer));
    assert!(a.edges(&p).is_ok());
    assert!(matches!(
        small_stats().with_params(FitParams { bins_ml: 0, ..p }),
        Err(FitError::Param {
            name: "bins_ml",
            ..
        })
    ));
}

#[test]
fn counts_over_other_edges_are_refused() {
    let s = small_stats();
    let e22 = s.edges(&FitParams::default()).unwrap();
    let e5 = s
        .edges(&FitParams {
            bins_map: 5,
            ..FitParams::default()
        })
        .unwrap();
    let mut c = FitCounts::new(&e22);
    assert_eq!(c.merge(&FitCounts::new(&e5)), Err(FitError::EdgesDiffer));
    // Edges of other statistics: the counts do not belong to these statistics.
    let mut wider = small_stats();
    wider.push(&row(9, &(Label::Class(0), vec![7.0, 7.0])));
    let foreign = FitCounts::new(&wider.edges(&FitParams::default()).unwrap());
    assert_eq!(finish(&s, &foreign).unwrap_err(), FitError::EdgesDiffer);
    // A value outside the edges is reported, so is a background row the stats lacked.
    assert!(!c.push(&row(0, &(Label::Class(0), vec![9.0, 0.0]))));
    let no_bg = {
        let mut t = FitStats::new(&["a", "b"]);
        t.push(&row(0, &(Label::Class(0), vec![1.0, 1.0])));
        t.push(&row(1, &(Label::Class(1), vec![2.0, 2.0])));
        t
    };
    let mut c = FitCounts::new(&no_bg.edges(&FitParams::default()).unwrap());
    assert!(c.push(&row(0, &(Label::Class(1), vec![1.5, 1.5]))));
    assert!(!c.push(&row(0, &(Label::Background, vec![1.5, 1.5]))));
    // Statistics with a class without rows have no edges.
    let e = FitStats::new(&["a", "b"]).edges(&FitParams::default());
    assert!(matches!(e, Err(FitError::EmptyClasses { .. })));
}

/// Replaces the format version of serialized bytes and fixes their checksum.
fn with_version(bytes: &[u8], version: u16) -> Vec<u8> {
    let mut b = bytes[..bytes.len() - 4].to_vec();
    b[8..10].copy_from_slice(&version.to_le_bytes());
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

#[test]
fn serialized_statistics_round_trip_and_bad_bytes_are_refused() {
    let s = small_stats().with_params(FitParams::default()).unwrap();
    let bytes = s.to_bytes();
    assert_eq!(&bytes[..8], b"MLMAPFST");
    assert_eq!(
        u16::from_le_bytes([bytes[8], bytes[9]]),
        STATS_FORMAT_VERSION
    );
    let back = FitStats::from_bytes(&bytes).unwrap();
    assert_eq!(back, s);
    assert_eq!(back.to_bytes(), bytes);
    for (m, n) in back.moments().iter().zip(s.moments()) {
        assert_eq!(m.min().to_bits(), n.min().to_bits());
        assert_eq!(m.mean().to_bits(), n.mean().to_bits());
    }
    let edges = s.edges(&FitParams::default()).unwrap();
    let mut counts = FitCounts::new(&edges);
    counts.push(&row(0, &(Label::Class(0), vec![1.0, -2.0])));
    let cbytes = counts.to_bytes();
    assert_eq!(FitCounts::from_bytes(&cbytes).unwrap(), counts);
    assert_eq!(FitEdges::from_bytes(&edges.to_bytes()).unwrap(), edges);

    let msg = |r: Result<FitStats, FitError>| r.unwrap_err().to_string();
    // A newer format version names itself.
    let m = msg(FitStats::from_bytes(&with_version(&bytes, 2)));
    assert!(m.contains("format version 2 is newer"), "{m}");
    // Another kind of file.
    let m = msg(FitStats::from_bytes(&cbytes));
    assert!(
        m.contains("these are pass-(b) counts, not pass-(a) statistics"),
        "{m}"
    );
    let m = FitCounts::from_bytes(&bytes).unwrap_err().to_string();
    assert!(m.contains("these are pass-(a) statistics"), "{m}");
    let m = msg(FitStats::from_bytes(b"label,a,b\n"));
    assert!(m.contains("unknown magic"), "{m}");
    // Every truncation and every flipped byte is an error, never a panic.
    for n in 0..bytes.len() {
        assert!(FitStats::from_bytes(&bytes[..n]).is_err(), "{n}");
    }
    for i in 0..bytes.len() {
        let mut b = bytes.clone();
        b[i] ^= 0x41;
        assert!(FitStats::from_bytes(&b).is_err(), "{i}");
    }
    for i in 0..cbytes.len() {
        let mut b = cbytes.clone();
        b[i] ^= 0x10;
        assert!(FitCounts::from_bytes(&b).is_err(), "{i}");
        assert!(FitCounts::from_bytes(&cbytes[..i]).is_err(), "{i}");
    }
    // Trailing bytes (with a valid checksum) are refused too.
    let mut long = bytes[..bytes.len() - 4].to_vec();
    long.push(0);
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&long);
    long.extend_from_slice(&crc.to_le_bytes());
    let m = msg(FitStats::from_bytes(&long));
    assert!(m.contains("unexpected bytes"), "{m}");
    assert!(FitError::Format {
        reason: String::new()
    }
    .is_bad_input());
}

#[test]
fn bad_rows_in_memory_are_errors_naming_the_rows() {
    let good = (Label::Class(0), vec![1.0, 2.0]);
    let mut l = loaded(2, &[good.clone(), (Label::Class(1), vec![0.0, 1.0])]);
    fit(&l, &FitParams::default()).unwrap();
    l.logits.pop();
    let e = fit(&l, &FitParams::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "rows: logits (rows x classes) holds 3 values; 4 are needed"
    );
    let l = loaded(2, &[good.clone(), (Label::Class(2), vec![0.0, 1.0])]);
    let e = fit(&l, &FitParams::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "rows: row index 1: column \"label\": label 2 is not a class index (0 to 1) or -1 (background)"
    );
    let l = loaded(2, &[good.clone(), (Label::Class(1), vec![0.0, f64::NAN])]);
    match fit(&l, &FitParams::default()).unwrap_err() {
        FitError::Data(d) => {
            assert!(matches!(d.kind(), DataErrorKind::NotFinite { .. }));
            assert_eq!(d.column(), Some("c1"));
        }
        other => panic!("{other:?}"),
    }
    let mut l = loaded(2, &[good.clone(), (Label::Class(1), vec![0.0, 1.0])]);
    l.objectness[1] = 1.5;
    assert!(fit(&l, &FitParams::default())
        .unwrap_err()
        .to_string()
        .contains(
            "row index 1: column \"objectness\": objectness \"1.5\" is not a number in [0, 1]"
        ));
    let l = loaded(2, &[good]);
    assert_eq!(
        fit(&l, &FitParams::default()).unwrap_err().to_string(),
        "rows: class \"c1\" has no training rows (rows labelled with the class); every class \
         needs at least one"
    );
}

/// Rows as arrays: K in 2..5, f32 logits of mixed scales (zeros and subnormals
/// included), integer labels (-1 background), every class with a row.
fn arrays_strategy() -> impl Strategy<Value = (usize, Vec<f32>, Vec<i64>)> {
    (2usize..5).prop_flat_map(|k| {
        let logit = prop_oneof![
            8 => -8.0f32..8.0,
            1 => (-1.0f32..1.0).prop_map(|x| 3e5 + x),
            1 => (-1.0f32..1.0).prop_map(|x| x * 1e-9),
            1 => Just(0.0f32),
            1 => (1u32..0x80_0000).prop_map(f32::from_bits),
        ];
        let one = (-1i64..k as i64, proptest::collection::vec(logit, k));
        (Just(k), proptest::collection::vec(one, 0..300)).prop_map(|(k, mut rows)| {
            for c in 0..k {
                rows.push((
                    c as i64,
                    (0..k).map(|j| (c * k + j) as f32 * 0.37).collect(),
                ));
            }
            let labels = rows.iter().map(|r| r.0).collect();
            (k, rows.into_iter().flat_map(|r| r.1).collect(), labels)
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// `push_rows` of blocks cut anywhere, f32 or f64, any label type, gives the bytes
    /// of `push` of every row (statistics, counts and the table).
    #[test]
    fn blocks_of_arrays_give_the_bytes_of_row_by_row_pushes(
        (k, logits, labels) in arrays_strategy(),
        params in params_strategy(),
        cuts in proptest::collection::vec(any::<prop::sample::Index>(), 0..6),
        wide in proptest::collection::vec(prop::bool::ANY, 7),
    ) {
        let classes: Vec<String> = (0..k).map(|c| format!("c{c}")).collect();
        let rows: Vec<(Label, Vec<f64>)> = logits
            .chunks(k)
            .zip(&labels)
            .map(|(x, &l)| {
                let label = if l < 0 { Label::Background } else { Label::Class(l as usize) };
                (label, x.iter().map(|&v| f64::from(v)).collect())
            })
            .collect();
        let mut one = FitStats::new(&classes);
        rows.iter().enumerate().for_each(|(i, r)| one.push(&row(i, r)));

        let n = labels.len();
        let mut bounds: Vec<usize> = cuts.iter().map(|i| i.index(n + 1)).collect();
        bounds.extend([0, n]);
        bounds.sort_unstable();
        let blocks: Vec<(usize, usize)> = bounds.windows(2).map(|w| (w[0], w[1])).collect();
        let widened: Vec<f64> = logits.iter().map(|&v| f64::from(v)).collect();
        let small: Vec<i8> = labels.iter().map(|&l| l as i8).collect();
        let mut stats = FitStats::new(&classes);
        for (b, &(lo, hi)) in blocks.iter().enumerate() {
            let r = if wide[b % 7] {
                stats.push_rows(&widened[lo * k..hi * k], &labels[lo..hi])
            } else {
                stats.push_rows(&logits[lo * k..hi * k], &small[lo..hi])
            };
            prop_assert!(r.is_ok());
        }
        prop_assert_eq!(stats.to_bytes(), one.to_bytes());

        let Ok(edges) = one.edges(&params) else { return Ok(()); };
        let mut want = FitCounts::new(&edges);
        for (i, r) in rows.iter().enumerate() {
            prop_assert!(want.push(&row(i, r)));
        }
        let mut counts = FitCounts::new(&edges);
        for (b, &(lo, hi)) in blocks.iter().enumerate() {
            let r = if wide[(b + 3) % 7] {
                counts.push_rows(&widened[lo * k..hi * k], &small[lo..hi])
            } else {
                counts.push_rows(&logits[lo * k..hi * k], &labels[lo..hi])
            };
            prop_assert_eq!(r, Ok(None));
        }
        prop_assert_eq!(counts.to_bytes(), want.to_bytes());
        let table = finish(&stats, &counts).map(|t| t.to_vec().unwrap());
        let whole = finish(&one, &want).map(|t| t.to_vec().unwrap());
        prop_assert_eq!(table, whole);
    }
}

/// `+0.0` and `-0.0` compare equal, so `f64::min` may keep either: the extremes follow
/// IEEE 754's total order instead (`-0.0 < +0.0`), and the statistics of rows holding
/// both zeros are the same bytes in every order of rows and of shards.
#[test]
fn signed_zeros_give_the_same_statistics_in_every_order() {
    let rows = [
        (Label::Class(0), vec![0.0, -0.0]),
        (Label::Class(0), vec![-0.0, 0.0]),
        (Label::Class(1), vec![0.0, 0.0]),
        (Label::Class(1), vec![-0.0, -0.0]),
    ];
    let stats = |order: &[usize]| {
        let mut s = FitStats::new(&["a", "b"]);
        for &i in order {
            s.push(&row(i, &rows[i]));
        }
        s
    };
    let forward = stats(&[0, 1, 2, 3]).to_bytes();
    assert_eq!(stats(&[3, 2, 1, 0]).to_bytes(), forward);
    assert_eq!(stats(&[1, 0, 3, 2]).to_bytes(), forward);
    let (mut a, b) = (stats(&[1, 3]), stats(&[0, 2]));
    a.merge(&b).unwrap();
    assert_eq!(a.to_bytes(), forward);
    // The recorded extremes are -0.0 and +0.0 (by their bits).
    let s = stats(&[2, 0, 3, 1]);
    for m in s.moments() {
        assert_eq!(m.min().to_bits(), (-0.0f64).to_bits());
        assert_eq!(m.max().to_bits(), 0.0f64.to_bits());
    }
}
