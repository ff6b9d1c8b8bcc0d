//! The conformal class sets (DESIGN §8) against the numpy reference
//! (tools/conformal_ref.py): thresholds, sets, coverage and the LAC baseline; the
//! section's checks; and the properties of the sets (coverage on exchangeable rows,
//! monotone in alpha, empty exactly when every score is below its threshold).

use std::path::Path;
use std::sync::OnceLock;

use mlmap::host::conformal::{
    coverage, evaluate, fit, scores, sets, softmax_scores, with_conformal, Fitted, Lac, Rows,
};
use mlmap::host::data::Loaded;
use mlmap::host::monitor::with_monitor;
use mlmap::host::DynTable;
use mlmap::{
    conformal_section_len, section_of, table_of, write_conformal_section, ConformalError,
    ConformalSpec, Head, InferError, MonitorParams, MonitorSpec, Table, Thresholds,
    CONFORMAL_MAGIC, FAST_MATH_MAX_SCORE_ERROR,
};
use proptest::prelude::*;
use serde_json::Value;

fn root(p: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn golden() -> &'static Value {
    static G: OnceLock<Value> = OnceLock::new();
    G.get_or_init(|| {
        let text = std::fs::read_to_string(root("tests/golden/conformal/reference.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    })
}

fn default_table() -> (DynTable, Vec<u8>) {
    let bytes = std::fs::read(root("tables/default.mlmap")).unwrap();
    (DynTable::from_bytes(&bytes).unwrap(), bytes)
}

struct Data {
    loaded: Loaded,
    labels: Vec<Option<usize>>,
}

fn data(name: &str) -> &'static Data {
    static CACHE: OnceLock<std::sync::Mutex<Vec<(String, &'static Data)>>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    let mut c = cache.lock().unwrap();
    if let Some((_, d)) = c.iter().find(|(n, _)| n == name) {
        return d;
    }
    let path = root(&format!("examples/data/{name}.csv"));
    let loaded = Loaded::read(&path).unwrap();
    let labels = loaded.class_labels(&path).unwrap();
    let d: &'static Data = Box::leak(Box::new(Data { loaded, labels }));
    c.push((name.to_string(), d));
    d
}

fn head_of(name: &str) -> Head {
    match name {
        "ml" => Head::Ml,
        "map" => Head::Map,
        "bayes" => Head::Bayes,
        "open" => Head::Open,
        _ => unreachable!(),
    }
}

/// The largest difference between the layer's `f32` score and the reference's `f64` one:
/// rounding for ML and MAP, the fast `exp` bound for the Bayes and open heads.
fn tolerance(head: Head) -> f64 {
    match head {
        Head::Ml | Head::Map => 2e-6,
        Head::Bayes | Head::Open => f64::from(FAST_MATH_MAX_SCORE_ERROR) + 2e-6,
    }
}

fn head_scores(table: &DynTable, head: Head, d: &Data) -> Vec<f32> {
    scores(
        table,
        head,
        &d.loaded.logits_f32(),
        &d.loaded.objectness_f32(),
    )
    .unwrap()
}

#[test]
fn thresholds_and_sets_match_numpy() {
    let (table, bytes) = default_table();
    let (val, test, ood) = (data("val"), data("test"), data("ood"));
    for case in golden()["cases"].as_array().unwrap() {
        let head = head_of(case["head"].as_str().unwrap());
        let alpha = case["alpha"].as_f64().unwrap();
        let tol = tolerance(head);
        let f = fit(head, alpha, 3, &head_scores(&table, head, val), &val.labels);
        let rows: Vec<u32> = case["rows"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as u32)
            .collect();
        assert_eq!(f.rows, rows, "{head} {alpha}");
        for (c, want) in case["thresholds"].as_array().unwrap().iter().enumerate() {
            match want.as_f64() {
                None => assert_eq!(f.thresholds[c], f32::NEG_INFINITY),
                Some(w) => assert!(
                    (f64::from(f.thresholds[c]) - w).abs() <= tol,
                    "{head} {alpha} class {c}: {} vs {w}",
                    f.thresholds[c]
                ),
            }
        }
        let file = with_conformal(&bytes, &f).unwrap();
        let spec = ConformalSpec::from_bytes(&file, &table.view()).unwrap();
        assert_eq!((spec.head(), spec.alpha()), (head, alpha as f32));
        // The sets of the first rows, where no score is within the tolerance of its
        // threshold (there the two precisions may rightly disagree).
        for (d, key, margin) in [
            (test, "test_sets", "test_margin"),
            (ood, "ood_sets", "ood_margin"),
        ] {
            let want = case[key].as_array().unwrap();
            let margins = case[margin].as_array().unwrap();
            let s = head_scores(&table, head, d);
            let got = sets(&spec, &s[..want.len() * 3]).unwrap();
            let mut compared = 0;
            for (i, (w, m)) in want.iter().zip(margins).enumerate() {
                if m.as_f64().unwrap() <= 2.0 * tol {
                    continue;
                }
                compared += 1;
                let w: Vec<bool> = w
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|b| b.as_u64() == Some(1))
                    .collect();
                assert_eq!(
                    &got[3 * i..3 * i + 3],
                    &w[..],
                    "{head} {alpha} {key} row {i}"
                );
            }
            assert!(
                compared * 10 >= want.len() * 9,
                "{head} {alpha} {key}: {compared}"
            );
        }
    }
}

/// Coverage, set size and empty sets of every test and unseen row, and the LAC
/// baseline, against numpy: equal up to the rows within the tolerance of a threshold.
#[test]
fn evaluation_matches_numpy() {
    let (table, bytes) = default_table();
    let (val, test, ood) = (data("val"), data("test"), data("ood"));
    let rows = |d: &'static Data, unseen: bool| Rows {
        logits: &d.loaded.logits,
        objectness: &d.loaded.objectness,
        labels: if unseen {
            Box::leak(vec![None; d.labels.len()].into_boxed_slice())
        } else {
            &d.labels
        },
    };
    let close = |got: f64, want: &Value, n: f64, what: &str| {
        let want = want.as_f64().unwrap();
        // Two rows' worth: a row or two may sit within the tolerance of a threshold.
        assert!(
            (got - want).abs() <= 2.0 / n + 1e-12,
            "{what}: {got} vs {want}"
        );
    };
    for case in golden()["cases"].as_array().unwrap() {
        let head = head_of(case["head"].as_str().unwrap());
        let alpha = case["alpha"].as_f64().unwrap();
        let f = fit(head, alpha, 3, &head_scores(&table, head, val), &val.labels);
        let file = with_conformal(&bytes, &f).unwrap();
        let spec = ConformalSpec::from_bytes(&file, &table.view()).unwrap();
        let ev = evaluate(
            &table,
            &spec,
            rows(test, false),
            Some(rows(val, false)),
            Some(rows(ood, true)),
        )
        .unwrap();
        let want = &case["eval"];
        for c in 0..3 {
            let (n, cov) = ev.sets.per_class[c];
            assert_eq!(n as u64, want["rows"][c].as_u64().unwrap());
            close(cov, &want["coverage"][c], n as f64, "coverage");
        }
        close(ev.sets.mean_size, &want["mean_size"], 8000.0, "mean size");
        close(ev.sets.empty_known, &want["empty_known"], 8000.0, "empty");
        close(
            ev.sets.empty_unseen.unwrap(),
            &want["empty_unseen"],
            2000.0,
            "empty unseen",
        );
        let lac = golden()["lac"]
            .as_array()
            .unwrap()
            .iter()
            .find(|l| l["alpha"].as_f64() == Some(alpha))
            .unwrap();
        let (l, lc) = ev.lac.unwrap();
        assert_eq!(l.rows as u64, lac["rows"].as_u64().unwrap());
        assert!((l.qhat - lac["qhat"].as_f64().unwrap()).abs() < 1e-12);
        for c in 0..3 {
            close(lc.per_class[c].1, &lac["eval"]["coverage"][c], 500.0, "LAC");
        }
        close(lc.mean_size, &lac["eval"]["mean_size"], 8000.0, "LAC size");
        close(
            lc.empty_unseen.unwrap(),
            &lac["eval"]["empty_unseen"],
            2000.0,
            "LAC empty",
        );
    }
}

fn fitted(head: Head, alpha: f32, rows: Vec<u32>, thresholds: Vec<f32>) -> Fitted {
    Fitted {
        head,
        alpha,
        rows,
        thresholds,
    }
}

#[test]
fn the_section_keeps_the_table_and_the_other_sections() {
    let (table, bytes) = default_table();
    let f = fitted(
        Head::Open,
        0.1,
        vec![100, 5, 40],
        vec![0.5, f32::NEG_INFINITY, 0.2],
    );
    let params = MonitorParams {
        window: 50,
        alpha: 0.0,
        thresholds: Thresholds::NONE,
    };
    let with_both = with_conformal(&with_monitor(&bytes, &table, &params).unwrap(), &f).unwrap();
    assert_eq!(table_of(&with_both), &bytes[..]);
    assert_eq!(
        with_both.len(),
        bytes.len() + mlmap::monitor_section_len(3, 22) + conformal_section_len(3)
    );
    // Every table decoder reads the file; the monitor still reads; a monitor written
    // later keeps the conformal section.
    DynTable::from_bytes(&with_both).unwrap();
    Table::<3, 22, 17, 22, 4>::from_bytes(&with_both).unwrap();
    MonitorSpec::from_bytes(&with_both, &table.view()).unwrap();
    let again = with_monitor(&with_both, &table, &params).unwrap();
    let spec = ConformalSpec::from_bytes(&again, &table.view()).unwrap();
    assert_eq!(spec.threshold(1), Some(f32::NEG_INFINITY));
    assert_eq!(spec.calibration_rows(2), Some(40));
    // A table without the section: absent, and it decodes as before.
    assert_eq!(
        ConformalSpec::from_bytes(&bytes, &table.view()).unwrap_err(),
        ConformalError::Absent
    );
    // The section alone reads against the table by shape.
    let alone = section_of(&with_both, CONFORMAL_MAGIC).unwrap();
    ConformalSpec::from_bytes(alone, &table.view()).unwrap();
}

/// A section with one field changed and its CRC made right again.
fn resealed(section: &[u8], at: usize, bytes: &[u8]) -> Vec<u8> {
    let mut s = section.to_vec();
    s[at..at + bytes.len()].copy_from_slice(bytes);
    let n = s.len();
    let crc = crc32(&s[..n - 4]);
    s[n - 4..].copy_from_slice(&crc.to_le_bytes());
    s
}

fn crc32(bytes: &[u8]) -> u32 {
    // CRC-32 (IEEE), bit by bit: independent of the crate's table-driven one.
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[test]
fn every_check_of_the_section() {
    let (table, bytes) = default_table();
    let v = table.view();
    let f = fitted(
        Head::Map,
        0.1,
        vec![100, 5, 40],
        vec![0.5, f32::NEG_INFINITY, 0.2],
    );
    let file = with_conformal(&bytes, &f).unwrap();
    let sec = section_of(&file, CONFORMAL_MAGIC).unwrap().to_vec();
    let err = |s: &[u8]| ConformalSpec::from_bytes(s, &v).unwrap_err();
    assert_eq!(
        err(&resealed(&sec, 4, &[2])),
        ConformalError::UnsupportedVersion { found: 2 }
    );
    assert_eq!(err(&resealed(&sec, 5, &[4])), ConformalError::Malformed);
    assert_eq!(err(&resealed(&sec, 6, &[1])), ConformalError::Malformed);
    assert_eq!(err(&resealed(&sec, 10, &[1])), ConformalError::Malformed);
    assert_eq!(
        err(&resealed(&sec, 8, &4u16.to_le_bytes())),
        ConformalError::ShapeMismatch {
            expected: 3,
            found: 4
        }
    );
    for a in [0.0f32, 1.0, -0.1, f32::NAN] {
        assert_eq!(
            err(&resealed(&sec, 16, &a.to_le_bytes())),
            ConformalError::Alpha
        );
    }
    // Thresholds: NaN, above 1, -inf where the rows give a rank, finite where they
    // give none.
    for (at, t) in [
        (24, f32::NAN),
        (24, 1.5),
        (24, f32::NEG_INFINITY),
        (24, -0.1),
        (32, 0.3),
    ] {
        let class = ((at - 24) / 8) as u16;
        assert_eq!(
            err(&resealed(&sec, at, &t.to_le_bytes())),
            ConformalError::Threshold {
                class: class.max(if at == 32 { 1 } else { 0 })
            }
        );
    }
    // Rows of class 1 raised to 9: rank floor(10 * 0.1) = 1, so -inf no longer fits.
    assert_eq!(
        err(&resealed(&sec, 28, &9u32.to_le_bytes())),
        ConformalError::Threshold { class: 1 }
    );
    // A flipped byte: the CRC; the section after another table: TableMismatch.
    let mut bad = file.clone();
    let n = bad.len();
    bad[n - 12] ^= 1;
    assert_eq!(
        ConformalSpec::from_bytes(&bad, &v).unwrap_err(),
        ConformalError::Corrupted
    );
    let mut other = bytes.clone();
    other.extend_from_slice(&resealed(&sec, 12, &0u32.to_le_bytes()));
    assert_eq!(
        ConformalSpec::from_bytes(&other, &v).unwrap_err(),
        ConformalError::TableMismatch
    );
    // Every truncation is refused or reads as no section; none panics.
    for cut in 0..file.len() {
        let _ = ConformalSpec::from_bytes(&file[..cut], &v);
    }
    // A head the table lacks.
    let no_bayes = wide_table(&["a".into(), "b".into(), "c".into()]);
    let nb = no_bayes.to_vec().unwrap();
    let f = fitted(
        Head::Open,
        0.1,
        vec![100, 5, 40],
        vec![0.5, f32::NEG_INFINITY, 0.2],
    );
    let file = with_conformal(&nb, &f).unwrap();
    assert_eq!(
        ConformalSpec::from_bytes(&file, &no_bayes.view()).unwrap_err(),
        ConformalError::MissingHead { head: Head::Open }
    );
    // The writer refuses a buffer of another size and mismatched lengths.
    let mut buf = vec![0u8; conformal_section_len(3) - 1];
    assert_eq!(
        write_conformal_section(&mut buf, 0, Head::Ml, 0.1, &[1, 2, 3], &[0.0; 3]),
        Err(ConformalError::BufferTooSmall)
    );
    assert_eq!(
        write_conformal_section(&mut buf, 0, Head::Ml, 0.1, &[1, 2], &[0.0; 3]),
        Err(ConformalError::Malformed)
    );
}

#[test]
fn set_errors_and_the_u64_form() {
    let (table, bytes) = default_table();
    let f = fitted(
        Head::Map,
        0.1,
        vec![100, 5, 40],
        vec![0.5, f32::NEG_INFINITY, 0.2],
    );
    let file = with_conformal(&bytes, &f).unwrap();
    let spec = ConformalSpec::from_bytes(&file, &table.view()).unwrap();
    let mut mask = [7u32; 2];
    assert_eq!(spec.set_of(&[0.5, 0.0, 0.19], &mut mask), Ok(2));
    assert_eq!(mask, [0b011, 7], "only the first word is written");
    assert_eq!(
        spec.set_of(&[0.5, f32::NAN, 0.19], &mut mask),
        Err(InferError::NanScore { class: 1 })
    );
    assert_eq!(spec.set_of(&[0.5, 0.1], &mut mask), Err(InferError::Length));
    assert_eq!(
        spec.set_of(&[0.5, 0.1, 0.3], &mut []),
        Err(InferError::Length)
    );
    let v = table.view();
    let (mut s, mut scratch) = ([0.0f32; 3], [0.0f32; 4]);
    let set = spec
        .set64(&v, &[6.0, -3.0, -3.0], 1.0, &mut s, &mut scratch)
        .unwrap();
    let mut want = 0u64;
    for (c, &score) in s.iter().enumerate() {
        if score >= spec.threshold(c).unwrap() {
            want |= 1 << c;
        }
    }
    assert_eq!(set, want);
    assert_eq!(
        spec.set64(&v, &[f32::NAN, 0.0, 0.0], 1.0, &mut s, &mut scratch),
        Err(InferError::NanLogit { class: 0 })
    );
    assert_eq!(
        spec.set64(&v, &[0.0, 0.0, 0.0], 1.5, &mut s, &mut scratch),
        Err(InferError::Objectness)
    );
}

/// The default table's scores of the pooled validation and test rows (exchangeable:
/// one generator), per head, computed once.
type Pooled = (Vec<f32>, Vec<Option<usize>>);

fn pooled(head: Head) -> &'static Pooled {
    static P: OnceLock<Vec<(Head, Pooled)>> = OnceLock::new();
    let all = P.get_or_init(|| {
        let (table, _) = default_table();
        [Head::Map, Head::Open]
            .into_iter()
            .map(|h| {
                let mut s = head_scores(&table, h, data("val"));
                s.extend(head_scores(&table, h, data("test")));
                let mut l = data("val").labels.clone();
                l.extend(&data("test").labels);
                (h, (s, l))
            })
            .collect()
    });
    &all.iter().find(|(h, _)| *h == head).unwrap().1
}

/// Splits the pooled rows at random into calibration and test rows (a permutation from
/// `seed`): scores and labels of each part.
fn split(head: Head, seed: u64, cal_share: f64) -> [(Vec<f32>, Vec<Option<usize>>); 2] {
    let (s, l) = pooled(head);
    let n = l.len();
    let mut idx: Vec<usize> = (0..n).collect();
    let mut state = seed;
    for i in (1..n).rev() {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let j = ((state >> 33) as usize) % (i + 1);
        idx.swap(i, j);
    }
    let cut = (n as f64 * cal_share) as usize;
    let part = |ix: &[usize]| {
        let mut ss = Vec::with_capacity(ix.len() * 3);
        let mut ll = Vec::with_capacity(ix.len());
        for &i in ix {
            ss.extend_from_slice(&s[3 * i..3 * i + 3]);
            ll.push(l[i]);
        }
        (ss, ll)
    };
    [part(&idx[..cut]), part(&idx[cut..])]
}

fn spec_bytes(f: &Fitted) -> Vec<u8> {
    let (_, bytes) = default_table();
    with_conformal(&bytes, f).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// On exchangeable rows, every class's coverage on the held-out rows is at least
    /// 1 - alpha, less four standard deviations of the sampling error: that of the
    /// threshold (the class's calibration rows) and that of the held-out rows.
    #[test]
    fn coverage_on_exchangeable_rows(seed in any::<u64>(), open in any::<bool>(), alpha in 0.05f64..0.3) {
        let head = if open { Head::Open } else { Head::Map };
        let [(cs, cl), (ts, tl)] = split(head, seed, 0.5);
        let f = fit(head, alpha, 3, &cs, &cl);
        let file = spec_bytes(&f);
        let (table, _) = default_table();
        let spec = ConformalSpec::from_bytes(&file, &table.view()).unwrap();
        let got = coverage(3, &sets(&spec, &ts).unwrap(), &tl, &[]);
        for (c, &(n, cov)) in got.per_class.iter().enumerate() {
            let n_cal = f64::from(f.rows[c]);
            let sd = (alpha * (1.0 - alpha) * (1.0 / n as f64 + 1.0 / n_cal)).sqrt();
            prop_assert!(cov >= 1.0 - alpha - 4.0 * sd, "class {c}: {cov} at alpha {alpha}, n {n}");
        }
    }

    /// A smaller alpha gives a superset, row by row; a set is empty exactly when every
    /// score is below its threshold, and holds exactly the classes at or above theirs.
    #[test]
    fn monotone_in_alpha_and_empty_iff_below(seed in any::<u64>(), a in 0.01f64..0.5, b in 0.01f64..0.5) {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        let [(cs, cl), (ts, _)] = split(Head::Open, seed, 0.3);
        let (table, _) = default_table();
        let fl = spec_bytes(&fit(Head::Open, lo, 3, &cs, &cl));
        let fh = spec_bytes(&fit(Head::Open, hi, 3, &cs, &cl));
        let sl = ConformalSpec::from_bytes(&fl, &table.view()).unwrap();
        let sh = ConformalSpec::from_bytes(&fh, &table.view()).unwrap();
        let (big, small) = (sets(&sl, &ts).unwrap(), sets(&sh, &ts).unwrap());
        for (x, y) in big.iter().zip(&small) {
            prop_assert!(*x || !*y);
        }
        let t: Vec<f32> = (0..3).map(|c| sh.threshold(c).unwrap()).collect();
        for (row, set) in ts.chunks_exact(3).zip(small.chunks_exact(3)) {
            for c in 0..3 {
                prop_assert_eq!(set[c], row[c] >= t[c]);
            }
            prop_assert_eq!(set.iter().all(|&s| !s), row.iter().zip(&t).all(|(s, t)| s < t));
        }
    }

    /// Any thresholds and scores: the bitmask of a K above 32 spreads over words, bit c
    /// of word c / 32, and its size is its popcount.
    #[test]
    fn wide_masks(k in 2usize..80, seed in any::<u64>()) {
        let mut state = seed;
        let mut next = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let thresholds: Vec<f32> = (0..k).map(|_| next()).collect();
        let rows = vec![1000u32; k];
        let mut sec = vec![0u8; conformal_section_len(k)];
        write_conformal_section(&mut sec, 0, Head::Ml, 0.1, &rows, &thresholds).unwrap();
        let names: Vec<String> = (0..k).map(|i| format!("c{i}")).collect();
        let table = wide_table(&names);
        let spec = ConformalSpec::from_bytes(&sec, &table.view()).unwrap();
        let s: Vec<f32> = (0..k).map(|_| next()).collect();
        let mut mask = vec![0u32; mlmap::set_words(k)];
        let size = spec.set_of(&s, &mut mask).unwrap();
        prop_assert_eq!(size, mask.iter().map(|w| w.count_ones()).sum::<u32>());
        for c in 0..k {
            prop_assert_eq!(mask[c / 32] >> (c % 32) & 1 == 1, s[c] >= thresholds[c]);
        }
    }
}

/// A table of the given classes without a Bayes head, fitted on a few rows (for the
/// shape only).
fn wide_table(names: &[String]) -> DynTable {
    use mlmap::host::dataset::Label;
    use mlmap::host::fit::{fit as fit_table, FitParams};
    let k = names.len();
    let mut rows = Loaded {
        classes: names.to_vec(),
        labels: Vec::new(),
        objectness: Vec::new(),
        logits: Vec::new(),
        locations: Vec::new(),
        has_labels: true,
        first_missing_label: None,
    };
    for r in 0..3 * k {
        rows.labels.push(Label::Class(r % k));
        rows.objectness.push(1.0);
        for c in 0..k {
            let d = r as f64 * 0.01;
            rows.logits
                .push(if c == r % k { 2.0 + d } else { -1.0 - d });
        }
    }
    let params = FitParams {
        bins_ml: 4,
        bins_map: 4,
        bayes: None,
        ..FitParams::default()
    };
    fit_table(&rows, &params).unwrap()
}

#[test]
fn lac_and_softmax_scores() {
    // Two classes, logits (0, ln 3): softmax (1/4, 3/4), times OS 0.8.
    let p = softmax_scores(2, &[0.0, 3f64.ln()], &[0.8]).unwrap();
    assert!((p[0] - 0.2).abs() < 1e-12 && (p[1] - 0.6).abs() < 1e-12);
    let l = Lac { qhat: 0.5, rows: 1 };
    assert!(l.contains(0.6) && !l.contains(0.2));
}
