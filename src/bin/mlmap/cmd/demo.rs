//! `mlmap demo`: the whole job on the data shipped in `examples/data/`.
//!
//! 1. fit a table with the authors' detection settings (22 / 17 bins);
//! 2. tune the lambdas of the three heads on the validation set, keeping the firmware's
//!    shape 22 / 17 / 22;
//! 3. evaluate sigmoid, softmax, temperature, ML, MAP and Bayes on the test set and on
//!    the never-seen objects;
//! 4. decode the written table with the no_std layer (`Table<3, 22, 17, 22, 4>`) and check
//!    that it scores every test row bit for bit like the host, every head;
//! 5. name the head to ship: the best ECE on test + never-seen objects among the heads
//!    within the accuracy and mAP guards against softmax.

use std::fmt::Write as _;
use std::path::Path;

use mlmap::host::data::{self, Loaded};
use mlmap::host::eval::{self, head_scores, Inputs};
use mlmap::host::fit::{FitParams, TrainingSet};
use mlmap::host::metrics::MetricsConfig;
use mlmap::host::tune::{self, BayesGrid, Guards, Objective, TuneParams};
use mlmap::host::DynTable;
use mlmap::{EdgeMode, Head, Table, UpperTail};

use crate::args::{DemoArgs, Format};
use crate::error::{fit_error, CliError, Result};
use crate::output;
use crate::report::{self, table_summary};
use crate::shared::{write_plots, write_table};

/// The shape the demo's firmware is built for, with room for a recalibration map per
/// head.
type Firmware = Table<3, 22, 17, 22, 4, { mlmap::MAX_KNOTS }>;

/// Scores every row with the decoded fixed-size table and with the host table;
/// returns (rows compared, rows whose scores differ in any bit).
fn device_check(
    bytes: &[u8],
    host: &DynTable,
    data: &Loaded,
    path: &Path,
) -> Result<(usize, usize)> {
    let device = Firmware::from_bytes(bytes)
        .map_err(|e| CliError::Internal(format!("the no_std layer refused the table: {e}")))?;
    let ml_host = head_scores(host, Head::Ml, data, path)?;
    let map_host = head_scores(host, Head::Map, data, path)?;
    let bayes_host = head_scores(host, Head::Bayes, data, path)?;
    let open_host = head_scores(host, Head::Open, data, path)?;
    let mut differ = 0;
    let rows = data.logits.chunks_exact(3).zip(&data.objectness);
    let host_rows = ml_host
        .chunks_exact(3)
        .zip(map_host.chunks_exact(3))
        .zip(bayes_host.chunks_exact(3))
        .zip(open_host.chunks_exact(3));
    for ((x, &os), (((ml_h, map_h), bayes_h), open_h)) in rows.zip(host_rows) {
        let mut xs = [0f32; 3];
        for (d, &v) in xs.iter_mut().zip(x) {
            *d = v as f32;
        }
        let x = xs;
        let (ml, map, bayes, open) = match (
            device.ml(&x, os as f32),
            device.map(&x, os as f32),
            device.bayes(&x, os as f32),
            device.open(&x, os as f32),
        ) {
            (Ok(a), Ok(b), Ok(c), Ok(d)) => (a, b, c, d),
            (Err(e), _, _, _) | (_, Err(e), _, _) | (_, _, Err(e), _) | (_, _, _, Err(e)) => {
                return Err(CliError::input(path, e))
            }
        };
        let same = |d: &[f32; 3], h: &[f64]| {
            d.iter()
                .zip(h)
                .all(|(a, &b)| a.to_bits() == (b as f32).to_bits())
        };
        if !same(&ml.0, ml_h)
            || !same(&map.0, map_h)
            || !same(&bayes.0, bayes_h)
            || !same(&open.0, open_h)
        {
            differ += 1;
        }
    }
    Ok((data.len(), differ))
}

