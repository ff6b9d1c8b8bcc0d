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
//! `map`, `bayes`, and a fixed fallback for any other name), and so does a class (by index).

mod draw;
mod stats;

use std::borrow::Cow;
use std::fmt;
use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use self::draw::{class_color, method_color, Colour, LikelihoodPanel};
use self::stats::{ece_label, pr_curve, PrCurve, ScoreHist};
use crate::escape::visible;
use crate::metrics::{self, MetricsConfig, MetricsError, Outcome};
use crate::DynTable;
use mlmap_core::Histogram;

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
/// `outcomes` are the rows' confidences and correctness (DESIGN §1.5, from
/// [`metrics::outcomes_with_logits`]); the bins and the ECE are those of
/// [`metrics::reliability`] with `cfg` (bin count and convention). The title shows
/// `ECE = ` with four decimals, or `n/a` without rows.
///
/// # Errors
///
/// [`PlotError::Input`] when the number of bins is 0 or too large or a confidence is
/// not finite; [`PlotError::Io`] when `dir` or the file cannot be written.
pub fn reliability_diagram(
    dir: &Path,
    method: &str,
    outcomes: &[Outcome],
    cfg: &MetricsConfig,
) -> Result<Vec<PathBuf>, PlotError> {
    let path = dir.join(format!("reliability_{}.svg", file_stem(method)));
    if cfg.bins == 0 {
        return Err(input(
            &path,
            "the reliability diagram needs at least one bin",
        ));
    }
    if let Some(i) = outcomes.iter().position(|o| !o.conf.is_finite()) {
        return Err(input(&path, format!("confidence {i} is not finite")));
    }
    let rel = metrics::reliability(outcomes, cfg).map_err(|e| input(&path, e.to_string()))?;
    ensure_dir(dir)?;
    let title = format!(
        "Reliability: {method} ({}, n = {})",
        ece_label(rel.ece),
        outcomes.len()
    );
    let svg = draw::reliability_svg(&path, &title, &rel.bins, method_color(method))?;
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
    let curves = class_names
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let curve = class_curve(&path, scores, k, labels, c)?;
            Ok((visible(name.as_ref()).into_owned(), class_color(c), curve))
        })
        .collect::<Result<Vec<(String, Colour, PrCurve)>, PlotError>>()?;
    ensure_dir(dir)?;
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
        let name = visible(name.as_ref());
        let path = dir.join(format!("{stem}.svg"));
        let curves = methods
            .iter()
            .map(|(method, scores)| {
                let curve = class_curve(&path, scores, k, labels, c)?;
                Ok(((*method).to_string(), method_color(method), curve))
            })
            .collect::<Result<Vec<(String, Colour, PrCurve)>, PlotError>>()?;
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
    // Names are SVG text: control characters (which XML cannot hold) made visible.
    let shown: Vec<Cow<'_, str>> = table.class_names().map(visible).collect();
    for (file, head, hists, lambda) in heads {
        let path = dir.join(file);
        let bins = hists.first().map_or(0, Histogram::bins);
        let title = format!(
            "{head} head: likelihood histograms ({bins} bins, λ = {lambda}) and Gaussian priors"
        );
        let panels: Vec<LikelihoodPanel<'_>> = shown
            .iter()
            .map(AsRef::as_ref)
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

/// The scores of every method on one labelled set, as [`plot_all`] takes them.
#[derive(Debug, Clone, Copy)]
pub struct Scored<'a, S> {
    /// Class names; `K` is their number.
    pub class_names: &'a [S],
    /// Each method's name and `N x K` row-major final scores.
    pub methods: &'a [(&'a str, &'a [f64])],
    /// The `N` labels (`None` for background).
    pub labels: &'a [Option<usize>],
    /// The `N x K` logits that decide ties (DESIGN §1.7), or empty.
    pub logits: &'a [f64],
}

/// Writes every plot of an evaluation into `dir` and returns the paths written.
///
/// For each method of `set.methods`: its [`reliability_diagram`] binned as `cfg`
/// says, its [`tp_fp_histograms`] and its [`pr_curves`]; then [`pr_by_class`] over all
/// methods and, when a table is given, [`fitted_histograms`]. Confidence and
/// correctness are those of the metrics ([`metrics::outcomes_with_logits`]).
///
/// # Errors
///
/// The first error of the functions above; the files written before it stay.
pub fn plot_all<S: AsRef<str>>(
    dir: &Path,
    set: &Scored<'_, S>,
    cfg: &MetricsConfig,
    table: Option<&DynTable>,
) -> Result<Vec<PathBuf>, PlotError> {
    let k = set.class_names.len();
    let mut written = Vec::new();
    for (method, scores) in set.methods {
        let path = dir.join(format!("reliability_{}.svg", file_stem(method)));
        check_matrix(&path, k, scores, set.labels)?;
        let outcomes = match metrics::outcomes_with_logits(scores, set.logits, k, set.labels) {
            Ok(outcomes) => outcomes,
            Err(MetricsError::Empty) => Vec::new(),
            Err(e) => return Err(input(&path, e.to_string())),
        };
        written.extend(reliability_diagram(dir, method, &outcomes, cfg)?);
        let (mut tp, mut fp) = (Vec::new(), Vec::new());
        for o in &outcomes {
            if o.correct {
                tp.push(o.conf)
            } else {
                fp.push(o.conf)
            }
        }
        written.extend(tp_fp_histograms(dir, method, &tp, &fp)?);
        written.extend(pr_curves(dir, method, set.class_names, scores, set.labels)?);
    }
    if !set.methods.is_empty() {
        written.extend(pr_by_class(dir, set.class_names, set.methods, set.labels)?);
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

/// The drawn precision-recall curve of class `c` (scores checked by [`check_matrix`]).
fn class_curve(
    path: &Path,
    scores: &[f64],
    k: usize,
    labels: &[Option<usize>],
    c: usize,
) -> Result<PrCurve, PlotError> {
    let points = match metrics::precision_recall_curve(scores, k, labels, c) {
        Ok(points) => points,
        Err(MetricsError::Empty) => Vec::new(),
        Err(e) => return Err(input(path, e.to_string())),
    };
    Ok(pr_curve(&points))
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
mod tests;
