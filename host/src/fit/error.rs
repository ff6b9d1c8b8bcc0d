//! What can go wrong in a fit ([`FitError`]), and what is legal but worth a word
//! ([`FitWarning`]).

use std::fmt;
use std::path::PathBuf;

use crate::dataset::DataError;
use crate::DynTable;
use mlmap_core::{TableError, VARIANCE_FLOOR};

/// Why a table could not be fitted.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum FitError {
    /// The training data could not be read.
    Data(DataError),
    /// A hyper-parameter is out of range.
    Param {
        /// Parameter name (as in [`FitParams`](super::FitParams)).
        name: &'static str,
        /// The value given.
        value: String,
        /// The accepted range.
        expected: &'static str,
    },
    /// The training data has no labels.
    NoLabels {
        /// The training input.
        path: PathBuf,
    },
    /// Some classes have no training rows.
    EmptyClasses {
        /// The training input.
        path: PathBuf,
        /// The classes without rows.
        classes: Vec<String>,
    },
    /// A class's histogram range cannot be split into the requested bins with distinct
    /// `f32` edges (the values span too little for their magnitude).
    Edges {
        /// The class.
        class: String,
        /// Requested bins.
        bins: usize,
        /// First edge.
        lo: f32,
        /// Last edge.
        hi: f32,
    },
    /// A class's logits, or their variance, do not fit in `f32`.
    OutOfF32 {
        /// The class.
        class: String,
    },
    /// The input changed between the two passes of [`fit`](super::fit()).
    Changed {
        /// The training input.
        path: PathBuf,
    },
    /// The fitted statistics break a table invariant.
    Table(TableError),
    /// Statistics of other classes cannot be merged or combined.
    ClassesDiffer {
        /// The classes of the statistics merged into.
        ours: Vec<String>,
        /// The classes of the other statistics.
        theirs: Vec<String>,
    },
    /// Statistics recorded with other fit settings cannot be merged or combined.
    ParamsDiffer,
    /// The bin counts were made with other edges than those of the statistics (pass
    /// (b) over edges of another pass (a)), or counts of other edges were merged.
    EdgesDiffer,
    /// The bin counts cover another number of rows than the statistics: the shards of
    /// pass (b) are not those of pass (a).
    RowsDiffer {
        /// Rows in the statistics (pass (a)).
        stats: u64,
        /// Rows in the counts (pass (b)).
        counts: u64,
    },
    /// The bin counts of one class cover another number of rows than the statistics
    /// of that class (the totals may agree): the shards of pass (b) are not those of
    /// pass (a).
    ClassRowsDiffer {
        /// The class.
        class: String,
        /// Rows of the class in the statistics (pass (a)).
        stats: u64,
        /// Rows of the class in the bin counts (pass (b)).
        counts: u64,
    },
    /// The fitted statistics of one class (or Bayes category) break a table invariant.
    ClassTable {
        /// The class, or `background` for the Bayes head's background category.
        class: String,
        /// The invariant, as the layer reports it.
        error: TableError,
    },
    /// Serialized statistics or counts cannot be decoded.
    Format {
        /// What is wrong with the bytes.
        reason: String,
    },
    /// Pass (b) of some rows met a value outside the edges it counts against: the edges
    /// are not those of statistics that include these rows ([`parts`](super::parts)).
    OutsideEdges {
        /// The input holding the row.
        path: PathBuf,
        /// The row's index in that input.
        row: u64,
    },
    /// The objectness feature (DESIGN §1.6) was asked for and cannot be fitted: every
    /// labelled row has an objectness of 0 or 1 (no finite objectness logit), or the
    /// rows come from statistics files, which do not hold the objectness.
    Objectness {
        /// Why.
        reason: &'static str,
    },
}

impl FitError {
    /// `true` when the input or the parameters are at fault (exit code 2), `false` for
    /// an I/O or internal failure (exit code 1).
    pub fn is_bad_input(&self) -> bool {
        match self {
            Self::Data(e) => e.is_bad_input(),
            Self::Changed { .. } | Self::Table(_) | Self::ClassTable { .. } => false,
            Self::Param { .. }
            | Self::NoLabels { .. }
            | Self::EmptyClasses { .. }
            | Self::Edges { .. }
            | Self::OutOfF32 { .. }
            | Self::ClassesDiffer { .. }
            | Self::ParamsDiffer
            | Self::EdgesDiffer
            | Self::RowsDiffer { .. }
            | Self::ClassRowsDiffer { .. }
            | Self::Format { .. }
            | Self::OutsideEdges { .. }
            | Self::Objectness { .. } => true,
        }
    }
}

