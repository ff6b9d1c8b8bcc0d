//! Command-line flags (DESIGN §4 is the stable interface; more flags are welcome).

use std::path::PathBuf;

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use mlmap::host::fit::{BayesParams, FitParams};
use mlmap::host::metrics::Binning;
use mlmap::host::names::Named;
use mlmap::host::tune::Objective;
use mlmap::{EdgeMode, Head, UpperTail};

/// The parser of a flag taking one of the values of a [`Named`] set: the possible
/// values, their descriptions and the parsing all come from the set's table.
pub(crate) fn named<T: Named + Clone + Send + Sync>() -> impl TypedValueParser<Value = T> {
    let values = T::NAMES
        .iter()
        .map(|n| PossibleValue::new(n.flag).help(n.help));
    PossibleValuesParser::new(values).try_map(|s| T::from_name(&s))
}

/// Fit, tune, apply and evaluate ML/MAP tables for object detectors.
#[derive(Debug, Parser)]
#[command(name = "mlmap", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Fit a table from training logits.
    Fit(FitArgs),
    /// Sharded fitting: the statistics of one shard (pass a), or with --stats its bin counts (pass b).
    Stats(StatsArgs),
    /// Merge the statistics or counts of shards; with --stats, write the table.
    Merge(MergeArgs),
    /// Choose bin counts and lambdas of every head on validation data, and write the best table.
    Tune(TuneArgs),
    /// Score every row of a file through the layer and write the scores (CSV or NPY).
    Apply(ApplyArgs),
    /// Compare sigmoid, softmax, temperature, ML, MAP and Bayes on labelled data.
    Eval(EvalArgs),
    /// Print a readable summary of a table.
    Inspect(InspectArgs),
    /// Run the whole job on the data shipped in examples/data.
    Demo(DemoArgs),
    /// Write a table as a C header (its bytes as a `const uint8_t[]`), for C firmware.
    ExportC(crate::cmd::export_c::ExportCArgs),
    /// Append a quantized section (int8 or int16 logits) to a table.
    Quantize(crate::cmd::quantize::QuantizeArgs),
    /// Replay a log through the drift monitor; `monitor fit` writes its alarm thresholds.
    Monitor(crate::cmd::monitor::MonitorArgs),
    /// Fit the thresholds of conformal class sets on labelled rows and write them into a table.
    Conformal(crate::cmd::conformal::ConformalArgs),
    /// Project a KITTI LiDAR scan into the camera image and write its dense range and reflectance maps.
    LidarMaps(crate::cmd::lidar_maps::LidarMapsArgs),
}

/// The fit settings of `fit` and of `stats` (pass a).
#[derive(Debug, Args)]
pub struct FitSettings {
    /// Bins of the ML histograms.
    #[arg(long, default_value_t = 22, value_name = "N")]
    pub bins_ml: usize,
    /// Additive smoothing of the ML head.
    #[arg(
        long,
        default_value_t = 0.0055,
        value_name = "X",
        value_parser = f32_value,
        allow_negative_numbers = true
    )]
    pub lambda_ml: f32,
    /// Bins of the MAP histograms.
    #[arg(long, default_value_t = 17, value_name = "N")]
    pub bins_map: usize,
    /// Additive smoothing of the MAP head.
    #[arg(
        long,
        default_value_t = 0.00012,
        value_name = "X",
        value_parser = f32_value,
        allow_negative_numbers = true
    )]
    pub lambda_map: f32,
    /// Edge placement.
    #[arg(long, value_parser = named::<EdgeMode>(), default_value = EdgeMode::Linspace.flag())]
    pub edges: EdgeMode,
    /// Likelihood above the last edge.
    #[arg(long, value_parser = named::<UpperTail>(), default_value = UpperTail::Zero.flag())]
    pub upper_tail: UpperTail,
    /// Bins per logit of the Bayes head.
    #[arg(long, default_value_t = 22, value_name = "N")]
    pub bins_bayes: usize,
    /// Additive smoothing of the Bayes head (inside its logarithm), in (0, 1].
    #[arg(
        long,
        default_value_t = 0.001,
        value_name = "X",
        value_parser = f32_value,
        allow_negative_numbers = true
    )]
    pub lambda_bayes: f32,
    /// Leave the Bayes head out (a version-1 table that older builds read).
    #[arg(long, conflicts_with_all = ["bins_bayes", "lambda_bayes"])]
    pub no_bayes: bool,
    /// The Bayes categories also model the objectness logit, ln(OS) - ln(1 - OS), as one
    /// more histogram (DESIGN §1.6), so that rows given as background with a low
    /// objectness teach the open head what they look like. Needs the rows (not --stats).
    #[arg(long, conflicts_with = "no_bayes")]
    pub objectness_feature: bool,
}

