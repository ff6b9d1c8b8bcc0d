//! The host metrics and baselines against independent reference values.
//!
//! The golden files in `tests/golden/metrics/` are written by
//! `tools/metrics_reference.py` (numpy, scipy and scikit-learn; the versions are
//! recorded in each file). Regenerate them from the repository root with:
//!
//! ```text
//! python3 tools/metrics_reference.py
//! ```
//!
//! Tolerances: [`REL`] relative (with an [`ABS`] floor for values that are 0) wherever
//! both sides compute the same closed form; bin counts, confidences and correctness are
//! compared exactly. The fitted temperature is compared to [`T_REL`]: the NLL is flat at
//! its minimum, so two correct searches agree on `T` only to about 1e-7, while their NLL
//! values agree to [`REL`].

use mlmap::host::baselines::{self, Baseline, Rows};
use mlmap::host::metrics::{self, Binning, MetricsConfig};
use serde_json::Value;

/// Relative tolerance for values both sides compute from the same formula.
const REL: f64 = 1e-12;
/// Absolute floor of the comparison, for values that are (nearly) 0.
const ABS: f64 = 1e-15;
/// Relative tolerance of the fitted temperature (see the module docs).
const T_REL: f64 = 1e-6;

const METRICS: &str = include_str!("golden/metrics/metrics.json");
const OOD: &str = include_str!("golden/metrics/ood.json");
const BASELINES: &str = include_str!("golden/metrics/baselines.json");
const TEMPERATURE: &str = include_str!("golden/metrics/temperature.json");

fn cases(text: &str) -> Vec<Value> {
    let doc: Value = serde_json::from_str(text).unwrap();
    doc["cases"].as_array().unwrap().clone()
}

/// A number, or the strings `inf` / `-inf` the script writes for non-finite values.
fn num(v: &Value) -> f64 {
    match v {
        Value::String(s) if s == "inf" => f64::INFINITY,
        Value::String(s) if s == "-inf" => f64::NEG_INFINITY,
        _ => v.as_f64().unwrap_or_else(|| panic!("not a number: {v}")),
    }
}

fn opt(v: &Value) -> Option<f64> {
    (!v.is_null()).then(|| num(v))
}

/// A matrix as row-major values and its column count.
fn matrix(v: &Value) -> (Vec<f64>, usize) {
    let rows = v.as_array().unwrap();
    let k = rows[0].as_array().unwrap().len();
    let flat = rows
        .iter()
        .flat_map(|r| r.as_array().unwrap().iter().map(num))
        .collect();
    (flat, k)
}

fn vector(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(num).collect()
}

fn labels(v: &Value) -> Vec<Option<usize>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_u64().map(|c| c as usize))
        .collect()
}

fn assert_close(got: f64, want: f64, rel: f64, what: &str) {
    let err = (got - want).abs();
    assert!(
        err <= rel * want.abs().max(got.abs()) + ABS,
        "{what}: got {got:e}, want {want:e} (error {err:e})"
    );
}

fn assert_opt(got: Option<f64>, want: &Value, what: &str) {
    match (got, opt(want)) {
        (Some(g), Some(w)) => assert_close(g, w, REL, what),
        (None, None) => {}
        (g, w) => panic!("{what}: got {g:?}, want {w:?}"),
    }
}

