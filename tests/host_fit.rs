//! `mlmap::host::fit`: golden tables, MATLAB's bin picker, widening, floors and errors.

use std::path::{Path, PathBuf};

use mlmap::host::dataset::{DataErrorKind, DataSource};
use mlmap::host::fit::{class_moments, fit, FitError, FitParams, TrainingSet};
use mlmap::host::DynTable;
use mlmap::{EdgeMode, UpperTail, VARIANCE_FLOOR};

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn train() -> DataSource {
    DataSource::open(&repo("examples/data/train.csv")).unwrap()
}

fn matlab() -> FitParams {
    FitParams {
        edges: EdgeMode::Matlab,
        ..FitParams::default()
    }
}

/// The ML and MAP heads alone (a version-1 table), as the v1 golden files hold.
fn no_bayes(p: FitParams) -> FitParams {
    FitParams { bayes: None, ..p }
}

/// Writes `text` as `data.csv` in a fresh temporary directory and opens it.
fn csv(text: &str) -> (tempfile::TempDir, DataSource) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("data.csv");
    std::fs::write(&path, text).unwrap();
    let src = DataSource::open(&path).unwrap();
    (dir, src)
}

/// A CSV of classes `a` and `b`: `a` rows have the logit `x` in column a, `b` rows the
/// logit `y` in column b (the other column holds a distracting constant).
fn two_classes(a: &[f64], b: &[f64]) -> String {
    let mut s = String::from("label,a,b\n");
    for x in a {
        s += &format!("a,{x},-99\n");
    }
    for y in b {
        s += &format!("b,99,{y}\n");
    }
    s
}

#[test]
fn linspace_fit_of_train_csv_equals_the_numpy_reference_byte_for_byte() {
    // tests/golden/train_linspace.mlmap was written by the independent numpy fit:
    //   python3 tools/mlmap_ref.py fit examples/data/train.csv tests/golden/train_linspace.mlmap
    let golden = std::fs::read(repo("tests/golden/train_linspace.mlmap")).unwrap();
    let params = no_bayes(FitParams::default());
    let table = fit(&train(), &params).unwrap();
    assert_eq!(table.to_vec().unwrap(), golden);
    let set = TrainingSet::read(&train()).unwrap();
    assert_eq!(set.fit(&params).unwrap(), table);
}

#[test]
fn default_fit_with_the_bayes_head_equals_the_numpy_reference_byte_for_byte() {
    // tests/golden/train_bayes.mlmap was written by the independent numpy fit, every
    // head with the defaults of `mlmap fit` (format version 3: the untuned open head):
    //   python3 tools/mlmap_ref.py fit examples/data/train.csv tests/golden/train_bayes.mlmap
    let golden = std::fs::read(repo("tests/golden/train_bayes.mlmap")).unwrap();
    assert_eq!(&golden[4..5], [3], "a version-3 file");
    let params = FitParams::default();
    let table = fit(&train(), &params).unwrap();
    assert_eq!(table.to_vec().unwrap(), golden);
    let set = TrainingSet::read(&train()).unwrap();
    assert_eq!(set.fit(&params).unwrap(), table);
    // Background rows make a fourth category; its prior is their share of the rows.
    let bayes = table.bayes_head().unwrap();
    assert_eq!(bayes.all_rows(), [11159, 1668, 3173, 4000]);
    assert_eq!((bayes.bins(), bayes.lambda()), (22, 1e-3));
    // Without the Bayes head, the same fit is the version-1 golden table.
    assert_eq!(
        table.without_bayes().to_vec().unwrap(),
        std::fs::read(repo("tests/golden/train_linspace.mlmap")).unwrap()
    );
}

