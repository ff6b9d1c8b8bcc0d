//! `mlmap export-c --table T --output table.h`: the table as a C header, for C firmware
//! that embeds its table at build time (the C API in `include/mlmap.h` decodes it).

use std::fs;
use std::path::PathBuf;

use clap::Args;
use mlmap::host::export::{c_header, check_c_name};

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
    /// The array's name, a C identifier that no C or C++ standard reserves; its length
    /// is the macro NAME_LEN, and NAME_IMPLEMENTATION defines it (upper case).
    #[arg(
        long,
        value_name = "IDENT",
        default_value = "mlmap_table_bytes",
        value_parser = c_name
    )]
    pub name: String,
}

/// Parses `--name`: a usage error (exit 2) for a name the header cannot use.
fn c_name(name: &str) -> std::result::Result<String, String> {
    check_c_name(name)
        .map(|()| name.to_owned())
        .map_err(|e| e.to_string())
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
