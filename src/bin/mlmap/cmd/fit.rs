//! `mlmap fit`: fit a table from training logits (DESIGN §1.1).

use mlmap::host::data;
use mlmap::host::fit;

use crate::args::FitArgs;
use crate::error::{fit_error, Result};
use crate::output;
use crate::report::table_summary;
use crate::shared::write_table;

pub fn run(args: &FitArgs) -> Result<()> {
    let params = args.settings.params();
    let train = &args.train;
    params.validate().map_err(|e| fit_error(train, e))?;
    let mut inputs = vec![train.as_path()];
    inputs.extend(args.background.iter().map(|p| p.as_path()));
    output::check_outputs(&args.output, &inputs)?;
    let src = data::open_twice(train)?;
    let background = data::open_background(&args.background)?;
    let src = data::WithBackground::new(&src, &background)?;
    let table = fit::fit(&src, &params).map_err(|e| fit_error(train, e))?;
    for w in fit::warnings(&table) {
        eprintln!("mlmap: warning: {}: {w}", train.display());
    }
    let size = write_table(&args.output, &table)?;
    output::print(&table_summary(&args.output, &table, size))
}
