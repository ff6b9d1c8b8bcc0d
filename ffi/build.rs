//! Reads the maximum table shape of the build from the environment and writes it to
//! `$OUT_DIR/limits.rs`:
//!
//! * `MLMAP_MAX_CLASSES`: classes K, 2..=255 (default 16);
//! * `MLMAP_MAX_BINS`: bins of the ML and of the MAP head, 1..=4096 (default 64);
//! * `MLMAP_MAX_BINS_BAYES`: bins per logit of the Bayes head, 0..=4096, 0 for no
//!   Bayes head (default 64);
//! * `MLMAP_FAST_CLASSES`: the class counts that get code specialised for them (loops
//!   of constant length, as in the Rust `Table`), comma-separated, each in 2..=16 and
//!   at most `MLMAP_MAX_CLASSES`; empty for none (default `2,3,4`). Each costs code
//!   size; other counts run the general code, with the same results.
//!
//! A C program built against another maximum defines the same `MLMAP_MAX_*` macros
//! before including `mlmap.h`.

use std::{env, fs, path::PathBuf};

fn limit(name: &str, default: usize, min: usize, max: usize) -> Result<usize, String> {
    println!("cargo::rerun-if-env-changed={name}");
    let value = match env::var(name) {
        Ok(s) => s
            .trim()
            .parse::<usize>()
            .map_err(|e| format!("{name}={s:?}: {e}"))?,
        Err(env::VarError::NotPresent) => default,
        Err(e) => return Err(format!("{name}: {e}")),
    };
    if !(min..=max).contains(&value) {
        return Err(format!("{name}={value}: must be in {min}..={max}"));
    }
    Ok(value)
}

fn main() -> Result<(), String> {
    println!("cargo::rerun-if-changed=build.rs");
    let classes = limit("MLMAP_MAX_CLASSES", 16, 2, 255)?;
    let bins = limit("MLMAP_MAX_BINS", 64, 1, 4096)?;
    let bins_bayes = limit("MLMAP_MAX_BINS_BAYES", 64, 0, 4096)?;
    let categories = if bins_bayes == 0 { 0 } else { classes + 1 };
    println!("cargo::rerun-if-env-changed=MLMAP_FAST_CLASSES");
    let fast_list = env::var("MLMAP_FAST_CLASSES").unwrap_or_else(|_| "2,3,4".to_owned());
    let mut fast = Vec::new();
    for item in fast_list
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
    {
        let k: usize = item
            .parse()
            .map_err(|e| format!("MLMAP_FAST_CLASSES={fast_list:?}: {item:?}: {e}"))?;
        if !(2..=16).contains(&k) || k > classes {
            return Err(format!(
                "MLMAP_FAST_CLASSES={fast_list:?}: {k} is not in 2..=16 and <= MLMAP_MAX_CLASSES"
            ));
        }
        fast.push(k.to_string());
    }
    let out = PathBuf::from(env::var("OUT_DIR").map_err(|e| e.to_string())?);
    let src = format!(
        "/// Most classes a table may have (`MLMAP_MAX_CLASSES`).\n\
         pub const MAX_CLASSES: usize = {classes};\n\
         /// Most bins of the ML and of the MAP head (`MLMAP_MAX_BINS`).\n\
         pub const MAX_BINS: usize = {bins};\n\
         /// Most bins per logit of the Bayes head (`MLMAP_MAX_BINS_BAYES`).\n\
         pub const MAX_BINS_BAYES: usize = {bins_bayes};\n\
         /// Most categories of the Bayes head (K + 1, or 0 without one).\n\
         pub const MAX_CATEGORIES: usize = {categories};\n\
         /// Class counts with specialised code (`MLMAP_FAST_CLASSES`).\n\
         pub const FAST_CLASSES: &[usize] = &[{fast}];\n",
        fast = fast.join(", ")
    );
    fs::write(out.join("limits.rs"), src).map_err(|e| e.to_string())
}
