//! `mlmap eval`: sigmoid, softmax, temperature, ML and MAP on labelled data
//! (DESIGN §1.4, §1.5, §4).

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
    let (table, _) = read_table(&a.table)?;
    let test = Loaded::read(&a.test)?;
    let val = a.val.as_deref().map(Loaded::read).transpose()?;
    let ood = a.ood.as_deref().map(Loaded::read).transpose()?;
    let ev = eval::evaluate(&Inputs {
        table: &table,
        test: (&test, &a.test),
        val: val.as_ref().zip(a.val.as_deref()),
        ood: ood.as_ref().zip(a.ood.as_deref()),
        config,
    })?;
    let mut text = report::evaluation(&ev, a.format);
    if let Some(dir) = &a.plots {
        let n = write_plots(&ev, dir, &table)?;
        if a.format == Format::Text {
            let _ = writeln!(text, "\nwrote {n} plots into {}", dir.display());
        }
    }
    output::print(&text)
}
