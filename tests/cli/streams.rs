//! Inputs that can be read only once, outputs that keep their modes, and runs ended by
//! a signal (DESIGN §2 and §4, Outputs): a FIFO or a pipe is read in one pass (or
//! refused by `fit`, which needs two, before it is opened); an output never replaces
//! the table it is made from, keeps the mode of the file it replaces or takes the one
//! the umask gives, is refused when write-protected; SIGINT, SIGTERM and SIGHUP leave
//! no temporary file.

use std::io::Write;
use std::os::unix::fs::PermissionsExt;
use std::process::Child;
use std::time::{Duration, Instant};

use super::*;

/// A small labelled CSV (two classes).
const SMALL: &str = "label,a,b\na,1.0,0.0\na,1.5,-0.5\nb,0.0,2.0\nb,-0.5,1.0\nb,0.2,1.7\n";

/// Waits for `child` at most `secs` seconds; kills it and fails the test on a hang.
fn wait_for(mut child: Child, secs: u64) -> Run {
    let deadline = Instant::now() + Duration::from_secs(secs);
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if Instant::now() > deadline {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("mlmap did not finish within {secs} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let run = Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8(out.stdout).unwrap(),
        stderr: String::from_utf8(out.stderr).unwrap(),
    };
    assert!(!run.stderr.contains("panicked"), "{run:?}");
    run
}

fn spawn(dir: &Path, args: &[&str], stdin: Stdio) -> Child {
    Command::new(env!("CARGO_BIN_EXE_mlmap"))
        .args(args)
        .current_dir(dir)
        .stdin(stdin)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn mkfifo(path: &Path) {
    assert!(Command::new("mkfifo").arg(path).status().unwrap().success());
}

/// A thread that writes `text` into the FIFO `path` (blocking until a reader opens it).
fn feed(path: &Path, text: String) -> std::thread::JoinHandle<()> {
    let path = path.to_path_buf();
    std::thread::spawn(move || {
        // The reader may end early (a refusal); a broken pipe is not this test's failure.
        if let Ok(mut f) = std::fs::OpenOptions::new().write(true).open(path) {
            let _ = f.write_all(text.as_bytes());
        }
    })
}

#[test]
fn a_fifo_or_a_pipe_is_read_once_by_apply() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", SMALL);
    ok(d, &["fit", "--train", "x.csv", "-o", "t.mlmap"]);
    ok(d, &apply_args("t.mlmap", "x.csv", "want.csv"));
    let want = std::fs::read_to_string(d.join("want.csv")).unwrap();
    // A named FIFO.
    mkfifo(&d.join("in.fifo"));
    let writer = feed(&d.join("in.fifo"), SMALL.to_string());
    let child = spawn(d, &apply_args("t.mlmap", "in.fifo", "a.csv"), Stdio::null());
    let run = wait_for(child, 30);
    writer.join().unwrap();
    assert_eq!(run.code, 0, "{run:?}");
    assert_eq!(std::fs::read_to_string(d.join("a.csv")).unwrap(), want);
    // A pipe, as `<(...)` gives: /dev/stdin fed by this process.
    let mut child = spawn(
        d,
        &apply_args("t.mlmap", "/dev/stdin", "b.csv"),
        Stdio::piped(),
    );
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(SMALL.as_bytes()).unwrap();
    drop(stdin);
    let run = wait_for(child, 30);
    assert_eq!(run.code, 0, "{run:?}");
    assert_eq!(std::fs::read_to_string(d.join("b.csv")).unwrap(), want);
    // An error in a piped input names its line.
    let writer = feed(&d.join("in.fifo"), format!("{SMALL}a,1,x\n"));
    let child = spawn(d, &apply_args("t.mlmap", "in.fifo", "c.csv"), Stdio::null());
    let run = wait_for(child, 30);
    writer.join().unwrap();
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run.stderr.contains("in.fifo:7: column \"b\""), "{run:?}");
    assert!(!d.join("c.csv").exists());
}

#[test]
fn fit_refuses_a_fifo_before_opening_it() {
    let dir = tempdir();
    let d = dir.path();
    mkfifo(&d.join("in.fifo"));
    // No writer: opening the FIFO would block, so a prompt refusal shows it was not.
    let child = spawn(
        d,
        &["fit", "--train", "in.fifo", "-o", "t.mlmap"],
        Stdio::null(),
    );
    let run = wait_for(child, 30);
    assert_eq!(run.code, 2, "{run:?}");
    assert!(run.stderr.contains("in.fifo"), "{run:?}");
    assert!(run.stderr.contains("read only once"), "{run:?}");
    assert!(!d.join("t.mlmap").exists());
}

