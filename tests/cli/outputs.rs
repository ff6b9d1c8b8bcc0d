//! Outputs that must not destroy anything (DESIGN §4, Outputs): an output naming an input
//! (the same path, a symbolic or a hard link, a file of an NPY input directory) is refused
//! before anything is read; a device or a FIFO is written directly, never replaced by a
//! regular file. And `fit`'s warning about a class whose prior variance is floored.

use std::io::Read;
use std::os::unix::fs::FileTypeExt;

use super::*;

/// A small labelled CSV (two classes).
const SMALL: &str = "label,a,b\na,1.0,0.0\na,1.5,-0.5\nb,0.0,2.0\nb,-0.5,1.0\nb,0.2,1.7\n";

#[test]
fn an_output_naming_an_input_is_refused_before_reading() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", SMALL);
    let table = bayes_table();
    // The same path, through apply, fit and tune.
    refused(
        d,
        &apply_args(&table, "x.csv", "x.csv"),
        &["x.csv", "same file as the input"],
    );
    refused(
        d,
        &["fit", "--train", "x.csv", "-o", "x.csv"],
        &["same file as the input"],
    );
    refused(
        d,
        &["tune", "--train", "x.csv", "--val", "x.csv", "-o", "x.csv"],
        &["same file as the input"],
    );
    // A symbolic link to the input, and a hard link.
    std::os::unix::fs::symlink(d.join("x.csv"), d.join("s.csv")).unwrap();
    refused(
        d,
        &apply_args(&table, "x.csv", "s.csv"),
        &["s.csv", "x.csv"],
    );
    std::fs::hard_link(d.join("x.csv"), d.join("h.csv")).unwrap();
    refused(
        d,
        &apply_args(&table, "h.csv", "x.csv"),
        &["x.csv", "h.csv"],
    );
    // The table itself.
    std::fs::copy(&table, d.join("t.mlmap")).unwrap();
    refused(d, &apply_args("t.mlmap", "x.csv", "t.mlmap"), &["t.mlmap"]);
    // A file of an NPY input directory.
    let npy = d.join("npy");
    std::fs::create_dir(&npy).unwrap();
    write_npy(&npy.join("logits.npy"), &[2, 2], &[1.0f32, 0.0, 0.0, 1.0]);
    write(&npy, "classes.txt", "a\nb\n");
    ok(d, &["fit", "--train", "x.csv", "-o", "fit_ab.mlmap"]);
    refused(
        d,
        &apply_args("fit_ab.mlmap", "npy", "npy/logits.npy"),
        &["logits.npy", "npy"],
    );
    // A different file in the same directory is fine.
    ok(d, &apply_args("fit_ab.mlmap", "x.csv", "y.csv"));
    assert_eq!(std::fs::read_to_string(d.join("x.csv")).unwrap(), SMALL);
}

#[test]
fn devices_and_fifos_are_written_directly() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", SMALL);
    ok(d, &["fit", "--train", "x.csv", "-o", "t.mlmap"]);
    // /dev/null stays a character device.
    let null = std::path::Path::new("/dev/null");
    assert!(std::fs::metadata(null)
        .unwrap()
        .file_type()
        .is_char_device());
    ok(d, &apply_args("t.mlmap", "x.csv", "/dev/null"));
    assert!(std::fs::metadata(null)
        .unwrap()
        .file_type()
        .is_char_device());
    // A FIFO: its reader gets the whole CSV, and it stays a FIFO.
    let fifo = d.join("out.fifo");
    let status = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(status.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut text = String::new();
            std::fs::File::open(fifo)
                .unwrap()
                .read_to_string(&mut text)
                .unwrap();
            text
        })
    };
    ok(d, &apply_args("t.mlmap", "x.csv", "out.fifo"));
    let text = reader.join().unwrap();
    assert!(text.starts_with("label,ml_a,ml_b,map_a,map_b,"), "{text}");
    assert_eq!(text.lines().count(), 1 + 5);
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
}

#[test]
fn fit_warns_about_a_floored_prior_variance() {
    let dir = tempdir();
    let d = dir.path();
    // Class `a` has one row; class `b` three rows with the same logit.
    write(
        d,
        "one.csv",
        "label,a,b\na,0.7,0\nb,0,2\nb,0.1,2\nb,-0.1,2\n",
    );
    let run = ok(d, &["fit", "--train", "one.csv", "-o", "t.mlmap"]);
    assert!(run
        .stderr
        .contains("warning: one.csv: class \"a\" has a single training row"));
    assert!(run
        .stderr
        .contains("class \"b\" has 3 training rows with the same logit"));
    assert!(run.stderr.contains("floored to 1e-12"));
    // Nothing to say for ordinary data.
    write(d, "x.csv", SMALL);
    let run = ok(d, &["fit", "--train", "x.csv", "-o", "u.mlmap"]);
    assert_eq!(run.stderr, "");
}
