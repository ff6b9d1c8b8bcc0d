//! The SVG plots of `mlmap eval --plots DIR` (metrics of DESIGN §1.5).
//!
//! * [`reliability_diagram`]: accuracy per confidence bin against the diagonal, with the
//!   ECE in the title and the rows per bin in a second panel.
//! * [`tp_fp_histograms`]: the final scores of true and false positives, as the paper's
//!   Figs. 8–9.
//! * [`pr_curves`] and [`pr_by_class`]: precision-recall curves, per method (one curve
//!   per class) and per class (one curve per method), with the average precision of
//!   DESIGN §1.5 in the legend.
//! * [`fitted_histograms`]: the fitted likelihood histograms of both heads with the
//!   Gaussian priors, one panel per class, as the paper's Figs. 5–6.
//! * [`plot_all`]: all of the above from one set of scores.
//!
//! The API takes plain data (slices of `f64`, labels, a [`DynTable`]), so callers need
//! not know the renderer. Every function creates `dir` if needed, renders in memory and
//! writes each file atomically (a temporary file in `dir`, then a rename), and returns
//! the paths it wrote. Text is written as SVG `<text>` elements: no font is needed to
//! write the plots, only to view them.
//!
//! A method keeps its colour in every plot (`sigmoid`, `softmax`, `temperature`, `ml`,
//! `map`, and a fixed fallback for any other name), and so does a class (by index).

mod draw;
mod stats;

use std::fmt;
use std::format;
use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::string::{String, ToString};
use std::vec;
use std::vec::Vec;

use self::draw::{class_color, method_color, Colour, LikelihoodPanel};
use self::stats::{
    column, confidence_and_correct, ece, ece_label, pr_curve, reliability_bins, PrCurve, ScoreHist,
};
use crate::host::DynTable;
use crate::Histogram;

/// Bins of the score histograms of [`tp_fp_histograms`], on `[0, 1]`.
pub const SCORE_BINS: usize = 20;

/// A plot that could not be written; every variant names the file (or directory).
#[derive(Debug)]
#[non_exhaustive]
pub enum PlotError {
    /// The inputs do not describe the plot: lengths that disagree, a label outside the
    /// classes, a score that is not finite, or zero bins.
    Input {
        /// The plot that was to be written.
        path: PathBuf,
        /// What is wrong with the inputs.
        reason: String,
    },
    /// The renderer failed.
    Render {
        /// The plot that was being drawn.
        path: PathBuf,
        /// The renderer's message.
        reason: String,
    },
    /// The directory could not be created or the file could not be written.
    Io {
        /// The directory or file involved.
        path: PathBuf,
        /// The operating system's error.
        source: io::Error,
    },
}

impl PlotError {
    /// The file or directory the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Input { path, .. } | Self::Render { path, .. } | Self::Io { path, .. } => path,
        }
    }
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Input { path, reason } => {
                write!(f, "{}: cannot plot: {reason}", path.display())
            }
            Self::Render { path, reason } => {
                write!(f, "{}: cannot draw: {reason}", path.display())
            }
            Self::Io { path, source } => write!(f, "{}: cannot write: {source}", path.display()),
        }
    }
}

impl std::error::Error for PlotError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Public API
// ---------------------------------------------------------------------------------------