#[test]
fn metrics_match_reference() {
    for case in cases(METRICS) {
        let name = case["name"].as_str().unwrap();
        let (scores, k) = matrix(&case["scores"]);
        let labels = labels(&case["labels"]);
        let classes: Vec<&str> = case["classes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_str().unwrap())
            .collect();
        let bins = case["bins"].as_u64().unwrap() as usize;
        let exp = &case["expected"];
        // Cases with logits decide tied top scores by them (DESIGN §1.7).
        let logits = match &case["logits"] {
            Value::Null => Vec::new(),
            v => matrix(v).0,
        };

        let outcomes = metrics::outcomes_with_logits(&scores, &logits, k, &labels).unwrap();
        let conf = vector(&exp["conf"]);
        let correct: Vec<bool> = exp["correct"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b.as_bool().unwrap())
            .collect();
        for (i, o) in outcomes.iter().enumerate() {
            assert_eq!(o.conf, conf[i], "{name}: conf of row {i}");
            assert_eq!(o.correct, correct[i], "{name}: correctness of row {i}");
        }

        for binning in Binning::ALL {
            let cfg = MetricsConfig { bins, binning };
            let m = metrics::evaluate_with_logits(&scores, &logits, k, &labels, &cfg).unwrap();
            let want = &exp["bins"][binning.name()];
            let what = format!("{name} / {binning}");
            assert_close(m.ece, num(&want["ece"]), REL, &format!("{what}: ece"));
            assert_close(m.mce, num(&want["mce"]), REL, &format!("{what}: mce"));
            let counts: Vec<usize> = m.reliability.iter().map(|b| b.count).collect();
            let want_counts: Vec<usize> = want["counts"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c.as_u64().unwrap() as usize)
                .collect();
            assert_eq!(counts, want_counts, "{what}: bin counts");

            // The other metrics do not depend on the binning.
            assert_opt(m.nll, &exp["nll"], &format!("{name}: nll"));
            assert_close(m.brier, num(&exp["brier"]), REL, &format!("{name}: brier"));
            for (key, got) in [
                ("tp_mean", m.tp_mean),
                ("tp_var", m.tp_var),
                ("fp_mean", m.fp_mean),
                ("fp_var", m.fp_var),
                ("auroc", m.auroc),
                ("accuracy", m.accuracy),
            ] {
                assert_opt(got, &exp[key], &format!("{name}: {key}"));
            }
            let want_ap = exp["ap"].as_array().unwrap();
            assert_eq!(m.ap.len(), want_ap.len());
            for (c, (got, want)) in m.ap.iter().zip(want_ap).enumerate() {
                assert_opt(*got, want, &format!("{name}: ap_{}", classes[c]));
            }

            // Keys in the DESIGN §1.5 order, values as the fields.
            let entries = m.entries(&classes);
            let keys: Vec<&str> = entries.iter().map(|e| e.0.as_str()).collect();
            let mut want_keys = Vec::from(metrics::Metrics::LEADING_KEYS);
            let ap_keys: Vec<String> = classes.iter().map(|c| format!("ap_{c}")).collect();
            want_keys.extend(ap_keys.iter().map(String::as_str));
            assert_eq!(keys, want_keys, "{name}: entry keys");
            assert_eq!(entries[0].1, Some(m.ece));
            assert_eq!(entries[8].1, m.auroc);
        }
    }
}

#[test]
fn ood_metrics_match_reference() {
    for case in cases(OOD) {
        let name = case["name"].as_str().unwrap();
        let (scores, k) = matrix(&case["scores"]);
        let got = metrics::ood_metrics(&scores, k).unwrap();
        let exp = &case["expected"];
        assert_close(got.ood_mean, num(&exp["ood_mean"]), REL, name);
        assert_close(got.ood_over_0_9, num(&exp["ood_over_0_9"]), REL, name);
        assert_eq!(got.rows, scores.len() / k);
    }
}

#[test]
fn baselines_match_reference() {
    for case in cases(BASELINES) {
        let (logits, k) = matrix(&case["logits"]);
        let objectness = vector(&case["objectness"]);
        let t = num(&case["t"]);
        let rows = Rows::new(&logits, k, &[], &objectness).unwrap();
        for (key, baseline) in [
            ("sigmoid", Baseline::Sigmoid),
            ("softmax", Baseline::Softmax),
            ("temperature", Baseline::Temperature(t)),
        ] {
            let got = baselines::score_rows(baseline, &rows).unwrap();
            let (want, _) = matrix(&case[key]);
            assert_eq!(got.len(), want.len());
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                let what = format!("{key} (T = {t}) row {} class {}", i / k, i % k);
                assert_close(*g, *w, REL, &what);
            }
            // The per-row functions agree with the batch one.
            let mut one = vec![0.0; k];
            let (row, os) = (&logits[k..2 * k], objectness[1]);
            match baseline {
                Baseline::Sigmoid => baselines::sigmoid(row, os, &mut one).unwrap(),
                Baseline::Softmax => baselines::softmax(row, os, &mut one).unwrap(),
                Baseline::Temperature(t) => baselines::temperature(row, os, t, &mut one).unwrap(),
            }
            assert_eq!(one, got[k..2 * k]);
        }
    }
}