#[test]
fn objectness_feature_fit_equals_the_numpy_reference_byte_for_byte() {
    // DESIGN §1.6's objectness feature (format version 4), written by the numpy fit:
    //   python3 tools/mlmap_ref.py fit --objectness-feature examples/data/train.csv \
    //       tests/golden/train_osf.mlmap
    let golden = std::fs::read(repo("tests/golden/train_osf.mlmap")).unwrap();
    assert_eq!(&golden[4..5], [4], "a version-4 file");
    let mut params = FitParams::default();
    if let Some(b) = params.bayes.as_mut() {
        b.objectness = true;
    }
    let table = fit(&train(), &params).unwrap();
    assert_eq!(table.to_vec().unwrap(), golden);
    let set = TrainingSet::read(&train()).unwrap();
    assert_eq!(set.fit(&params).unwrap(), table);
    let bayes = table.bayes_head().unwrap();
    assert_eq!(bayes.features(), 4);
    assert_eq!(bayes.objectness_terms().len(), 22 * 4);
    // Statistics do not hold the objectness: the feature needs the rows.
    let mut stats = mlmap::host::fit::FitStats::new(&["car", "cyclist", "pedestrian"]);
    train()
        .for_each_row(|row| {
            stats.push(&row);
            Ok::<(), mlmap::host::fit::FitError>(())
        })
        .unwrap();
    let err = stats.edges(&params).unwrap_err();
    assert!(err.to_string().contains("objectness"), "{err}");
}

#[test]
fn the_shipped_default_table_is_the_numpy_fit_of_the_shipped_training_data() {
    // tables/default.mlmap (embedded by build.rs unless MLMAP_TABLE says otherwise) is the
    // default fit of examples/data/train.csv: the very bytes the independent numpy fit
    // wrote to tests/golden/train_bayes.mlmap.
    let shipped = std::fs::read(repo("tables/default.mlmap")).unwrap();
    let golden = std::fs::read(repo("tests/golden/train_bayes.mlmap")).unwrap();
    assert_eq!(shipped, golden);
}

#[test]
fn matlab_fit_of_train_csv_equals_the_python_reference_byte_for_byte() {
    // tests/golden/train_matlab.mlmap was written by a Python bin picker:
    //   python3 tools/matlab_fit_ref.py examples/data/train.csv tests/golden/train_matlab.mlmap
    let golden = std::fs::read(repo("tests/golden/train_matlab.mlmap")).unwrap();
    let table = fit(&train(), &no_bayes(matlab())).unwrap();
    assert_eq!(table.to_vec().unwrap(), golden);
    assert_eq!(table.settings().edge_mode, EdgeMode::Matlab);
    let set = TrainingSet::read(&train()).unwrap();
    assert_eq!(set.fit(&no_bayes(matlab())).unwrap(), table);
}

#[test]
fn matlab_edges_of_mathworks_histcounts_example() {
    // MathWorks' histcounts documentation, "Specify Number of Bins":
    //   X = [2 3 5 7 11 13 17 19 23 29]; [N,edges] = histcounts(X,6)
    //   N = 2 2 2 2 1 1, edges = 0 4.9 9.8 14.7 19.6 24.5 29.4
    // With 3 bins (worked by hand in host/src/fit/binpicker.rs): edges 0 10 20 30,
    // N = 4 4 2.
    let primes = [2.0, 3.0, 5.0, 7.0, 11.0, 13.0, 17.0, 19.0, 23.0, 29.0];
    let (_dir, src) = csv(&two_classes(&primes, &[1.0, 2.0]));
    let params = FitParams {
        bins_ml: 6,
        bins_map: 3,
        ..matlab()
    };
    let table = fit(&src, &params).unwrap();
    let ml = &table.ml_histograms()[0];
    assert_eq!((ml.lo(), ml.hi()), (0.0, 29.4));
    let edges: Vec<f32> = (0..=6).map(|k| ml.edge(k)).collect();
    for (got, want) in edges.iter().zip([0.0, 4.9, 9.8, 14.7, 19.6, 24.5, 29.4]) {
        assert!((got - want).abs() < 1e-5, "edge {got}, want {want}");
    }
    assert_eq!(ml.frequencies(), [0.2, 0.2, 0.2, 0.2, 0.1, 0.1]);
    let map = &table.map_histograms()[0];
    assert_eq!((map.lo(), map.hi()), (0.0, 30.0));
    assert_eq!(map.frequencies(), [0.4, 0.4, 0.2]);
}

#[test]
fn linspace_edges_span_min_to_max() {
    let (_dir, src) = csv(&two_classes(&[-1.0, 0.0, 0.5, 3.0], &[1.0, 2.0]));
    let params = FitParams {
        bins_ml: 4,
        bins_map: 2,
        ..FitParams::default()
    };
    let table = fit(&src, &params).unwrap();
    let ml = &table.ml_histograms()[0];
    // Edges -1, 0, 1, 2, 3: 0 opens bin 1, 3 closes the last bin.
    assert_eq!((ml.lo(), ml.hi()), (-1.0, 3.0));
    assert_eq!(ml.frequencies(), [0.25, 0.5, 0.0, 0.25]);
    assert_eq!(table.map_histograms()[0].frequencies(), [0.75, 0.25]);
    assert_eq!(table.rows(), [4, 2]);
}