/// Writes `reliability_<method>.svg`: the accuracy of each confidence bin against the
/// diagonal, the gap to the bin's mean confidence shaded, the ECE in the title, and the
/// rows per bin in a lower panel.
///
/// `conf[i]` is the confidence of row `i` (its largest score) and `correct[i]` whether
/// it is a true positive (DESIGN §1.5). The `bins` bins are `((m-1)/M, m/M]` with the
/// edges computed in `f64` as `m / M`, confidence 0 (and below) in the first bin and
/// above 1 in the last, as the default ECE of DESIGN §1.5; the title shows
/// `ECE = ` with four decimals, or `n/a` without rows.
///
/// # Errors
///
/// [`PlotError::Input`] when the slices differ in length, `bins` is 0 or a confidence is
/// not finite; [`PlotError::Io`] when `dir` or the file cannot be written.
pub fn reliability_diagram(
    dir: &Path,
    method: &str,
    conf: &[f64],
    correct: &[bool],
    bins: usize,
) -> Result<Vec<PathBuf>, PlotError> {
    let path = dir.join(format!("reliability_{}.svg", file_stem(method)));
    if conf.len() != correct.len() {
        return Err(input(
            &path,
            format!(
                "{} confidences but {} correctness flags",
                conf.len(),
                correct.len()
            ),
        ));
    }
    if bins == 0 {
        return Err(input(
            &path,
            "the reliability diagram needs at least one bin",
        ));
    }
    check_finite(&path, "confidence", conf)?;
    ensure_dir(dir)?;
    let stats = reliability_bins(conf, correct, bins);
    let title = format!(
        "Reliability: {method} ({}, n = {})",
        ece_label(ece(&stats)),
        conf.len()
    );
    let svg = draw::reliability_svg(&path, &title, &stats, method_color(method))?;
    write_atomic(&path, &svg)?;
    Ok(vec![path])
}

/// Writes `scores_<method>.svg`: histograms of the final scores (confidences) of the
/// true positives and of the false positives, side by side, [`SCORE_BINS`] bins on
/// `[0, 1]`, with the number of rows and the mean in each legend (the paper's Figs. 8–9).
///
/// A bin is `[k/20, (k+1)/20)`, the last one closed, as `numpy.histogram`; scores
/// outside `[0, 1]` are counted in the nearest bin. An empty set draws an empty panel
/// whose mean is `n/a`.
///
/// # Errors
///
/// [`PlotError::Input`] when a score is not finite; [`PlotError::Io`] when `dir` or the
/// file cannot be written.
pub fn tp_fp_histograms(
    dir: &Path,
    method: &str,
    conf_tp: &[f64],
    conf_fp: &[f64],
) -> Result<Vec<PathBuf>, PlotError> {
    let path = dir.join(format!("scores_{}.svg", file_stem(method)));
    check_finite(&path, "true-positive score", conf_tp)?;
    check_finite(&path, "false-positive score", conf_fp)?;
    ensure_dir(dir)?;
    let tp = ScoreHist::new(conf_tp);
    let fp = ScoreHist::new(conf_fp);
    let title = format!("Scores of true and false positives: {method}");
    let svg = draw::scores_svg(&path, &title, &tp, &fp, method_color(method))?;
    write_atomic(&path, &svg)?;
    Ok(vec![path])
}

/// Writes `pr_<method>.svg`: one precision-recall curve per class for one method, with
/// each class's average precision in the legend.
///
/// `scores` holds N rows of K scores (row-major, K = `class_names.len()`) and `labels`
/// the N labels (`None` for background). For class `c` the positives are the rows
/// labelled `c`, ranked by score `c`; precision and recall are taken at every distinct
/// score, and AP is `sum_n (R_n - R_{n-1}) P_n`, the step-wise area that
/// `sklearn.metrics.average_precision_score` computes (DESIGN §1.5). A class without
/// positives has no curve and `no positives` in the legend.
///
/// # Errors
///
/// [`PlotError::Input`] when the shapes disagree, a label is not a class or a score is
/// not finite; [`PlotError::Io`] when `dir` or the file cannot be written.
pub fn pr_curves<S: AsRef<str>>(
    dir: &Path,
    method: &str,
    class_names: &[S],
    scores: &[f64],
    labels: &[Option<usize>],
) -> Result<Vec<PathBuf>, PlotError> {
    let path = dir.join(format!("pr_{}.svg", file_stem(method)));
    let k = class_names.len();
    check_matrix(&path, k, scores, labels)?;
    ensure_dir(dir)?;
    let curves: Vec<(String, Colour, PrCurve)> = class_names
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let curve = pr_curve(column(scores, k, c), labels, c);
            (name.as_ref().to_string(), class_color(c), curve)
        })
        .collect();
    let title = format!("Precision-recall per class: {method}");
    let svg = draw::pr_svg(&path, &title, &curves)?;
    write_atomic(&path, &svg)?;
    Ok(vec![path])
}