#[test]
fn temperature_fit_matches_grid_search() {
    for case in cases(TEMPERATURE) {
        let name = case["name"].as_str().unwrap();
        let (logits, k) = matrix(&case["logits"]);
        let labels = labels(&case["labels"]);
        let objectness = vector(&case["objectness"]);
        let rows = Rows::new(&logits, k, &labels, &objectness).unwrap();
        let fit = baselines::fit_temperature_detailed(&rows).unwrap();
        let (t, nll) = (num(&case["t"]), num(&case["nll"]));
        assert_close(fit.t, t, T_REL, &format!("{name}: T"));
        assert_close(fit.nll, nll, REL, &format!("{name}: NLL at the optimum"));
        assert!(!fit.at_limit, "{name}");
        assert_eq!(fit.labelled, labels.iter().flatten().count());
        assert_eq!(baselines::fit_temperature(&rows), Ok(fit.t));
    }
}

const SEPARATION: &str = include_str!("golden/metrics/separation.json");
const ISOTONIC: &str = include_str!("golden/metrics/isotonic.json");

/// Relative tolerance of the isotonic scores: both sides interpolate the same knots,
/// but scikit-learn's pooled means and `numpy.interp` round differently from the
/// exact block counts here, by a few units in the last place.
const ISO_REL: f64 = 1e-12;

#[test]
fn unseen_separation_matches_reference() {
    for case in cases(SEPARATION) {
        let name = case["name"].as_str().unwrap();
        let (known, unseen) = (vector(&case["known"]), vector(&case["unseen"]));
        let exp = &case["expected"];
        assert_opt(
            metrics::separation_auroc(&known, &unseen),
            &exp["auroc"],
            &format!("{name}: ood_auroc"),
        );
        assert_opt(
            metrics::fpr_at_95_tpr(&known, &unseen),
            &exp["fpr95"],
            &format!("{name}: ood_fpr95"),
        );
    }
}

#[test]
fn isotonic_and_energy_match_reference() {
    for case in cases(ISOTONIC) {
        let name = case["name"].as_str().unwrap();
        let (vx, k) = matrix(&case["val_logits"]);
        let vl = labels(&case["val_labels"]);
        let vo = vector(&case["val_objectness"]);
        let iso = baselines::fit_isotonic(&Rows::new(&vx, k, &vl, &vo).unwrap()).unwrap();
        let (tx, _) = matrix(&case["logits"]);
        let to = vector(&case["objectness"]);
        let rows = Rows::new(&tx, k, &[], &to).unwrap();
        let got = baselines::score_isotonic(&iso, &rows).unwrap();
        let (want, _) = matrix(&case["isotonic"]);
        assert_eq!(got.len(), want.len());
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            let what = format!("{name}: isotonic row {} class {}", i / k, i % k);
            assert_close(*g, *w, ISO_REL, &what);
        }
        let energy = baselines::negative_energies(&rows).unwrap();
        for (i, (g, w)) in energy
            .iter()
            .zip(vector(&case["negative_energy"]))
            .enumerate()
        {
            assert_close(*g, w, REL, &format!("{name}: negative energy of row {i}"));
        }
    }
}