#[test]
fn constant_class_is_widened_and_its_variance_floored() {
    let (_dir, src) = csv(&two_classes(&[2.0, 2.0, 2.0], &[1.0, 2.0, 4.0]));
    for (edges, range) in [
        (EdgeMode::Linspace, (1.5, 2.5)),
        // MATLAB: floor(2 (2 - 1/4)) / 2 = 1.5, ceil(2 (2 + 1/4)) / 2 = 2.5.
        (EdgeMode::Matlab, (1.5, 2.5)),
    ] {
        let table = fit(
            &src,
            &FitParams {
                edges,
                ..FitParams::default()
            },
        )
        .unwrap();
        for h in [&table.ml_histograms()[0], &table.map_histograms()[0]] {
            assert_eq!((h.lo(), h.hi()), range, "{edges:?}");
            let k = h.bin(2.0).unwrap();
            assert_eq!(h.frequencies()[k], 1.0, "{edges:?}");
            assert_eq!(h.frequencies().iter().sum::<f32>(), 1.0);
        }
        let prior = table.priors()[0];
        assert_eq!(prior.mean(), 2.0);
        assert_eq!(prior.variance(), VARIANCE_FLOOR as f32);
        // Class b: sample variance of 1, 2, 4 (ddof = 1) is 7/3.
        assert_eq!(table.priors()[1].variance(), (7.0f64 / 3.0) as f32);
    }
}

#[test]
fn a_single_row_class_gets_the_variance_floor() {
    let (_dir, src) = csv(&two_classes(&[0.7], &[1.0, 2.0]));
    let table = fit(&src, &FitParams::default()).unwrap();
    assert_eq!(table.priors()[0].variance(), VARIANCE_FLOOR as f32);
    assert_eq!(table.priors()[0].mean(), 0.7);
    assert_eq!(table.rows(), [1, 2]);
}

#[test]
fn background_and_unlabelled_rows_are_not_used() {
    let base = two_classes(&[0.5, 1.5, 2.0], &[-1.0, 3.0]);
    let (_d1, plain) = csv(&base);
    let noisy = format!("{base}background,50,50\n,-50,-50\nbackground,-7,8\n");
    let (_d2, with_fp) = csv(&noisy);
    // The ML and MAP heads ignore them; the Bayes head learns a background category
    // from the background rows only.
    for params in [FitParams::default(), matlab()] {
        let (a, b) = (
            fit(&plain, &params).unwrap(),
            fit(&with_fp, &params).unwrap(),
        );
        assert_eq!(a.clone().without_bayes(), b.clone().without_bayes());
        assert_eq!(a.bayes_head().unwrap().all_rows(), [3, 2]);
        assert_eq!(b.bayes_head().unwrap().all_rows(), [3, 2, 2]);
    }
}

#[test]
fn only_the_column_of_the_label_counts() {
    // Row "a" has a huge logit in column b: it must not widen class b's range.
    let (_dir, src) = csv("label,a,b\na,1,1000\na,2,1000\nb,-5,3\nb,-5,4\n");
    let table = fit(&src, &FitParams::default()).unwrap();
    let b = &table.ml_histograms()[1];
    assert_eq!((b.lo(), b.hi()), (3.0, 4.0));
    assert_eq!(table.priors()[1].mean(), 3.5);
}

#[test]
fn a_class_without_rows_is_an_error_naming_the_class_and_file() {
    let (_dir, src) = csv("label,car,cyclist,pedestrian\ncar,1,2,3\nbackground,1,2,3\n");
    let err = fit(&src, &FitParams::default()).unwrap_err();
    assert_eq!(
        err,
        FitError::EmptyClasses {
            path: src.path().to_path_buf(),
            classes: vec!["cyclist".into(), "pedestrian".into()],
        }
    );
    let shown = err.to_string();
    assert!(shown.contains(&src.path().display().to_string()), "{shown}");
    assert!(shown.contains("\"cyclist\""), "{shown}");
    assert!(err.is_bad_input());
    assert!(matches!(
        TrainingSet::read(&src),
        Err(FitError::EmptyClasses { .. })
    ));
}

