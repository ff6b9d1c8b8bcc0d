//! The plots written to temporary directories and read back.
use super::*;
use mlmap_core::{ClassSpec, EdgeMode, Settings, UpperTail};

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn read(path: &Path) -> String {
    fs::read_to_string(path).unwrap()
}

fn assert_svg(path: &Path) -> String {
    let svg = read(path);
    assert!(
        svg.starts_with("<svg"),
        "{}: {}",
        path.display(),
        &svg[..40]
    );
    assert!(svg.trim_end().ends_with("</svg>"), "{}", path.display());
    svg
}

fn no_temporaries(dir: &Path) {
    for entry in fs::read_dir(dir).unwrap() {
        let name = entry.unwrap().file_name();
        assert!(
            !name.to_string_lossy().ends_with(".tmp"),
            "{name:?} left behind"
        );
    }
}

/// A directory that cannot be created even by root: its parent is a file.
fn unwritable(base: &Path) -> PathBuf {
    let file = base.join("a_file");
    fs::write(&file, b"x").unwrap();
    file.join("plots")
}

fn assert_names_path(err: &PlotError, path: &Path) {
    assert!(err.path().starts_with(path) || path.starts_with(err.path()));
    let msg = err.to_string();
    assert!(msg.contains(&path.display().to_string()), "{msg}");
}

fn table() -> DynTable {
    let settings = Settings {
        lambda_ml: 0.0055,
        lambda_map: 0.00012,
        edge_mode: EdgeMode::Linspace,
        upper_tail: UpperTail::Zero,
    };
    let spec = |name, mean, ml: Vec<f32>, map: Vec<f32>| ClassSpec {
        name,
        rows: 100,
        mean,
        variance: 1.5,
        ml_range: (mean - 3.0, mean + 3.0),
        ml_freqs: ml,
        map_range: (mean - 2.5, mean + 2.5),
        map_freqs: map,
    };
    DynTable::new(
        settings,
        vec![
            spec(
                "car",
                4.0,
                vec![0.1, 0.2, 0.4, 0.2, 0.1],
                vec![0.25, 0.5, 0.25],
            ),
            spec(
                "cyclist",
                -1.0,
                vec![0.2, 0.2, 0.2, 0.2, 0.2],
                vec![0.5, 0.25, 0.25],
            ),
            spec(
                "pedestrian",
                0.5,
                vec![0.0, 0.1, 0.3, 0.5, 0.1],
                vec![0.2, 0.3, 0.5],
            ),
        ],
    )
    .unwrap()
}

#[test]
fn file_stems_are_safe() {
    assert_eq!(file_stem("ml"), "ml");
    assert_eq!(file_stem("a/b c"), "a_b_c");
    assert_eq!(file_stem("..x"), "_.x");
    assert_eq!(file_stem(""), "unnamed");
    let stems = class_stems(&["car", "ml", "a b", "a_b"], ["ml", "map"].into_iter());
    assert_eq!(stems, ["pr_car", "pr_class_ml", "pr_a_b", "pr_a_b_3"]);
}

fn cfg(bins: usize) -> MetricsConfig {
    MetricsConfig {
        bins,
        ..MetricsConfig::default()
    }
}

fn outcome((conf, correct): (f64, bool)) -> Outcome {
    Outcome {
        conf,
        pred: 0,
        correct,
    }
}

#[test]
fn the_reliability_diagram_follows_the_binning() {
    // Confidences 0.3 (correct) and 0.35 (wrong): one bin (0.3, 0.4] apart from
    // 0.3 under the DESIGN rule (ECE 0.5 * 0.7 + 0.5 * 0.35), one bin [0.3, 0.4)
    // together under torchmetrics' (ECE |0.5 - 0.325| = 0.175).
    let dir = tmp();
    let outcomes = [(0.3, true), (0.35, false)].map(outcome);
    let svg = |binning| {
        let cfg = MetricsConfig { bins: 10, binning };
        let paths = reliability_diagram(dir.path(), "ml", &outcomes, &cfg).unwrap();
        assert_svg(&paths[0])
    };
    assert!(svg(metrics::Binning::Design).contains("ECE = 0.5250"));
    assert!(svg(metrics::Binning::Torchmetrics).contains("ECE = 0.1750"));
}

#[test]
fn reliability_diagram_shows_the_ece() {
    let dir = tmp();
    // Bin (0.9, 1]: acc 0.5, conf 0.95; bin (0.5, 0.6]: acc 1, conf 0.6.
    // ECE = 0.5 * 0.45 + 0.5 * 0.4 = 0.425.
    let outcomes = [(0.95, true), (0.95, false), (0.6, true), (0.6, true)].map(outcome);
    let paths = reliability_diagram(dir.path(), "ml", &outcomes, &cfg(10)).unwrap();
    assert_eq!(paths, [dir.path().join("reliability_ml.svg")]);
    let svg = assert_svg(&paths[0]);
    assert!(svg.contains("ECE = 0.4250"), "{svg}");
    assert!(svg.contains("Reliability: ml"));
    assert!(svg.contains("perfect calibration"));
    no_temporaries(dir.path());
}