/// Writes one `pr_<class>.svg` per class: the precision-recall curves of every method
/// for that class, with their average precisions in the legend (see [`pr_curves`] for
/// the definitions).
///
/// `methods` pairs each method's name with its N x K row-major scores. A class whose
/// file name would be that of a method's [`pr_curves`] file (a class named `ml`, say)
/// is written as `pr_class_<class>.svg` instead, and two classes whose names give the
/// same file name get their index appended.
///
/// # Errors
///
/// As [`pr_curves`], for any method.
pub fn pr_by_class<S: AsRef<str>>(
    dir: &Path,
    class_names: &[S],
    methods: &[(&str, &[f64])],
    labels: &[Option<usize>],
) -> Result<Vec<PathBuf>, PlotError> {
    let k = class_names.len();
    let stems = class_stems(class_names, methods.iter().map(|(m, _)| *m));
    for (method, scores) in methods {
        let path = dir.join(format!("pr_{}.svg", file_stem(method)));
        check_matrix(&path, k, scores, labels).map_err(|e| match e {
            PlotError::Input { path, reason } => PlotError::Input {
                path,
                reason: format!("method {method}: {reason}"),
            },
            other => other,
        })?;
    }
    ensure_dir(dir)?;
    let mut written = Vec::with_capacity(k);
    for (c, (name, stem)) in class_names.iter().zip(&stems).enumerate() {
        let name = name.as_ref();
        let path = dir.join(format!("{stem}.svg"));
        let curves: Vec<(String, Colour, PrCurve)> = methods
            .iter()
            .map(|(method, scores)| {
                let curve = pr_curve(column(scores, k, c), labels, c);
                ((*method).to_string(), method_color(method), curve)
            })
            .collect();
        let positives = labels.iter().filter(|l| **l == Some(c)).count();
        let title = format!(
            "Precision-recall: {name} ({positives} positives of {} rows)",
            labels.len()
        );
        let svg = draw::pr_svg(&path, &title, &curves)?;
        write_atomic(&path, &svg)?;
        written.push(path);
    }
    Ok(written)
}

/// Writes `likelihood_ml.svg` and `likelihood_map.svg`: for each head, one panel per
/// class with the normalised histogram of the table (bars over the bin edges, left
/// axis "frequency") and the class's Gaussian prior (curve, right axis "prior
/// density"), as the paper's Figs. 5–6.
///
/// The ML head does not use the prior; it is drawn there too, for comparison.
///
/// # Errors
///
/// [`PlotError::Io`] when `dir` or a file cannot be written.
pub fn fitted_histograms(dir: &Path, table: &DynTable) -> Result<Vec<PathBuf>, PlotError> {
    ensure_dir(dir)?;
    let settings = table.settings();
    let heads = [
        (
            "likelihood_ml.svg",
            "ML",
            table.ml_histograms(),
            settings.lambda_ml,
        ),
        (
            "likelihood_map.svg",
            "MAP",
            table.map_histograms(),
            settings.lambda_map,
        ),
    ];
    let mut written = Vec::with_capacity(heads.len());
    for (file, head, hists, lambda) in heads {
        let path = dir.join(file);
        let bins = hists.first().map_or(0, Histogram::bins);
        let title = format!(
            "{head} head: likelihood histograms ({bins} bins, λ = {lambda}) and Gaussian priors"
        );
        let panels: Vec<LikelihoodPanel<'_>> = table
            .class_names()
            .zip(hists)
            .zip(table.priors())
            .zip(table.rows())
            .enumerate()
            .map(|(c, (((name, hist), prior), rows))| LikelihoodPanel {
                name,
                rows: *rows,
                hist,
                prior,
                color: class_color(c),
            })
            .collect();
        let svg = draw::likelihood_svg(&path, &title, &panels)?;
        write_atomic(&path, &svg)?;
        written.push(path);
    }
    Ok(written)
}

