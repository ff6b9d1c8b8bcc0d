//! The drift monitor (DESIGN §7) against the numpy reference (tools/monitor_ref.py):
//! the training shares, every window of two logs, the fitted thresholds; the section's
//! checks; and the properties of the counts and the PSI on random tables and streams.

use std::path::Path;

use mlmap::host::data::Loaded;
use mlmap::host::dataset::Label;
use mlmap::host::fit::{fit, FitParams};
use mlmap::host::monitor::{fit_thresholds, reference, with_monitor, DynMonitor};
use mlmap::host::{DynQTable, DynTable};
use mlmap::{
    InferError, Monitor, MonitorError, MonitorParams, MonitorSpec, Table, Thresholds, MONITOR_MAGIC,
};
use proptest::prelude::*;
use serde_json::Value;

fn root(p: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

fn golden(name: &str) -> Value {
    let text = std::fs::read_to_string(root("tests/golden/monitor").join(name)).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn default_table() -> (DynTable, Vec<u8>) {
    let bytes = std::fs::read(root("tables/default.mlmap")).unwrap();
    (DynTable::from_bytes(&bytes).unwrap(), bytes)
}

fn params(window: u32) -> MonitorParams {
    MonitorParams {
        window,
        alpha: 0.0,
        thresholds: Thresholds::NONE,
    }
}

fn close(got: f64, want: f64, rel: f64, abs: f64, what: &str) {
    assert!(
        (got - want).abs() <= abs + rel * want.abs(),
        "{what}: {got} against {want}"
    );
}

#[test]
fn training_shares_match_numpy() {
    let (table, bytes) = default_table();
    let want = golden("reference.json");
    let got = reference(&table).unwrap();
    let file = with_monitor(&bytes, &table, &params(50)).unwrap();
    let spec = MonitorSpec::from_bytes(&file, &table.view()).unwrap();
    let bins = spec.bins();
    for (j, row) in want["reference"].as_array().unwrap().iter().enumerate() {
        for (b, e) in row.as_array().unwrap().iter().enumerate() {
            let e = e.as_f64().unwrap();
            // The host's f64 shares are the numpy ones exactly (counts over N).
            assert_eq!(got[j * bins + b], e, "logit {j} bin {b}");
            // The section stores them rounded once to f32.
            assert_eq!(spec.reference(j, b), Some(e as f32));
        }
    }
}

#[test]
fn windows_match_numpy() {
    let (table, bytes) = default_table();
    let file = with_monitor(&bytes, &table, &params(50)).unwrap();
    let spec = MonitorSpec::from_bytes(&file, &table.view()).unwrap();
    for name in ["ood", "test"] {
        let want = golden(&format!("windows_{name}.json"));
        let data = Loaded::read(&root(&format!("examples/data/{name}.csv"))).unwrap();
        let (x, os) = (data.logits_f32(), data.objectness_f32());
        let mut mon = DynMonitor::new(&spec);
        let mut got = Vec::new();
        for (row, &o) in x.chunks_exact(3).zip(&os) {
            if let Some(w) = mon.push(&spec, row, o).unwrap() {
                got.push(w);
            }
        }
        got.extend(mon.finish(&spec));
        let want = want["windows"].as_array().unwrap();
        assert_eq!(got.len(), want.len(), "{name}");
        for ((s, psi), w) in got.iter().zip(want) {
            let what = format!("{name} window {}", s.window);
            assert_eq!(u64::from(s.window), w["window"].as_u64().unwrap(), "{what}");
            assert_eq!(u64::from(s.rows), w["rows"].as_u64().unwrap(), "{what}");
            // f32 sums and the monitor's own ln: a relative 1e-5 of each term.
            for (p, wp) in psi.iter().zip(w["psi"].as_array().unwrap()) {
                close(f64::from(*p), wp.as_f64().unwrap(), 1e-5, 1e-6, &what);
            }
            close(
                f64::from(s.psi_max),
                w["psi_max"].as_f64().unwrap(),
                1e-5,
                1e-6,
                &what,
            );
            close(
                f64::from(s.oos_rate),
                w["oos_rate"].as_f64().unwrap(),
                0.0,
                1e-7,
                &what,
            );
            close(
                f64::from(s.q_mean.unwrap()),
                w["q_mean"].as_f64().unwrap(),
                0.0,
                1e-5,
                &what,
            );
            // No fitted thresholds: never an alarm.
            assert!(!s.alarms.any(), "{what}");
        }
    }
}

#[test]
fn thresholds_match_numpy() {
    let (table, bytes) = default_table();
    let want = golden("thresholds.json");
    let file = with_monitor(&bytes, &table, &params(50)).unwrap();
    let spec = MonitorSpec::from_bytes(&file, &table.view()).unwrap();
    let val = Loaded::read(&root("examples/data/val.csv")).unwrap();
    let got = fit_thresholds(
        &spec,
        &val.logits_f32(),
        &val.objectness_f32(),
        0.05,
        2000,
        0,
    )
    .unwrap();
    // The same windows are drawn; the quantiles are the same ranks of metrics that
    // agree to a relative 1e-5.
    assert_eq!(got.windows.len(), 2000);
    assert!((got.level - want["level"].as_f64().unwrap()).abs() < 1e-12);
    assert!((got.alarm_rate - want["alarm_rate"].as_f64().unwrap()).abs() < 1e-12);
    let t = got.thresholds;
    close(
        f64::from(t.psi),
        want["psi"].as_f64().unwrap(),
        1e-5,
        1e-6,
        "psi",
    );
    close(
        f64::from(t.oos),
        want["oos"].as_f64().unwrap(),
        0.0,
        1e-7,
        "oos",
    );
    close(f64::from(t.q), want["q"].as_f64().unwrap(), 0.0, 1e-5, "q");
    assert!(got.alarm_rate <= 0.05);
}

#[test]
fn the_shipped_example_reads_back() {
    let bytes = std::fs::read(root("tests/golden/monitor_small.mlmap")).unwrap();
    let table: Table<3, 22, 17, 22, 4> = Table::from_bytes(&bytes).unwrap();
    let spec = MonitorSpec::from_bytes(&bytes, &table.view()).unwrap();
    let want = golden("thresholds.json");
    let p = spec.params();
    assert_eq!(p.window, 50);
    assert_eq!(p.alpha, 0.05);
    close(
        f64::from(p.thresholds.psi),
        want["psi"].as_f64().unwrap(),
        1e-5,
        1e-6,
        "psi",
    );
    // The fixed-size monitor and the vector one agree bit for bit.
    let data = Loaded::read(&root("examples/data/ood.csv")).unwrap();
    let mut fixed: Monitor<'_, 3, 22, 4> = Monitor::new(&spec).unwrap();
    let mut dynamic = DynMonitor::new(&spec);
    let mut alarms = 0;
    for (row, &o) in data
        .logits_f32()
        .chunks_exact(3)
        .zip(&data.objectness_f32())
    {
        let x: [f32; 3] = row.try_into().unwrap();
        let a = fixed.push(&x, o).unwrap();
        let b = dynamic.push(&spec, &x, o).unwrap();
        assert_eq!(a.map(|r| (r.summary, r.psi.to_vec())), b);
        if let Some(r) = a {
            alarms += u32::from(r.summary.alarms.any());
        }
    }
    // The out-of-distribution log alarms in every window.
    assert_eq!(alarms, 2000 / 50);
}

#[test]
fn open_scores_and_monitor_in_one_pass() {
    let bytes = std::fs::read(root("tests/golden/monitor_small.mlmap")).unwrap();
    let table: Table<3, 22, 17, 22, 4> = Table::from_bytes(&bytes).unwrap();
    let spec = MonitorSpec::from_bytes(&bytes, &table.view()).unwrap();
    let mut a: Monitor<'_, 3, 22, 4> = Monitor::new(&spec).unwrap();
    let mut b: Monitor<'_, 3, 22, 4> = Monitor::new(&spec).unwrap();
    let data = Loaded::read(&root("examples/data/test.csv")).unwrap();
    for (row, &o) in data
        .logits_f32()
        .chunks_exact(3)
        .zip(&data.objectness_f32())
    {
        let x: [f32; 3] = row.try_into().unwrap();
        let (scores, ra) = a.push_open(&x, o).unwrap();
        assert_eq!(scores.0, table.open(&x, o).unwrap().0);
        assert_eq!(ra, b.push(&x, o).unwrap());
    }
}

#[test]
fn sections_combine_and_older_readers_ignore_them() {
    let (table, bytes) = default_table();
    let q8 = std::fs::read(root("tables/default_q8.mlmap")).unwrap();
    // Quantized, then monitor: both read, and the table decodes as before.
    let file = with_monitor(&q8, &table, &params(100)).unwrap();
    assert!(file.starts_with(&bytes));
    assert_eq!(DynTable::from_bytes(&file).unwrap(), table);
    let t: Table<3, 22, 17, 22, 4> = Table::from_bytes(&file).unwrap();
    let q = DynQTable::from_bytes(&file).unwrap();
    assert_eq!(q.section_len(), q8.len() - bytes.len());
    let spec = MonitorSpec::from_bytes(&file, &t.view()).unwrap();
    assert_eq!(spec.params().window, 100);
    // Writing again replaces the monitor section and keeps the quantized one.
    let again = with_monitor(&file, &table, &params(7)).unwrap();
    assert_eq!(again.len(), file.len());
    let spec = MonitorSpec::from_bytes(&again, &t.view()).unwrap();
    assert_eq!(spec.params().window, 7);
    assert!(DynQTable::from_bytes(&again).is_ok());
}

#[test]
fn bad_sections_are_refused() {
    let (table, bytes) = default_table();
    let view = table.view();
    let file = with_monitor(&bytes, &table, &params(50)).unwrap();
    assert_eq!(
        MonitorSpec::from_bytes(&bytes, &view).unwrap_err(),
        MonitorError::Absent
    );
    // Any flipped bit of the section: the CRC, or the trailer no longer finds it.
    for i in bytes.len()..file.len() {
        let mut bad = file.clone();
        bad[i] ^= 0x10;
        let e = MonitorSpec::from_bytes(&bad, &view).unwrap_err();
        assert!(
            matches!(e, MonitorError::Corrupted | MonitorError::Absent),
            "byte {i}: {e:?}"
        );
    }
    // Every truncation.
    for cut in 0..file.len() {
        assert!(MonitorSpec::from_bytes(&file[..cut], &view).is_err());
    }
    // A section written for another table.
    let other_bytes = std::fs::read(root("tests/golden/layer/small_open.mlmap")).unwrap();
    let other = DynTable::from_bytes(&other_bytes).unwrap();
    let section = &file[bytes.len()..];
    let mut moved = other_bytes.clone();
    moved.extend_from_slice(section);
    let e = MonitorSpec::from_bytes(&moved, &other.view()).unwrap_err();
    assert!(matches!(
        e,
        MonitorError::ShapeMismatch { .. } | MonitorError::TableMismatch
    ));
    let mut mismatch = bytes.clone();
    mismatch.extend_from_slice(section);
    let last = bytes.len() - 1;
    mismatch[last] ^= 1; // the table's CRC no longer the one the section names
    let t2 = DynTable::from_bytes(&bytes).unwrap();
    assert_eq!(
        MonitorSpec::from_bytes(&mismatch, &t2.view()).unwrap_err(),
        MonitorError::TableMismatch
    );
    // A section alone reads (its table checked by shape only).
    assert!(MonitorSpec::from_bytes(section, &view).is_ok());
    assert_eq!(&section[..4], &MONITOR_MAGIC);
    // A window of 0, an alpha of 1, a NaN threshold: refused as written.
    for (p, e) in [
        (params(0), MonitorError::Window),
        (
            MonitorParams {
                alpha: 1.0,
                ..params(5)
            },
            MonitorError::Alpha,
        ),
        (
            MonitorParams {
                thresholds: Thresholds {
                    psi: f32::NAN,
                    ..Thresholds::NONE
                },
                ..params(5)
            },
            MonitorError::Threshold,
        ),
    ] {
        let f = with_monitor(&bytes, &table, &p).unwrap();
        assert_eq!(MonitorSpec::from_bytes(&f, &view).unwrap_err(), e);
    }
    // No Bayes head: no monitor.
    let no_bayes = table.clone().without_bayes();
    assert_eq!(
        with_monitor(&bytes, &no_bayes, &params(5)).unwrap_err(),
        MonitorError::NoBayesHead
    );
}

#[test]
fn bad_detections_count_nothing() {
    let bytes = std::fs::read(root("tests/golden/monitor_small.mlmap")).unwrap();
    let table: Table<3, 22, 17, 22, 4> = Table::from_bytes(&bytes).unwrap();
    let spec = MonitorSpec::from_bytes(&bytes, &table.view()).unwrap();
    let mut m: Monitor<'_, 3, 22, 4> = Monitor::new(&spec).unwrap();
    assert_eq!(
        m.push(&[0.0, f32::NAN, 1.0], 1.0).unwrap_err(),
        InferError::NanLogit { class: 1 }
    );
    assert_eq!(
        m.push(&[0.0, 0.0, 1.0], 1.5).unwrap_err(),
        InferError::Objectness
    );
    assert_eq!(m.accumulators().rows, 0);
    // Infinite logits are counted below or above.
    m.push(&[f32::NEG_INFINITY, f32::INFINITY, 0.0], 1.0)
        .unwrap();
    let (below, _, above) = m.counts(0).unwrap();
    assert_eq!((below, above), (1, 0));
    let (below, _, above) = m.counts(1).unwrap();
    assert_eq!((below, above), (0, 1));
    assert_eq!(m.accumulators().outside, 1);
    // A monitor type of another shape is refused.
    assert!(matches!(
        Monitor::<'_, 3, 21, 4>::new(&spec),
        Err(MonitorError::ShapeMismatch { .. })
    ));
}

/// A table fitted on `n` random rows of 3 classes (with background rows), and the rows.
fn random_table(seed: u64, n: usize) -> (DynTable, Loaded) {
    let mut s = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
    let mut next = move || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut rows = Loaded {
        classes: vec!["a".into(), "b".into(), "c".into()],
        labels: Vec::new(),
        objectness: Vec::new(),
        logits: Vec::new(),
        locations: Vec::new(),
        has_labels: true,
        first_missing_label: None,
    };
    for i in 0..n {
        let label = i % 4;
        rows.labels.push(if label == 3 {
            Label::Background
        } else {
            Label::Class(label)
        });
        rows.objectness.push(next());
        for j in 0..3 {
            let mean = if j == label { 2.0 } else { -1.0 };
            rows.logits.push(mean + 3.0 * (next() - 0.5));
        }
    }
    let params = FitParams {
        bayes: Some(mlmap::host::fit::BayesParams {
            bins: 9,
            lambda: 1e-3,
            objectness: false,
        }),
        ..FitParams::default()
    };
    (fit(&rows, &params).unwrap(), rows)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Every window's counts sum to its rows for every logit; the PSI is never negative;
    /// the training rows themselves, as one window, give a PSI of 0 for every logit.
    #[test]
    fn counts_psi_and_the_training_window(seed in any::<u64>(), n in 8usize..200, w in 1u32..40) {
        let (table, rows) = random_table(seed, n);
        let bytes = table.to_vec().unwrap();
        let file = with_monitor(&bytes, &table, &params(w)).unwrap();
        let spec = MonitorSpec::from_bytes(&file, &table.view()).unwrap();
        let mut mon = DynMonitor::new(&spec);
        let (x, os) = (rows.logits_f32(), rows.objectness_f32());
        // A stream shifted away from the training rows half the time.
        for (i, (row, &o)) in x.chunks_exact(3).zip(&os).enumerate() {
            let shifted: Vec<f32> = row.iter().map(|v| if i % 2 == 0 { v + 1.5 } else { *v }).collect();
            let before = mon.accumulators().rows;
            let r = mon.push(&spec, &shifted, o).unwrap();
            if let Some((s, psi)) = r {
                prop_assert_eq!(before + 1, w);
                prop_assert_eq!(s.rows, w);
                prop_assert!(psi.iter().all(|&p| p >= 0.0));
                prop_assert!(s.psi_max >= 0.0 && s.psi_max.is_finite());
                prop_assert!((0.0..=1.0).contains(&s.oos_rate));
            } else {
                // Each logit's counts sum to the window's rows so far.
                let acc = *mon.accumulators();
                prop_assert_eq!(acc.rows, before + 1);
            }
        }
        // The training rows as one window of exactly their number.
        let whole = with_monitor(&bytes, &table, &params(n as u32)).unwrap();
        let spec = MonitorSpec::from_bytes(&whole, &table.view()).unwrap();
        let mut mon = DynMonitor::new(&spec);
        let mut last = None;
        for (row, &o) in x.chunks_exact(3).zip(&os) {
            last = mon.push(&spec, row, o).unwrap();
        }
        let (s, psi) = last.unwrap();
        prop_assert_eq!(s.rows, n as u32);
        for p in psi {
            prop_assert!(p.abs() <= 1e-5, "psi {}", p);
        }
        prop_assert_eq!(s.oos_rate, 0.0);
    }

    /// The counts of the fixed-size monitor sum to the rows pushed, per logit.
    #[test]
    fn counts_sum_to_the_rows(xs in proptest::collection::vec(proptest::array::uniform3(-1e3f32..1e3), 1..60)) {
        let bytes = std::fs::read(root("tests/golden/monitor_small.mlmap")).unwrap();
        let table: Table<3, 22, 17, 22, 4> = Table::from_bytes(&bytes).unwrap();
        let spec = MonitorSpec::from_bytes(&bytes, &table.view()).unwrap();
        let mut m: Monitor<'_, 3, 22, 4> = Monitor::new(&spec).unwrap();
        for x in &xs {
            m.push(x, 0.5).unwrap();
            let rows = m.accumulators().rows;
            for j in 0..3 {
                let (below, bins, above) = m.counts(j).unwrap();
                prop_assert_eq!(below + bins.iter().sum::<u32>() + above, rows);
            }
        }
    }
}