#[test]
fn reliability_diagram_handles_empty_and_refuses_bad_input() {
    let dir = tmp();
    let paths = reliability_diagram(dir.path(), "map", &[], &cfg(10)).unwrap();
    assert!(assert_svg(&paths[0]).contains("ECE = n/a"));

    let one = [outcome((0.5, true))];
    let err = reliability_diagram(dir.path(), "map", &one, &cfg(0)).unwrap_err();
    assert!(matches!(err, PlotError::Input { .. }));
    assert_names_path(&err, &dir.path().join("reliability_map.svg"));
    let nan = [outcome((f64::NAN, true))];
    let err = reliability_diagram(dir.path(), "map", &nan, &cfg(10)).unwrap_err();
    assert!(err.to_string().contains("not finite"), "{err}");
}

#[test]
fn score_histograms_have_means_in_the_legend() {
    let dir = tmp();
    let paths = tp_fp_histograms(dir.path(), "softmax", &[0.9, 0.8, 0.85], &[0.99, 0.2]).unwrap();
    assert_eq!(paths, [dir.path().join("scores_softmax.svg")]);
    let svg = assert_svg(&paths[0]);
    assert!(svg.contains("mean = 0.850"), "{svg}");
    assert!(svg.contains("mean = 0.595"), "{svg}");
    assert!(svg.contains("true positives (n = 3)"));
    assert!(svg.contains("false positives (n = 2)"));

    for (tp, fp) in [
        (&[][..], &[0.3][..]),
        (&[0.3][..], &[][..]),
        (&[][..], &[][..]),
    ] {
        let paths = tp_fp_histograms(dir.path(), "softmax", tp, fp).unwrap();
        let svg = assert_svg(&paths[0]);
        assert!(svg.contains("mean = n/a") && svg.contains("(n = 0)"));
    }
    no_temporaries(dir.path());
}

#[test]
fn pr_curves_name_every_class_and_its_ap() {
    let dir = tmp();
    let names = ["car".to_string(), "cyclist".into(), "pedestrian".into()];
    // Four rows; nobody is a pedestrian.
    let scores = [
        0.8, 0.1, 0.1, //
        0.35, 0.6, 0.05, //
        0.4, 0.3, 0.3, //
        0.1, 0.2, 0.7,
    ];
    let labels = [Some(0), Some(1), None, Some(0)];
    let paths = pr_curves(dir.path(), "ml", &names, &scores, &labels).unwrap();
    assert_eq!(paths, [dir.path().join("pr_ml.svg")]);
    let svg = assert_svg(&paths[0]);
    // car: scores 0.8+, 0.4-, 0.35-, 0.1+ -> AP = 0.5 * 1 + 0.5 * 0.5 = 0.75.
    assert!(svg.contains("car (AP = 0.7500)"), "{svg}");
    assert!(svg.contains("cyclist (AP = 1.0000)"), "{svg}");
    assert!(svg.contains("pedestrian (no positives)"), "{svg}");
}

#[test]
fn pr_by_class_overlays_the_methods() {
    let dir = tmp();
    let names = ["car", "ml"];
    let a = [0.9, 0.1, 0.2, 0.8, 0.6, 0.4];
    let b = [0.6, 0.4, 0.5, 0.5, 0.5, 0.5];
    let labels = [Some(0), Some(1), None];
    let methods: [(&str, &[f64]); 2] = [("ml", &a), ("map", &b)];
    let paths = pr_by_class(dir.path(), &names, &methods, &labels).unwrap();
    assert_eq!(
        paths,
        [
            dir.path().join("pr_car.svg"),
            dir.path().join("pr_class_ml.svg")
        ]
    );
    let svg = assert_svg(&paths[0]);
    assert!(svg.contains("ml (AP = 1.0000)") && svg.contains("map (AP = "));
    assert!(svg.contains("Precision-recall: car (1 positives of 3 rows)"));

    let bad: [(&str, &[f64]); 1] = [("map", &a[..5])];
    let err = pr_by_class(dir.path(), &names, &bad, &labels).unwrap_err();
    assert!(err.to_string().contains("method map"), "{err}");
    let err = pr_curves(dir.path(), "ml", &names, &a, &[Some(2), None, None]).unwrap_err();
    assert!(err.to_string().contains("label 2 of row 0"), "{err}");
}

#[test]
fn fitted_histograms_draw_both_heads() {
    let dir = tmp();
    let paths = fitted_histograms(dir.path(), &table()).unwrap();
    assert_eq!(
        paths,
        [
            dir.path().join("likelihood_ml.svg"),
            dir.path().join("likelihood_map.svg")
        ]
    );
    let ml = assert_svg(&paths[0]);
    assert!(ml.contains("ML head") && ml.contains("λ = 0.0055") && ml.contains("5 bins"));
    let map = assert_svg(&paths[1]);
    assert!(map.contains("MAP head") && map.contains("λ = 0.00012"));
    for svg in [&ml, &map] {
        for name in ["car", "cyclist", "pedestrian", "prior density", "frequency"] {
            assert!(svg.contains(name), "{name}");
        }
    }
    no_temporaries(dir.path());
}

