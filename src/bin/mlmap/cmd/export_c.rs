//! `mlmap export-c --table T --output table.h`: the table as a C header, for C firmware
//! that embeds its table at build time (the C API in `include/mlmap.h` decodes it).

use std::fs;
use std::path::PathBuf;

use clap::Args;
use mlmap::host::export::c_header;

use crate::error::{CliError, Result};
use crate::output;

/// Flags of `export-c`.
#[derive(Debug, Args)]
pub struct ExportCArgs {
    /// The table.
    #[arg(long, value_name = "TABLE")]
    pub table: PathBuf,
    /// The C header to write.
    #[arg(long, short, value_name = "FILE.h")]
    pub output: PathBuf,
    /// The array's name; its length is the macro NAME_LEN (upper case).
    #[arg(long, value_name = "IDENT", default_value = "mlmap_table_bytes")]
    pub name: String,
}

pub fn run(args: &ExportCArgs) -> Result<()> {
    output::check_outputs(&args.output, &[&args.table])?;
    let bytes = fs::read(&args.table).map_err(|e| CliError::input(&args.table, e))?;
    let source = args.table.file_name().map_or_else(
        || args.table.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let header =
        c_header(&bytes, &args.name, &source).map_err(|e| CliError::input(&args.table, e))?;
    output::write_bytes_atomic(&args.output, header.as_bytes())
}