impl FitSettings {
    /// The fit parameters these flags give.
    pub fn params(&self) -> FitParams {
        FitParams {
            bins_ml: self.bins_ml,
            lambda_ml: self.lambda_ml,
            bins_map: self.bins_map,
            lambda_map: self.lambda_map,
            edges: self.edges,
            upper_tail: self.upper_tail,
            bayes: (!self.no_bayes).then_some(BayesParams {
                bins: self.bins_bayes,
                lambda: self.lambda_bayes,
                objectness: self.objectness_feature,
            }),
        }
    }
}

/// Flags of `fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Training data: a CSV file or an NPY directory.
    #[arg(long, value_name = "FILE")]
    pub train: PathBuf,
    /// Rows taken as `background` whatever their label (repeatable; CSV or NPY): known
    /// unknowns such as logged false positives, for the Bayes and open heads.
    #[arg(long, value_name = "FILE")]
    pub background: Vec<PathBuf>,
    /// The fit settings.
    #[command(flatten)]
    pub settings: FitSettings,
    /// The table file to write.
    #[arg(long, short, value_name = "TABLE")]
    pub output: PathBuf,
}

/// Flags of `stats`.
#[derive(Debug, Args)]
pub struct StatsArgs {
    /// One shard of the training data (CSV file or NPY directory).
    #[arg(long, value_name = "FILE")]
    pub train: PathBuf,
    /// Rows taken as `background` whatever their label (repeatable; CSV or NPY): the
    /// shard's known unknowns; give each background file to one shard's passes (a) and (b).
    #[arg(long, value_name = "FILE")]
    pub background: Vec<PathBuf>,
    /// Pass (b): the merged pass-(a) statistics of every shard; the shard's bin counts
    /// are written, over the edges and with the settings recorded there.
    #[arg(
        long,
        value_name = "STATS",
        conflicts_with_all = [
            "bins_ml", "lambda_ml", "bins_map", "lambda_map", "edges", "upper_tail",
            "bins_bayes", "lambda_bayes", "no_bayes", "objectness_feature",
        ]
    )]
    pub stats: Option<PathBuf>,
    /// The fit settings, recorded in the pass-(a) statistics.
    #[command(flatten)]
    pub settings: FitSettings,
    /// The statistics (pass a) or counts (pass b) file to write.
    #[arg(long, short, value_name = "FILE")]
    pub output: PathBuf,
}

/// Flags of `merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Files written by `stats`: all pass (a), or all pass (b).
    #[arg(value_name = "FILE", required = true)]
    pub files: Vec<PathBuf>,
    /// The merged pass-(a) statistics the pass-(b) FILES were counted with: the table
    /// is then written.
    #[arg(long, value_name = "STATS")]
    pub stats: Option<PathBuf>,
    /// The merged file (or, with --stats, the table) to write.
    #[arg(long, short, value_name = "FILE")]
    pub output: PathBuf,
}

/// Output format of `tune`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TuneFormat {
    /// Aligned tables of the best candidates and a summary of the written table.
    Text,
    /// One JSON object: the best candidates of each head and the written table.
    Json,
}