#[test]
fn plot_all_writes_every_file() {
    let dir = tmp();
    let names = ["car", "cyclist", "pedestrian"];
    let ml = [0.7, 0.2, 0.1, 0.3, 0.3, 0.3, 0.1, 0.1, 0.8];
    let sm = [0.9, 0.05, 0.05, 0.1, 0.8, 0.1, 0.2, 0.2, 0.6];
    let labels = [Some(0), None, Some(2)];
    let methods: [(&str, &[f64]); 2] = [("ml", &ml), ("softmax", &sm)];
    let out = dir.path().join("nested").join("plots");
    let set = Scored {
        class_names: &names,
        methods: &methods,
        labels: &labels,
        logits: &[],
    };
    let paths = plot_all(&out, &set, &cfg(10), Some(&table())).unwrap();
    let mut files: Vec<String> = paths
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    files.sort();
    let want = [
        "likelihood_map.svg",
        "likelihood_ml.svg",
        "pr_car.svg",
        "pr_cyclist.svg",
        "pr_ml.svg",
        "pr_pedestrian.svg",
        "pr_softmax.svg",
        "reliability_ml.svg",
        "reliability_softmax.svg",
        "scores_ml.svg",
        "scores_softmax.svg",
    ];
    assert_eq!(files, want);
    for p in &paths {
        assert_svg(p);
    }
    no_temporaries(&out);
    let none = Scored {
        methods: &[],
        ..set
    };
    assert!(plot_all(&out, &none, &cfg(10), None).unwrap().is_empty());
}

#[test]
fn an_unwritable_directory_is_refused_with_its_path() {
    let base = tmp();
    let dir = unwritable(base.path());
    let errs = [
        reliability_diagram(&dir, "ml", &[outcome((0.5, true))], &cfg(10)).unwrap_err(),
        tp_fp_histograms(&dir, "ml", &[0.5], &[0.4]).unwrap_err(),
        pr_curves(&dir, "ml", &["a", "b"], &[0.5, 0.5], &[Some(0)]).unwrap_err(),
        pr_by_class(&dir, &["a", "b"], &[("ml", &[0.5, 0.5][..])], &[Some(0)]).unwrap_err(),
        fitted_histograms(&dir, &table()).unwrap_err(),
    ];
    for err in &errs {
        assert!(matches!(err, PlotError::Io { .. }), "{err}");
        assert_names_path(err, &dir);
        assert!(std::error::Error::source(err).is_some());
    }
}

#[test]
fn a_file_in_the_way_is_refused_with_its_path() {
    // The directory exists but the plot's name is taken by a directory.
    let dir = tmp();
    let target = dir.path().join("scores_ml.svg");
    fs::create_dir(&target).unwrap();
    let err = tp_fp_histograms(dir.path(), "ml", &[0.5], &[]).unwrap_err();
    assert!(matches!(err, PlotError::Io { .. }), "{err}");
    assert_eq!(err.path(), target);
    no_temporaries(dir.path());
}

#[test]
fn fitted_histograms_lay_out_more_classes_and_a_floored_prior() {
    let settings = *table().settings();
    let spec = |name, variance| ClassSpec {
        name,
        rows: 10,
        mean: 1.0,
        variance,
        ml_range: (0.5, 1.5),
        ml_freqs: vec![0.5, 0.5],
        map_range: (0.5, 1.5),
        map_freqs: vec![1.0],
    };
    let classes = ["a", "b", "c", "d", "e"]
        .into_iter()
        .map(|n| spec(n, 1.0))
        .chain([spec("constant", 1e-12)])
        .collect();
    let t = DynTable::new(settings, classes).unwrap();
    let dir = tmp();
    let paths = fitted_histograms(dir.path(), &t).unwrap();
    let svg = assert_svg(&paths[0]);
    assert!(
        svg.contains("constant (n = 10)") && svg.contains("1.00e-12"),
        "{svg}"
    );
}

#[test]
fn a_class_without_positives_is_named_in_every_legend() {
    let dir = tmp();
    let scores = [0.9, 0.1, 0.6, 0.4];
    let labels = [Some(0), None];
    let methods: [(&str, &[f64]); 2] = [("sigmoid", &scores), ("temperature", &scores)];
    let paths = pr_by_class(dir.path(), &["car", "cyclist"], &methods, &labels).unwrap();
    let svg = assert_svg(&paths[1]);
    assert!(svg.contains("sigmoid (no positives)"));
    assert!(svg.contains("temperature (no positives)"));
    assert!(svg.contains("0 positives of 2 rows"));
}