#[test]
fn unlabelled_data_cannot_be_fitted() {
    let (_dir, src) = csv("a,b\n1,2\n");
    assert_eq!(
        fit(&src, &FitParams::default()),
        Err(FitError::NoLabels {
            path: src.path().to_path_buf()
        })
    );
}

#[test]
fn data_errors_surface_from_either_pass() {
    let (_dir, src) = csv("label,a,b\na,1,2\nb,1,oops\n");
    match fit(&src, &FitParams::default()) {
        Err(FitError::Data(e)) => {
            assert_eq!(e.line(), Some(3));
            assert!(e.is_bad_input());
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn ranges_a_table_cannot_hold_are_refused() {
    // 1e6 and 1e6 + 0.1: 100 bins of width 1e-3 are below the f32 spacing at 1e6.
    let (_dir, src) = csv(&two_classes(&[1e6, 1e6 + 0.1], &[1.0, 2.0]));
    let params = FitParams {
        bins_ml: 100,
        ..FitParams::default()
    };
    assert!(matches!(
        fit(&src, &params),
        Err(FitError::Edges { ref class, bins: 100, .. }) if class == "a"
    ));
    // Logits beyond f32 are refused by the reader, with their line and column.
    let (_dir, src) = csv(&two_classes(&[1e39, 2e39], &[1.0, 2.0]));
    match fit(&src, &FitParams::default()) {
        Err(FitError::Data(e)) => {
            assert!(matches!(e.kind(), DataErrorKind::OutOfF32 { .. }), "{e}");
            assert_eq!(e.line(), Some(2), "{e}");
            assert_eq!(e.column(), Some("a"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    // Logits within f32 whose range a histogram cannot split.
    let (_dir, src) = csv(&two_classes(&[3e38, -3e38], &[1.0, 2.0]));
    assert!(matches!(
        fit(&src, &FitParams::default()),
        Err(FitError::Edges { ref class, .. }) if class == "a"
    ));
}

#[test]
fn upper_tail_and_lambdas_are_recorded() {
    let params = FitParams {
        lambda_ml: 0.25,
        lambda_map: 1e-8,
        upper_tail: UpperTail::Clamp,
        ..FitParams::default()
    };
    let table = fit(&train(), &params).unwrap();
    let s = table.settings();
    assert_eq!(s.upper_tail, UpperTail::Clamp);
    assert_eq!((s.lambda_ml, s.lambda_map), (0.25, 1e-8));
    assert_eq!(
        DynTable::from_bytes(&table.to_vec().unwrap()).unwrap(),
        table
    );
}

#[test]
fn every_training_value_has_a_likelihood_and_frequencies_sum_to_one() {
    let set = TrainingSet::read(&train()).unwrap();
    for params in [FitParams::default(), matlab()] {
        let table = set.fit(&params).unwrap();
        for c in 0..table.k() {
            let values = set.values(c).unwrap();
            assert_eq!(values.len() as u64, table.rows()[c]);
            for h in [&table.ml_histograms()[c], &table.map_histograms()[c]] {
                let sum: f64 = h.frequencies().iter().map(|&f| f64::from(f)).sum();
                assert!((sum - 1.0).abs() < 1e-6, "{sum}");
                for &v in values {
                    assert!(h.likelihood(v, UpperTail::Zero) > 0.0, "class {c}: {v}");
                }
            }
        }
    }
}

#[test]
fn streaming_and_in_memory_fits_agree_for_many_bin_counts() {
    let src = train();
    let set = TrainingSet::read(&src).unwrap();
    assert_eq!(set.moments(), class_moments(&src).unwrap());
    for edges in [EdgeMode::Linspace, EdgeMode::Matlab] {
        for (bins_ml, bins_map) in [(1, 2), (5, 64), (40, 9), (200, 3)] {
            let params = FitParams {
                bins_ml,
                bins_map,
                edges,
                ..FitParams::default()
            };
            assert_eq!(
                fit(&src, &params).unwrap(),
                set.fit(&params).unwrap(),
                "{params:?}"
            );
            let hists = set.histograms(bins_ml, edges).unwrap();
            for (h, m) in hists.iter().zip(set.moments()) {
                assert_eq!(h.total(), m.count());
                assert_eq!(h.bins(), bins_ml);
            }
        }
    }
}
