//! Any bytes through the companion's CSV reader give rows that satisfy DESIGN §2, or an
//! error that names the file; never a panic.
//!
//! Every row the reader yields is checked: K finite logits, objectness in [0, 1], a
//! class label below K; every error names the file.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use mlmap::host::dataset::DataSource;

/// One scratch file per fuzzing process (the reader takes a path; `.csv` selects CSV).
fn scratch() -> &'static PathBuf {
    static P: OnceLock<PathBuf> = OnceLock::new();
    P.get_or_init(|| {
        std::env::temp_dir().join(format!("mlmap-fuzz-csv-{}.csv", std::process::id()))
    })
}

fuzz_target!(|data: &[u8]| {
    let path = scratch();
    std::fs::write(path, data).expect("the scratch file is writable");
    let file = path
        .file_name()
        .and_then(|n| n.to_str())
        .expect("UTF-8 file name");
    let names_file = |e: &dyn std::fmt::Display| {
        let msg = e.to_string();
        assert!(msg.contains(file), "error does not name the file: {msg}");
    };
    let source = match DataSource::open(path) {
        Ok(s) => s,
        Err(e) => return names_file(&e),
    };
    let k = source.classes().len();
    assert!(k >= 2, "a source with fewer than 2 classes");
    let mut rows = 0usize;
    // The reader stops at the first malformed row with an error naming the file.
    let result = source.for_each_row(|row| -> Result<(), mlmap::host::dataset::DataError> {
        assert_eq!(row.logits.len(), k, "row {rows}: logit count");
        assert!(
            row.logits.iter().all(|x| x.is_finite()),
            "row {rows}: non-finite logit"
        );
        assert!(
            (0.0..=1.0).contains(&row.objectness),
            "row {rows}: objectness"
        );
        if let mlmap::host::dataset::Label::Class(i) = row.label {
            assert!(i < k, "row {rows}: label {i} of {k} classes");
        }
        rows += 1;
        Ok(())
    });
    if let Err(e) = result {
        names_file(&e);
    }
});