/// Writes every plot of an evaluation into `dir` and returns the paths written.
///
/// For each method of `methods` (name, N x K row-major final scores): its
/// [`reliability_diagram`] with `bins` bins, its [`tp_fp_histograms`] and its
/// [`pr_curves`]; then [`pr_by_class`] over all methods and, when a table is given,
/// [`fitted_histograms`]. Confidence and correctness follow DESIGN §1.5: `conf` is the
/// largest score of a row, and a row is a true positive when its label is a class and
/// its argmax (lowest index on ties) equals it.
///
/// # Errors
///
/// The first error of the functions above; the files written before it stay.
pub fn plot_all<S: AsRef<str>>(
    dir: &Path,
    class_names: &[S],
    methods: &[(&str, &[f64])],
    labels: &[Option<usize>],
    bins: usize,
    table: Option<&DynTable>,
) -> Result<Vec<PathBuf>, PlotError> {
    let k = class_names.len();
    let mut written = Vec::new();
    for (method, scores) in methods {
        let path = dir.join(format!("reliability_{}.svg", file_stem(method)));
        check_matrix(&path, k, scores, labels)?;
        let (conf, correct) = confidence_and_correct(scores, k, labels);
        written.extend(reliability_diagram(dir, method, &conf, &correct, bins)?);
        let (mut tp, mut fp) = (Vec::new(), Vec::new());
        for (&c, &ok) in conf.iter().zip(&correct) {
            if ok {
                tp.push(c)
            } else {
                fp.push(c)
            }
        }
        written.extend(tp_fp_histograms(dir, method, &tp, &fp)?);
        written.extend(pr_curves(dir, method, class_names, scores, labels)?);
    }
    if !methods.is_empty() {
        written.extend(pr_by_class(dir, class_names, methods, labels)?);
    }
    if let Some(table) = table {
        written.extend(fitted_histograms(dir, table)?);
    }
    Ok(written)
}

// ---------------------------------------------------------------------------------------
// Input checks, file names, writing
// ---------------------------------------------------------------------------------------

fn input(path: &Path, reason: impl Into<String>) -> PlotError {
    PlotError::Input {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

fn check_finite(path: &Path, what: &str, values: &[f64]) -> Result<(), PlotError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(input(path, format!("{what} {i} is not finite"))),
        None => Ok(()),
    }
}

/// Checks an N x K score matrix and its N labels.
fn check_matrix(
    path: &Path,
    k: usize,
    scores: &[f64],
    labels: &[Option<usize>],
) -> Result<(), PlotError> {
    if k == 0 {
        return Err(input(path, "no classes"));
    }
    if labels.len().checked_mul(k) != Some(scores.len()) {
        return Err(input(
            path,
            format!(
                "{} scores are not {} rows of {k} classes",
                scores.len(),
                labels.len()
            ),
        ));
    }
    if let Some(i) = scores.iter().position(|v| !v.is_finite()) {
        return Err(input(
            path,
            format!("score of row {}, class {} is not finite", i / k, i % k),
        ));
    }
    if let Some((row, c)) = labels
        .iter()
        .enumerate()
        .find_map(|(row, l)| l.filter(|c| *c >= k).map(|c| (row, c)))
    {
        return Err(input(
            path,
            format!("label {c} of row {row} is not one of the {k} classes"),
        ));
    }
    Ok(())
}

/// A file-name-safe form of a method or class name: ASCII letters, digits, `-`, `_`
/// and inner `.` are kept, anything else becomes `_`.
fn file_stem(name: &str) -> String {
    let stem: String = name
        .chars()
        .enumerate()
        .map(|(i, ch)| {
            if ch.is_ascii_alphanumeric() || ch == '-' || ch == '_' || (ch == '.' && i > 0) {
                ch
            } else {
                '_'
            }
        })
        .collect();
    if stem.is_empty() {
        "unnamed".to_string()
    } else {
        stem
    }
}

