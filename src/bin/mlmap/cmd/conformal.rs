//! `mlmap conformal`: the thresholds of the conformal class sets of DESIGN §8, fitted
//! on labelled calibration rows and written, with alpha and the head, into the table
//! file's conformal section.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use mlmap::host::conformal::{fit, scores, with_conformal};
use mlmap::host::data::{self, check_classes, Loaded};
use mlmap::host::names::Named as _;
use mlmap::{ConformalSpec, Head};

use crate::args::named;
use crate::error::{CliError, Result};
use crate::output;
use crate::shared::{read_table, threshold_line};

/// Flags of `conformal`.
#[derive(Debug, Args)]
pub struct ConformalArgs {
    /// The table.
    #[arg(long, value_name = "TABLE")]
    pub table: PathBuf,
    /// Labelled calibration rows (CSV file or NPY directory), never the training rows.
    #[arg(long, value_name = "FILE")]
    pub val: PathBuf,
    /// The miscoverage level: each class's set misses it on at most this share of its rows.
    #[arg(long, value_name = "ALPHA")]
    pub alpha: f64,
    /// The head whose scores the sets threshold.
    #[arg(long, value_parser = named::<Head>(), default_value = "map")]
    pub head: Head,
    /// The file to write: the table with its conformal section.
    #[arg(long, short, value_name = "FILE")]
    pub output: PathBuf,
}

pub fn run(args: &ConformalArgs) -> Result<()> {
    output::check_outputs(&args.output, &[&args.table, &args.val])?;
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        return Err(CliError::Input(format!(
            "--alpha {} is out of range: (0, 1)",
            args.alpha
        )));
    }
    let (table, bytes) = read_table(&args.table)?;
    if !table.view().has_head(args.head) {
        return Err(CliError::input(
            &args.table,
            format!("has no {} head for --head {}", args.head, args.head.name()),
        ));
    }
    let val = Loaded::read(&args.val)?;
    check_classes(&args.val, &val.classes, table.class_names())?;
    let labels = val.class_labels(&args.val)?;
    let (x, os) = (val.logits_f32(), val.objectness_f32());
    let s =
        scores(&table, args.head, &x, &os).map_err(|(i, e)| row_error(&args.val, &val, i, e))?;
    let fitted = fit(args.head, args.alpha, table.k(), &s, &labels);
    let out = with_conformal(&bytes, &fitted).map_err(|e| CliError::input(&args.table, e))?;
    // What is written reads back with the device's checks.
    ConformalSpec::from_bytes(&out, &table.view()).map_err(|e| CliError::input(&args.output, e))?;
    output::write_bytes_atomic(&args.output, &out)?;
    let mut text = format!(
        "wrote {}: conformal sets of the {} head at alpha {}, thresholds from {} rows of {} \
         ({} labelled with a class)\n",
        args.output.display(),
        args.head.name(),
        fitted.alpha,
        val.len(),
        args.val.display(),
        labels.iter().flatten().count()
    );
    let names: Vec<&str> = table.class_names().collect();
    for ((name, &n), &t) in names.iter().zip(&fitted.rows).zip(&fitted.thresholds) {
        let _ = writeln!(text, "{}", threshold_line(name, n, t, fitted.alpha));
    }
    output::print(&text)
}

fn row_error(path: &Path, val: &Loaded, i: usize, e: mlmap::InferError) -> CliError {
    CliError::Input(match val.locations.get(i) {
        Some(&loc) => format!("{}: {e}", data::at(path, loc)),
        None => format!("{}: {e}", path.display()),
    })
}