/// Flags of `tune`.
#[derive(Debug, Args)]
pub struct TuneArgs {
    /// Training data (CSV file or NPY directory).
    #[arg(long, value_name = "FILE")]
    pub train: PathBuf,
    /// Rows taken as `background` whatever their label (repeatable; CSV or NPY): known
    /// unknowns such as logged false positives, for the Bayes and open heads.
    #[arg(long, value_name = "FILE")]
    pub background: Vec<PathBuf>,
    /// Validation data the candidates are scored on.
    #[arg(long, value_name = "FILE")]
    pub val: PathBuf,
    /// Never-seen objects (labels ignored): they join the validation rows as background.
    #[arg(long, value_name = "FILE")]
    pub ood: Option<PathBuf>,
    /// What to minimise.
    #[arg(long, value_parser = named::<Objective>(), default_value = Objective::Ece.flag())]
    pub objective: Objective,
    /// ML bin counts to try: `N`, `A..B` (inclusive) or `A,B,C`.
    #[arg(long, default_value = "4..40", value_name = "SET")]
    pub bins_ml: String,
    /// MAP bin counts to try: `N`, `A..B` (inclusive) or `A,B,C`.
    #[arg(long, default_value = "4..40", value_name = "SET")]
    pub bins_map: String,
    /// Bayes bin counts per logit to try: `N`, `A..B` (inclusive) or `A,B,C`.
    #[arg(long, default_value = "4..40", value_name = "SET")]
    pub bins_bayes: String,
    /// Smallest Bayes lambda (default: --lambda-min), in (0, 1].
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub lambda_bayes_min: Option<f64>,
    /// Largest Bayes lambda (default: --lambda-max), in (0, 1].
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub lambda_bayes_max: Option<f64>,
    /// Leave the Bayes head out of the search and of the table.
    #[arg(long, conflicts_with_all = ["bins_bayes", "lambda_bayes_min", "lambda_bayes_max"])]
    pub no_bayes: bool,
    /// Largest top-1 accuracy a chosen candidate may lose against softmax (0.005 = half a point).
    #[arg(
        long,
        default_value_t = 0.005,
        value_name = "X",
        allow_negative_numbers = true
    )]
    pub max_accuracy_loss: f64,
    /// Largest mAP a chosen candidate may lose against softmax (0.01 = one point).
    #[arg(
        long,
        default_value_t = 0.01,
        value_name = "X",
        allow_negative_numbers = true
    )]
    pub max_map_loss: f64,
    /// Smallest lambda of the log grid (ML and MAP; Bayes too unless --lambda-bayes-min).
    #[arg(
        long,
        default_value_t = 1e-8,
        value_name = "X",
        allow_negative_numbers = true
    )]
    pub lambda_min: f64,
    /// Largest lambda of the log grid (ML and MAP; Bayes too unless --lambda-bayes-max).
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "X",
        allow_negative_numbers = true
    )]
    pub lambda_max: f64,
    /// Lambdas per decade of the log grid.
    #[arg(long, default_value_t = 3, value_name = "N")]
    pub lambdas_per_decade: usize,
    /// Edge placement.
    #[arg(long, value_parser = named::<EdgeMode>(), default_value = EdgeMode::Linspace.flag())]
    pub edges: EdgeMode,
    /// Likelihood above the last edge.
    #[arg(long, value_parser = named::<UpperTail>(), default_value = UpperTail::Zero.flag())]
    pub upper_tail: UpperTail,
    /// How many of the best candidates to print per head.
    #[arg(long, default_value_t = 5, value_name = "N")]
    pub top: usize,
    /// The Bayes categories also model the objectness logit (DESIGN §1.6), as `fit
    /// --objectness-feature` does.
    #[arg(long, conflicts_with = "no_bayes")]
    pub objectness_feature: bool,
    /// Fit no recalibration map (DESIGN §1.9): by default each head gets one where it
    /// lowers the validation ECE out of sample within the guards.
    #[arg(long)]
    pub no_maps: bool,
    /// Output format of the candidates (`json` prints them at full precision).
    #[arg(long, value_enum, default_value_t = TuneFormat::Text)]
    pub format: TuneFormat,
    /// The table file to write (the best candidate of each head).
    #[arg(long, short, value_name = "TABLE")]
    pub output: PathBuf,
}