pub fn run(a: &DemoArgs) -> Result<()> {
    let path = |name: &str| a.data.join(name);
    let (train_p, val_p, test_p, ood_p) = (
        path("train.csv"),
        path("val.csv"),
        path("test.csv"),
        path("ood.csv"),
    );
    // Every input is read and checked before anything is written.
    let train = TrainingSet::read(&data::open(&train_p)?).map_err(|e| fit_error(&train_p, e))?;
    let val = Loaded::read(&val_p)?;
    let test = Loaded::read(&test_p)?;
    let ood = Loaded::read(&ood_p)?;
    std::fs::create_dir_all(&a.output)
        .map_err(|e| CliError::input(&a.output, format!("cannot create: {e}")))?;
    let mut log = String::new();
    let _ = writeln!(
        log,
        "mlmap demo: synthetic detector data from {}\n",
        a.data.display()
    );

    // 1. Fit with the authors' detection settings.
    let fitted = train
        .fit(&FitParams::default())
        .map_err(|e| fit_error(&train_p, e))?;
    let fitted_path = a.output.join("fitted.mlmap");
    let size = write_table(&fitted_path, &fitted)?;
    let _ = writeln!(log, "1. fit (authors' detection settings)");
    log.push_str(&table_summary(&fitted_path, &fitted, size));

    // 2. Tune the lambdas on the validation set at the firmware's shape. The
    //    never-seen objects stay out of it: they are for the evaluation.
    let lambdas = tune::lambda_grid(1e-8, 1e-1, 4).map_err(CliError::Input)?;
    let guards = Guards::default();
    let params = TuneParams {
        bins: vec![(Head::Ml, vec![22]), (Head::Map, vec![17])],
        bayes: Some(BayesGrid {
            bins: vec![22],
            lambdas: lambdas.clone(),
            objectness: false,
        }),
        epsilons: tune::epsilon_grid(),
        lambdas,
        guards,
        objective: Objective::Ece,
        edges: EdgeMode::Linspace,
        tail: UpperTail::Zero,
        detail: 5,
        maps: true,
    };
    let tune::Tuned {
        result,
        table: tuned,
        comparison,
        maps,
    } = tune::tune(&train, &val, &val_p, None, &params, |_, _| {})?;
    let tuned_path = a.output.join("tuned.mlmap");
    let size = write_table(&tuned_path, &tuned)?;
    let mut tune_text = report::candidates(&result, params.objective, 5, |h| params.candidates(h));
    tune_text.push('\n');
    tune_text.push_str(&report::comparison(&comparison, params.objective));
    tune_text.push('\n');
    tune_text.push_str(&report::maps_text(&maps));
    output::write_bytes_atomic(&a.output.join("tune.txt"), tune_text.as_bytes())?;
    let _ = writeln!(
        log,
        "\n2. tune lambdas on {} (ECE, bins kept at 22 / 17 / 22)",
        val_p.display()
    );
    log.push_str(&table_summary(&tuned_path, &tuned, size));

    // 3. Evaluate the six methods.
    let config = MetricsConfig::default();
    let ev = eval::evaluate(&Inputs {
        table: &tuned,
        test: (&test, &test_p),
        val: Some((&val, &val_p)),
        ood: Some((&ood, &ood_p)),
        config,
        groups: None,
    })?;
    for (format, name) in [
        (Format::Text, "eval.txt"),
        (Format::Json, "eval.json"),
        (Format::Markdown, "eval.md"),
    ] {
        output::write_bytes_atomic(
            &a.output.join(name),
            report::evaluation(&ev, format, None).as_bytes(),
        )?;
    }
    let plots_dir = a.output.join("plots");
    let n_plots = write_plots(&ev, &plots_dir, &tuned)?;
    let _ = writeln!(
        log,
        "\n3. evaluate on {} and {}",
        test_p.display(),
        ood_p.display()
    );
    log.push_str(&report::evaluation(&ev, Format::Text, None));

    // 4. The no_std layer decodes the written table and scores like the host.
    let bytes = std::fs::read(&tuned_path).map_err(|e| CliError::internal(&tuned_path, e))?;
    let (n, differ) = device_check(&bytes, &tuned, &test, &test_p)?;
    let _ = writeln!(
        log,
        "\n4. no_std layer: Table<3, 22, 17, 22, 4, 32>::from_bytes({}) scored {n} test rows: {} with scores differing from the host's in any bit",
        tuned_path.display(),
        differ
    );
    if differ != 0 {
        output::print(&log)?;
        return Err(CliError::Internal(format!(
            "{differ} rows differ between the no_std layer and the host"
        )));
    }

    let pct = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{:.1}%", 100.0 * v));
    let num = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
    let _ = writeln!(log, "\nsummary");
    let line = |what: &str, key: &str, show: &dyn Fn(Option<f64>) -> String| {
        let values: Vec<String> = ev
            .methods
            .iter()
            .map(|r| format!("{} {}", r.method.title(), show(ev.value(r.method, key))))
            .collect();
        format!("  {what}: {}\n", values.join(", "))
    };
    log.push_str(&line("calibration (ECE, lower is better)", "ece", &num));
    log.push_str(&line(
        "never-seen objects scored above 0.9",
        "ood_over_0_9",
        &pct,
    ));
    let best = ev.best_head(params.objective, &guards)?;
    let _ = match best {
        Some((method, m)) => writeln!(
            log,
            "  head to ship: {} has the best ECE on test + never-seen objects ({}) among the heads within {:.1} points of softmax's accuracy and {:.1} of its mAP (accuracy {}, mAP {})",
            method.title(),
            num(Some(m.ece)),
            100.0 * guards.max_accuracy_loss,
            100.0 * guards.max_map_loss,
            pct(m.accuracy),
            num(m.mean_ap()),
        ),
        None => writeln!(
            log,
            "  head to ship: none of the heads keeps within {:.1} points of softmax's accuracy and {:.1} of its mAP on test + never-seen objects",
            100.0 * guards.max_accuracy_loss,
            100.0 * guards.max_map_loss,
        ),
    };
    let _ = writeln!(
        log,
        "  wrote fitted.mlmap, tuned.mlmap, tune.txt, eval.txt, eval.json, eval.md and {n_plots} plots into {}",
        a.output.display()
    );
    output::print(&log)
}
