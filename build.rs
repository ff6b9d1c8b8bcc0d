//! Turns the table file named by `MLMAP_TABLE` (default `tables/default.mlmap`) into
//! validated Rust constants in `$OUT_DIR/embedded_table.rs` (docs/DESIGN.md §5, way 2).
//!
//! The decoder, the validation and the derived constants (bin widths, Gaussian
//! normalisers, Bayes log priors) come from `mlmap-core`, the crate the layer itself is
//! built from, so the build accepts exactly the tables `Table::from_bytes` accepts and
//! computes the constants with the same `f32` code as the device.
//!
//! Likewise the quantized section of the file named by `MLMAP_QUANTIZED` (default
//! `tables/default_q8.mlmap`) becomes `$OUT_DIR/embedded_quantized.rs`.

use std::path::PathBuf;
use std::{env, fmt, fs};

use mlmap_core::DynTable;

/// A build failure whose `Debug` is the plain message, so cargo shows it readably.
struct BuildError(String);

impl fmt::Debug for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BuildError {}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("cargo::rerun-if-env-changed=MLMAP_TABLE");
    println!("cargo::rerun-if-changed=build.rs");
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR")?);
    let path = match env::var_os("MLMAP_TABLE") {
        Some(p) => {
            let p = PathBuf::from(p);
            if p.is_absolute() {
                p
            } else {
                manifest.join(p)
            }
        }
        None => manifest.join("tables").join("default.mlmap"),
    };
    println!("cargo::rerun-if-changed={}", path.display());
    let fail = |msg: String| -> Box<dyn std::error::Error> {
        Box::new(BuildError(format!(
            "mlmap: cannot embed the table `{}` (MLMAP_TABLE): {msg}",
            path.display()
        )))
    };
    let bytes = fs::read(&path).map_err(|e| fail(e.to_string()))?;
    let table = DynTable::from_bytes(&bytes).map_err(|e| fail(e.to_string()))?;
    // Name the source relative to the package when it is inside it (reproducible builds).
    let shown = path
        .strip_prefix(&manifest)
        .unwrap_or(&path)
        .display()
        .to_string();
    let code = mlmap_core::__embed_source::rust_source(&table, &shown, &bytes, "crate");
    let out = PathBuf::from(env::var("OUT_DIR")?).join("embedded_table.rs");
    fs::write(out, code)?;
    embed_quantized(&manifest)
}

/// The quantized section of the file named by `MLMAP_QUANTIZED` (default
/// `tables/default_q8.mlmap`, the shipped table quantized to int8 with scale 0.08)
/// into `$OUT_DIR/embedded_quantized.rs`, validated by the section reader of the layer.
fn embed_quantized(manifest: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    println!("cargo::rerun-if-env-changed=MLMAP_QUANTIZED");
    let path = match env::var_os("MLMAP_QUANTIZED") {
        Some(p) => manifest.join(PathBuf::from(p)),
        None => manifest.join("tables").join("default_q8.mlmap"),
    };
    println!("cargo::rerun-if-changed={}", path.display());
    let fail = |msg: String| -> Box<dyn std::error::Error> {
        Box::new(BuildError(format!(
            "mlmap: cannot embed the quantized section `{}` (MLMAP_QUANTIZED): {msg}",
            path.display()
        )))
    };
    let bytes = fs::read(&path).map_err(|e| fail(e.to_string()))?;
    let shown = path
        .strip_prefix(manifest)
        .unwrap_or(&path)
        .display()
        .to_string();
    let code = mlmap_core::__embed_source::quantized_source(&bytes, &shown, "crate")
        .map_err(|e| fail(e.to_string()))?;
    let out = PathBuf::from(env::var("OUT_DIR")?).join("embedded_quantized.rs");
    fs::write(out, code)?;
    Ok(())
}
