//! `mlmap eval`: the baselines and the layer's heads on labelled data, on the whole
//! test set and per group (DESIGN §1.4, §1.5, §4).

use std::fmt::Write as _;

use mlmap::host::data::Loaded;
use mlmap::host::eval::{self, Inputs};
use mlmap::host::metrics::{self, MetricsConfig};

use crate::args::{EvalArgs, Format};
use crate::error::{CliError, Result};
use crate::output;
use crate::report;
use crate::shared::{read_table, write_plots};

pub fn run(a: &EvalArgs) -> Result<()> {
    if a.ece_bins == 0 || a.ece_bins > metrics::MAX_BINS {
        return Err(CliError::Input(format!(
            "--ece-bins must be in 1..={}",
            metrics::MAX_BINS
        )));
    }
    let config = MetricsConfig {
        bins: a.ece_bins,
        binning: a.ece_binning,
    };
    if let Some(c) = a.group_by.as_deref() {
        if matches!(c, "label" | "objectness" | "id") || c.trim() != c || c.is_empty() {
            return Err(CliError::Input(format!(
                "--group-by {c:?}: name a column other than label, objectness and id, \
                 as written in the header"
            )));
        }
    }
    let (table, _) = read_table(&a.table)?;
    // With --group-by the column is not a class in any file; only the test file must
    // have it.
    let read = |p: &std::path::Path, required: bool| match a.group_by.as_deref() {
        Some(c) => Loaded::read_with_column(p, c, required),
        None => Loaded::read(p).map(|d| (d, None)),
    };
    let (test, groups) = read(&a.test, true)?;
    let val = a.val.as_deref().map(|p| read(p, false)).transpose()?;
    let ood = a.ood.as_deref().map(|p| read(p, false)).transpose()?;
    let ev = eval::evaluate(&Inputs {
        table: &table,
        test: (&test, &a.test),
        val: val.as_ref().map(|v| &v.0).zip(a.val.as_deref()),
        ood: ood.as_ref().map(|o| &o.0).zip(a.ood.as_deref()),
        config,
        groups: groups.as_deref(),
    })?;
    let mut text = report::evaluation(&ev, a.format, a.group_by.as_deref());
    if let Some(dir) = &a.plots {
        let n = write_plots(&ev, dir, &table)?;
        if a.format == Format::Text {
            let _ = writeln!(text, "\nwrote {n} plots into {}", dir.display());
        }
    }
    output::print(&text)
}