/// The file stems of [`pr_by_class`]: `pr_<class>`, or `pr_class_<class>` when that
/// is a method's `pr_<method>`, with `_<index>` appended to a repeated stem.
fn class_stems<'m, S: AsRef<str>>(
    class_names: &[S],
    methods: impl Iterator<Item = &'m str>,
) -> Vec<String> {
    let method_stems: Vec<String> = methods.map(|m| format!("pr_{}", file_stem(m))).collect();
    let mut stems: Vec<String> = Vec::with_capacity(class_names.len());
    for (c, name) in class_names.iter().enumerate() {
        let plain = file_stem(name.as_ref());
        let mut stem = format!("pr_{plain}");
        if method_stems.contains(&stem) {
            stem = format!("pr_class_{plain}");
        }
        if stems.contains(&stem) || method_stems.contains(&stem) {
            stem = format!("{stem}_{c}");
        }
        stems.push(stem);
    }
    stems
}

fn ensure_dir(dir: &Path) -> Result<(), PlotError> {
    fs::create_dir_all(dir).map_err(|source| PlotError::Io {
        path: dir.to_path_buf(),
        source,
    })
}

/// Writes `contents` to a temporary file next to `path`, then renames it into place,
/// so a reader never sees a partial plot; the temporary file is removed on failure.
fn write_atomic(path: &Path, contents: &str) -> Result<(), PlotError> {
    let name = path
        .file_name()
        .map_or_else(|| "plot".into(), |n| n.to_string_lossy());
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| -> io::Result<()> {
        let mut file = fs::File::create(&tmp)?;
        file.write_all(contents.as_bytes())?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    result.map_err(|source| {
        // Best effort: the file may not exist.
        let _ = fs::remove_file(&tmp);
        PlotError::Io {
            path: path.to_path_buf(),
            source,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ClassSpec, EdgeMode, Settings, UpperTail};

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

    #[test]
    fn reliability_diagram_shows_the_ece() {
        let dir = tmp();
        // Bin (0.9, 1]: acc 0.5, conf 0.95; bin (0.5, 0.6]: acc 1, conf 0.6.
        // ECE = 0.5 * 0.45 + 0.5 * 0.4 = 0.425.
        let conf = [0.95, 0.95, 0.6, 0.6];
        let correct = [true, false, true, true];
        let stats = reliability_bins(&conf, &correct, 10);
        let e = ece(&stats).unwrap();
        assert!((e - 0.425).abs() < 1e-12, "{e}");
        let paths = reliability_diagram(dir.path(), "ml", &conf, &correct, 10).unwrap();
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
        let paths = reliability_diagram(dir.path(), "map", &[], &[], 10).unwrap();
        assert!(assert_svg(&paths[0]).contains("ECE = n/a"));

        let err = reliability_diagram(dir.path(), "map", &[0.5], &[], 10).unwrap_err();
        assert!(matches!(err, PlotError::Input { .. }));
        assert_names_path(&err, &dir.path().join("reliability_map.svg"));
        let err = reliability_diagram(dir.path(), "map", &[0.5], &[true], 0).unwrap_err();
        assert!(matches!(err, PlotError::Input { .. }));
        let err = reliability_diagram(dir.path(), "map", &[f64::NAN], &[true], 10).unwrap_err();
        assert!(err.to_string().contains("not finite"), "{err}");
    }

    #[test]
    fn score_histograms_have_means_in_the_legend() {
        let dir = tmp();
        let paths =
            tp_fp_histograms(dir.path(), "softmax", &[0.9, 0.8, 0.85], &[0.99, 0.2]).unwrap();
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
        let paths = plot_all(&out, &names, &methods, &labels, 10, Some(&table())).unwrap();
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
        assert!(plot_all(&out, &names, &[], &labels, 10, None)
            .unwrap()
            .is_empty());
    }

    #[test]
    fn an_unwritable_directory_is_refused_with_its_path() {
        let base = tmp();
        let dir = unwritable(base.path());
        let errs = [
            reliability_diagram(&dir, "ml", &[0.5], &[true], 10).unwrap_err(),
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
}