#[test]
fn a_signal_during_apply_leaves_no_temporary_file() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", SMALL);
    ok(d, &["fit", "--train", "x.csv", "-o", "t.mlmap"]);
    mkfifo(&d.join("in.fifo"));
    // A CSV file, then an NPY directory (a temporary directory).
    let cases = [("TERM", 143), ("INT", 130), ("HUP", 129)]
        .into_iter()
        .map(|s| (s, "out.csv"))
        .chain([(("TERM", 143), "out/"), (("INT", 130), "out/")]);
    for ((signal, code), out) in cases {
        // The writer sends a large part of the input and keeps the FIFO open, so that
        // `apply` is in the middle of its output when the signal comes.
        let (release_tx, release_rx) = std::sync::mpsc::channel::<()>();
        let writer = {
            let path = d.join("in.fifo");
            std::thread::spawn(move || {
                let mut f = std::fs::OpenOptions::new().write(true).open(path).unwrap();
                let mut text = String::from("label,a,b\n");
                for i in 0..200_000 {
                    text.push_str(&format!("a,{}.5,-0.25\n", i % 7));
                }
                let _ = f.write_all(text.as_bytes());
                let _ = release_rx.recv();
            })
        };
        let child = spawn(d, &apply_args("t.mlmap", "in.fifo", out), Stdio::null());
        let temporary = || {
            std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(".mlmap-") && n.ends_with(".tmp"))
                .collect::<Vec<_>>()
        };
        let deadline = Instant::now() + Duration::from_secs(30);
        while temporary().is_empty() {
            assert!(Instant::now() < deadline, "no temporary file appeared");
            std::thread::sleep(Duration::from_millis(10));
        }
        // Let it write part of the rows.
        std::thread::sleep(Duration::from_millis(200));
        let status = Command::new("kill")
            .args([format!("-{signal}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
        let run = wait_for(child, 30);
        drop(release_tx);
        writer.join().unwrap();
        assert_eq!(run.code, code, "SIG{signal}: {run:?}");
        assert_eq!(temporary(), Vec::<String>::new(), "SIG{signal}");
        assert!(!d.join(out).exists(), "SIG{signal}, {out}");
    }
}

/// The permission bits of `path`.
fn mode(path: &Path) -> u32 {
    std::fs::metadata(path).unwrap().permissions().mode() & 0o7777
}

/// Runs `mlmap ARGS` in `dir` under `umask`, through the shell.
fn with_umask(dir: &Path, umask: &str, args: &[&str]) -> i32 {
    let status = Command::new("sh")
        .arg("-c")
        .arg(format!("umask {umask} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_mlmap"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .status()
        .unwrap();
    status.code().unwrap()
}

#[test]
fn outputs_honour_the_umask_and_the_mode_they_replace() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", SMALL);
    for (umask, want) in [("022", 0o644), ("077", 0o600), ("002", 0o664)] {
        let table = format!("t{umask}.mlmap");
        assert_eq!(
            with_umask(d, umask, &["fit", "--train", "x.csv", "-o", &table]),
            0
        );
        assert_eq!(mode(&d.join(&table)), want, "umask {umask}");
        let out = format!("o{umask}.csv");
        assert_eq!(with_umask(d, umask, &apply_args(&table, "x.csv", &out)), 0);
        assert_eq!(mode(&d.join(&out)), want, "umask {umask}");
        // An NPY directory: its files as any file, the directory with the search bits.
        let npy = format!("n{umask}/");
        assert_eq!(with_umask(d, umask, &apply_args(&table, "x.csv", &npy)), 0);
        assert_eq!(mode(&d.join(&npy).join("ml.npy")), want, "umask {umask}");
        assert_eq!(
            mode(&d.join(&npy)),
            want | (want & 0o444) >> 2,
            "umask {umask}"
        );
        let header = format!("h{umask}.h");
        assert_eq!(
            with_umask(d, umask, &["export-c", "--table", &table, "-o", &header]),
            0
        );
        assert_eq!(mode(&d.join(&header)), want, "umask {umask}");
    }
    // A replaced file keeps its mode, whatever the umask.
    std::fs::set_permissions(d.join("o022.csv"), std::fs::Permissions::from_mode(0o640)).unwrap();
    assert_eq!(
        with_umask(d, "077", &apply_args("t022.mlmap", "x.csv", "o022.csv")),
        0
    );
    assert_eq!(mode(&d.join("o022.csv")), 0o640);
}

#[test]
fn a_write_protected_output_is_refused() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", SMALL);
    ok(d, &["fit", "--train", "x.csv", "-o", "t.mlmap"]);
    write(d, "o.csv", "keep me\n");
    std::fs::set_permissions(d.join("o.csv"), std::fs::Permissions::from_mode(0o444)).unwrap();
    std::fs::copy(d.join("t.mlmap"), d.join("ro.mlmap")).unwrap();
    std::fs::set_permissions(d.join("ro.mlmap"), std::fs::Permissions::from_mode(0o400)).unwrap();
    // The mode bits decide (the superuser could open the file anyway).
    refused(
        d,
        &apply_args("t.mlmap", "x.csv", "o.csv"),
        &["o.csv", "write-protected", "0444"],
    );
    refused(
        d,
        &["fit", "--train", "x.csv", "-o", "ro.mlmap"],
        &["ro.mlmap", "write-protected"],
    );
    refused(
        d,
        &["export-c", "--table", "t.mlmap", "-o", "o.csv"],
        &["o.csv", "write-protected"],
    );
    assert_eq!(
        std::fs::read_to_string(d.join("o.csv")).unwrap(),
        "keep me\n"
    );
}

#[test]
fn export_c_refuses_to_overwrite_its_table() {
    let dir = tempdir();
    let d = dir.path();
    write(d, "x.csv", SMALL);
    std::fs::create_dir(d.join("sub")).unwrap();
    ok(d, &["fit", "--train", "x.csv", "-o", "t.mlmap"]);
    std::os::unix::fs::symlink(d.join("t.mlmap"), d.join("s.mlmap")).unwrap();
    std::fs::hard_link(d.join("t.mlmap"), d.join("h.mlmap")).unwrap();
    for output in ["t.mlmap", "./sub/../t.mlmap", "s.mlmap", "h.mlmap"] {
        refused(
            d,
            &["export-c", "--table", "t.mlmap", "-o", output],
            &[output, "same file as the input t.mlmap"],
        );
    }
    let run = ok(d, &["export-c", "--table", "t.mlmap", "-o", "t.h"]);
    assert_eq!(run.stderr, "");
    read_table(&d.join("t.mlmap"));
}