/// Flags of `apply`.
#[derive(Debug, Args)]
pub struct ApplyArgs {
    /// The table.
    #[arg(long, value_name = "TABLE")]
    pub table: PathBuf,
    /// Rows to score (CSV file or NPY directory; labels optional).
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// The output: a CSV file, or an NPY directory (when the path ends in `/`, or with
    /// `--format npy`): `<head>.npy` (N x K float32 scores)
    /// and `<head>_pred.npy` (int32 class indices) per head, `sets.npy`, `labels.npy`,
    /// `ids.txt` and `classes.txt`. An existing NPY output is replaced as a whole.
    #[arg(long, short, value_name = "FILE.csv|DIR/")]
    pub output: PathBuf,
    /// The output's format (default: from `--output`, as above).
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub format: Option<ApplyFormat>,
    /// Score and write only these heads (comma-separated), in the usual column order;
    /// each must be one the table has. Default: every head the table has. Conformal sets
    /// are written when the head they threshold is among them.
    #[arg(long, value_delimiter = ',', value_parser = named::<Head>(), value_name = "HEAD,...")]
    pub heads: Option<Vec<Head>>,
    /// The logits are quantized codes (CSV integers, NPY int8 or int16), scored through
    /// the table's quantized section (`mlmap quantize`).
    #[arg(long)]
    pub quantized: bool,
}

/// Output format of `apply`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ApplyFormat {
    /// One CSV file.
    Csv,
    /// A directory of NPY arrays.
    Npy,
}

/// Output format of `eval` and `inspect`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// An aligned text table.
    Text,
    /// One JSON object.
    Json,
    /// A markdown table.
    Markdown,
}

/// Flags of `eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The table.
    #[arg(long, value_name = "TABLE")]
    pub table: PathBuf,
    /// Labelled test data.
    #[arg(long, value_name = "FILE")]
    pub test: PathBuf,
    /// Labelled validation data (fits the temperature and isotonic baselines).
    #[arg(long, value_name = "FILE")]
    pub val: Option<PathBuf>,
    /// Out-of-distribution data (never-seen objects; labels ignored).
    #[arg(long, value_name = "FILE")]
    pub ood: Option<PathBuf>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
    /// Write SVG plots into this directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub plots: Option<PathBuf>,
    /// ECE bins.
    #[arg(long, default_value_t = 10, value_name = "M")]
    pub ece_bins: usize,
    /// ECE bin closure convention.
    #[arg(long, value_parser = named::<Binning>(), default_value = Binning::Design.flag())]
    pub ece_binning: Binning,
    /// Also report every metric per value of this column of the test file (CSV): the
    /// column is not a class in any of the data files.
    #[arg(long, value_name = "COLUMN")]
    pub group_by: Option<String>,
}

/// Flags of `inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The table file.
    #[arg(value_name = "TABLE")]
    pub table: PathBuf,
    /// Also print every bin's edges and frequency.
    #[arg(long)]
    pub bins: bool,
    /// Output format (`markdown` is treated as text).
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
}

/// Flags of `demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Directory holding train.csv, val.csv, test.csv and ood.csv.
    #[arg(long, default_value = "examples/data", value_name = "DIR")]
    pub data: PathBuf,
    /// Directory the tables, reports and plots are written into.
    #[arg(long, default_value = "mlmap-demo", value_name = "DIR")]
    pub output: PathBuf,
}

/// A 32-bit float flag, refused when the `f32` is not the number written: a finite
/// value beyond `f32::MAX`, or a nonzero value that rounds to 0. Values out of a
/// flag's range are refused later, by the flag's own check.
pub fn f32_value(text: &str) -> Result<f32, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("{text:?} is not a number"))?;
    let x = v as f32;
    if v.is_finite() && !x.is_finite() {
        return Err(format!(
            "{text} is beyond the range of a 32-bit float (magnitude at most {:e})",
            f32::MAX
        ));
    }
    if v != 0.0 && x == 0.0 {
        return Err(format!(
            "{text} is too small for a 32-bit float: it would be 0 (smallest magnitude {:e})",
            f32::from_bits(1)
        ));
    }
    Ok(x)
}
