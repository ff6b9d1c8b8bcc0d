//! `mlmap fit`: fit a table from training logits (DESIGN §1.1).

use std::fmt::Write as _;
use std::path::Path;

use mlmap::host::fit::{self, FitError, FitParams};
use mlmap::host::DynTable;

use crate::args::FitArgs;
use crate::cmd::inspect::{edge_mode_name, tail_name};
use crate::error::{CliError, Result};
use crate::{load, output};

/// Maps an error of fitting on the training data `train` to exit code 2 (bad input)
/// or 1, naming `train` when the error does not name a file itself, and naming a
/// parameter by its flag.
pub fn fit_error(train: &Path, e: FitError) -> CliError {
    let msg = match &e {
        FitError::Param {
            name,
            value,
            expected,
        } => format!(
            "--{} {value} is out of range: expected {expected}",
            name.replace('_', "-")
        ),
        FitError::Data(_)
        | FitError::NoLabels { .. }
        | FitError::EmptyClasses { .. }
        | FitError::Changed { .. } => e.to_string(),
        _ => format!("{}: {e}", train.display()),
    };
    if e.is_bad_input() {
        CliError::Input(msg)
    } else {
        CliError::Internal(msg)
    }
}

/// Encodes and writes a table atomically; returns its size.
pub fn write_table(path: &Path, table: &DynTable) -> Result<usize> {
    let bytes = table
        .to_vec()
        .map_err(|e| CliError::internal(path, format!("cannot encode the table: {e}")))?;
    output::write_bytes_atomic(path, &bytes)?;
    Ok(bytes.len())
}

/// A few lines describing a written table.
pub fn summary(path: &Path, table: &DynTable, size: usize) -> String {
    let st = table.settings();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "wrote {} ({size} bytes): {} classes, edges {}, upper tail {}",
        path.display(),
        table.k(),
        edge_mode_name(st.edge_mode),
        tail_name(st.upper_tail)
    );
    let _ = writeln!(
        s,
        "  ML  {:>3} bins, lambda {:e}\n  MAP {:>3} bins, lambda {:e}",
        table.bins_ml(),
        st.lambda_ml,
        table.bins_map(),
        st.lambda_map
    );
    let rows: Vec<String> = table
        .class_names()
        .zip(table.rows())
        .map(|(n, r)| format!("{n} {r}"))
        .collect();
    let _ = writeln!(s, "  training rows: {}", rows.join(", "));
    s
}

pub fn run(args: &FitArgs) -> Result<()> {
    let params = FitParams {
        bins_ml: args.bins_ml,
        lambda_ml: args.lambda_ml,
        bins_map: args.bins_map,
        lambda_map: args.lambda_map,
        edges: super::edge_mode(args.edges),
        upper_tail: super::upper_tail(args.upper_tail),
        bayes: (!args.no_bayes).then_some(fit::BayesParams {
            bins: args.bins_bayes,
            lambda: args.lambda_bayes,
        }),
    };
    let train = &args.train;
    params.validate().map_err(|e| fit_error(train, e))?;
    output::check_outputs(&args.output, &[train])?;
    let src = load::open(train)?;
    let table = fit::fit(&src, &params).map_err(|e| fit_error(train, e))?;
    for w in fit::warnings(&table) {
        eprintln!("mlmap: warning: {}: {w}", train.display());
    }
    let size = write_table(&args.output, &table)?;
    output::print(&summary(&args.output, &table, size))
}