impl From<DataError> for FitError {
    fn from(e: DataError) -> Self {
        Self::Data(e)
    }
}

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Data(e) => write!(f, "{e}"),
            Self::Objectness { reason } => {
                write!(f, "the objectness feature cannot be fitted: {reason}")
            }
            Self::Param {
                name,
                value,
                expected,
            } => write!(f, "{name} = {value} is out of range: expected {expected}"),
            Self::NoLabels { path } => write!(
                f,
                "{}: the data has no labels (a `label` column or labels.npy); \
                 fitting needs labelled rows",
                path.display()
            ),
            Self::EmptyClasses { path, classes } => {
                write!(f, "{}: ", path.display())?;
                let quoted: Vec<String> = classes.iter().map(|c| format!("{c:?}")).collect();
                match quoted.as_slice() {
                    [one] => write!(f, "class {one} has no training rows")?,
                    many => write!(f, "classes {} have no training rows", many.join(", "))?,
                }
                f.write_str(" (rows labelled with the class); every class needs at least one")
            }
            Self::Edges {
                class,
                bins,
                lo,
                hi,
            } => write!(
                f,
                "class {class:?}: the range [{lo}, {hi}] cannot be split into {bins} bins \
                 with distinct f32 edges; use fewer bins"
            ),
            Self::OutOfF32 { class } => write!(
                f,
                "class {class:?}: the training logits or their variance exceed the f32 \
                 range of a table"
            ),
            Self::Changed { path } => write!(
                f,
                "{}: the input changed while it was being read",
                path.display()
            ),
            Self::Table(e) => write!(f, "the fitted table is invalid: {e}"),
            Self::ClassTable { class, error } => write!(
                f,
                "the fitted table is invalid: {}",
                name_class(error, class)
            ),
            Self::ClassesDiffer { ours, theirs } => write!(
                f,
                "statistics of classes [{}] cannot be combined with statistics of classes \
                 [{}] (same names, same order needed)",
                ours.join(", "),
                theirs.join(", ")
            ),
            Self::ParamsDiffer => f.write_str(
                "the statistics were recorded with other fit settings (bins, lambdas, edges, \
                 tail or Bayes head); every shard must use the same settings",
            ),
            Self::EdgesDiffer => f.write_str(
                "the bin counts were made with the edges of other statistics; count every \
                 shard with the edges of the merged pass-(a) statistics",
            ),
            Self::RowsDiffer { stats, counts } if stats == counts => write!(
                f,
                "the bin counts and the statistics both cover {stats} rows, but not the \
                 same rows per class: the shards of pass (b) are not those of pass (a)"
            ),
            Self::RowsDiffer { stats, counts } => write!(
                f,
                "the bin counts cover {counts} rows but the statistics {stats} rows: the \
                 shards of pass (b) are not those of pass (a)"
            ),
            Self::ClassRowsDiffer {
                class,
                stats,
                counts,
            } => write!(
                f,
                "the bin counts of class {class:?} cover {counts} rows but its statistics \
                 {stats} rows: the shards of pass (b) are not those of pass (a)"
            ),
            Self::Format { reason } => write!(f, "not valid fit statistics: {reason}"),
            Self::OutsideEdges { path, row } => write!(
                f,
                "{}: row index {row}: a training value lies outside the edges; pass (b) \
                 needs the edges of statistics that include these rows",
                path.display()
            ),
        }
    }
}

impl std::error::Error for FitError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Data(e) => Some(e),
            Self::Table(e) | Self::ClassTable { error: e, .. } => Some(e),
            _ => None,
        }
    }
}

/// Something legal but suspicious about a fitted table, worth telling the user.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum FitWarning {
    /// The class has one training row, or all its rows have the same logit: its sample
    /// variance is 0 and the prior's variance is the floor.
    DegeneratePrior {
        /// The class.
        class: String,
        /// Its training rows.
        rows: u64,
        /// The prior's mean (the class's one training value).
        mean: f32,
    },
}

impl fmt::Display for FitWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::DegeneratePrior { class, rows, mean } => {
                let why = if *rows == 1 {
                    "has a single training row".to_string()
                } else {
                    format!("has {rows} training rows with the same logit")
                };
                write!(
                    f,
                    "class {class:?} {why}: its sample variance is 0, floored to {VARIANCE_FLOOR:e}, \
                     so its MAP prior is a spike at {mean}: MAP gives the class evidence only for \
                     logits within about 1e-5 of that value, and lambda alone elsewhere; \
                     collect more rows for it, or rely on the ML or Bayes head"
                )
            }
        }
    }
}

/// The warnings of a fitted table (see [`FitWarning`]).
pub fn warnings(table: &DynTable) -> Vec<FitWarning> {
    table
        .class_names()
        .zip(table.rows())
        .zip(table.priors())
        .filter(|(_, p)| f64::from(p.variance()) <= VARIANCE_FLOOR)
        .map(|((name, &rows), p)| FitWarning::DegeneratePrior {
            class: name.to_string(),
            rows,
            mean: p.mean(),
        })
        .collect()
}

/// The class index a table error is about, if any.
pub(crate) fn class_index(e: &TableError) -> Option<u16> {
    match *e {
        TableError::Edges { class, .. }
        | TableError::Frequencies { class, .. }
        | TableError::BinCount { class, .. }
        | TableError::Mean { class }
        | TableError::Variance { class }
        | TableError::Name { class, .. }
        | TableError::DuplicateName { class }
        | TableError::CategoryRows { class } => Some(class),
        _ => None,
    }
}

/// The layer's message for `e`, naming the class `name` where it gives an index.
fn name_class(e: &TableError, name: &str) -> String {
    let text = e.to_string();
    let Some(i) = class_index(e) else {
        return text;
    };
    let mut out = String::with_capacity(text.len() + name.len());
    let mut rest = text.as_str();
    for word in ["class ", "category "] {
        let index = format!("{word}{i}");
        if let Some(at) = rest.find(&index) {
            let after = rest.get(at + index.len()..).unwrap_or_default();
            if !after.starts_with(|c: char| c.is_ascii_digit()) {
                out.push_str(rest.get(..at).unwrap_or_default());
                out.push_str(&format!("{word}{name:?}"));
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}
