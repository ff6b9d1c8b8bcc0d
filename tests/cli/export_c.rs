//! `export-c`: the header compiles as C99, C11 and C++11 under `-pedantic -Wall -Wextra
//! -Werror`, in a file that defines the array, one that uses it and one that only
//! includes it, linked into one program whose array holds the table file's bytes; class
//! names (hostile ones included) cannot put code into it; `--name` takes only a C
//! identifier no standard reserves.

use std::path::Path;
use std::process::Command;

use super::*;
use crate::support::RawTable;

/// The file that defines the array (`NAME_IMPLEMENTATION`).
fn implementation(upper: &str) -> String {
    format!("#define {upper}_IMPLEMENTATION\n#include \"table.h\"\n#include \"table.h\"\n")
}

/// A program that writes the array's bytes to the file named by its argument. The
/// injected `int pwn = 1;` of a hostile class name would collide with `pwn` here.
fn user(name: &str, upper: &str) -> String {
    format!(
        "#include <stdio.h>\n\
         #include \"table.h\"\n\
         static const int pwn = 7;\n\
         int main(int argc, char **argv) {{\n\
         \x20   FILE *f;\n\
         \x20   size_t n;\n\
         \x20   if (argc != 2 || pwn != 7) return 3;\n\
         \x20   f = fopen(argv[1], \"wb\");\n\
         \x20   if (f == NULL) return 4;\n\
         \x20   n = fwrite({name}, 1, {upper}_LEN, f);\n\
         \x20   if (fclose(f) != 0 || n != {upper}_LEN || sizeof {name} != {upper}_LEN) return 5;\n\
         \x20   return 0;\n\
         }}\n"
    )
}

/// A file that includes the header and uses nothing of it.
const UNUSED: &str =
    "#include \"table.h\"\nint unused_file(void);\nint unused_file(void) { return 0; }\n";

/// Compiles `files` (name, text) with `compilers` (one per file: `cc` or `c++`, with
/// their standard), links them with `link`, runs the program and returns the bytes it
/// wrote.
fn build_and_run(dir: &Path, files: &[(&str, &str, &[&str])], link: &str) -> Vec<u8> {
    let mut objects = Vec::new();
    for (file, compiler, flags) in files {
        let object = format!("{file}.o");
        let out = Command::new(compiler)
            .args(*flags)
            .args(["-pedantic", "-Wall", "-Wextra", "-Werror", "-c", file, "-o"])
            .arg(&object)
            .current_dir(dir)
            .output()
            .unwrap_or_else(|e| panic!("{compiler}: {e}"));
        assert!(
            out.status.success(),
            "{compiler} {flags:?} {file}:\n{}\n{}",
            String::from_utf8_lossy(&out.stderr),
            std::fs::read_to_string(dir.join("table.h")).unwrap()
        );
        objects.push(object);
    }
    let out = Command::new(link)
        .args(&objects)
        .args(["-o", "prog"])
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "link: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let status = Command::new(dir.join("prog"))
        .arg("bytes.bin")
        .current_dir(dir)
        .status()
        .unwrap();
    assert!(status.success(), "the program failed: {status}");
    std::fs::read(dir.join("bytes.bin")).unwrap()
}

/// Writes the header of `table` (with `--name name`, or the default) and checks it in
/// C99, C11, C++11 and mixed C / C++ programs of three files.
fn assert_header_compiles(table: &Path, name: Option<&str>) {
    let dir = tempdir();
    let d = dir.path();
    let table_arg = table.to_string_lossy().into_owned();
    let mut args = vec!["export-c", "--table", &table_arg, "--output", "table.h"];
    if let Some(n) = name {
        args.extend(["--name", n]);
    }
    ok(d, &args);
    let name = name.unwrap_or("mlmap_table_bytes");
    let upper = name.to_ascii_uppercase();
    let want = std::fs::read(table).unwrap();
    write(d, "imp.c", &implementation(&upper));
    write(d, "user.c", &user(name, &upper));
    write(d, "unused.c", UNUSED);
    for (from, to) in [
        ("imp.c", "imp.cpp"),
        ("user.c", "user.cpp"),
        ("unused.c", "unused.cpp"),
    ] {
        std::fs::copy(d.join(from), d.join(to)).unwrap();
    }
    let c99: &[&str] = &["-std=c99"];
    let c11: &[&str] = &["-std=c11"];
    let cxx: &[&str] = &["-std=c++11"];
    for std in [c99, c11] {
        let files = [
            ("imp.c", "cc", std),
            ("user.c", "cc", std),
            ("unused.c", "cc", std),
        ];
        assert_eq!(build_and_run(d, &files, "cc"), want, "{std:?}");
    }
    let files = [
        ("imp.cpp", "c++", cxx),
        ("user.cpp", "c++", cxx),
        ("unused.cpp", "c++", cxx),
    ];
    assert_eq!(build_and_run(d, &files, "c++"), want, "C++");
    // The array defined in C, used from C++, and the other way round.
    let files = [
        ("imp.c", "cc", c99),
        ("user.cpp", "c++", cxx),
        ("unused.c", "cc", c99),
    ];
    assert_eq!(build_and_run(d, &files, "c++"), want, "C and C++");
    let files = [
        ("imp.cpp", "c++", cxx),
        ("user.c", "cc", c11),
        ("unused.cpp", "c++", cxx),
    ];
    assert_eq!(build_and_run(d, &files, "c++"), want, "C++ and C");
}

#[test]
fn header_compiles_in_c_and_cpp_with_one_definition() {
    assert_header_compiles(Path::new(&bayes_table()), None);
    assert_header_compiles(Path::new(&golden_table()), Some("T"));
    let long = format!("t{}", "_x9".repeat(20) + "ab");
    assert_eq!(long.len(), 63);
    assert_header_compiles(Path::new(&bayes_table()), Some(&long));
}

/// A class name that closes the comment (accepted by `fit`: it is printable) stays in
/// the comment, escaped.
#[test]
fn hostile_class_names_stay_in_the_comment() {
    let dir = tempdir();
    let d = dir.path();
    let hostile = "*/ int pwn = 1; /*";
    let csv = std::fs::read_to_string(data("train"))
        .unwrap()
        .replace("cyclist", hostile);
    write(d, "train.csv", &csv);
    ok(d, &["fit", "--train", "train.csv", "--output", "t.mlmap"]);
    assert_eq!(
        read_table(&d.join("t.mlmap")).class_names().nth(1),
        Some(hostile)
    );
    assert_header_compiles(&d.join("t.mlmap"), Some("hostile"));
    ok(
        d,
        &[
            "export-c", "--table", "t.mlmap", "--output", "t.h", "--name", "t",
        ],
    );
    let h = std::fs::read_to_string(d.join("t.h")).unwrap();
    assert!(!h.contains("*/ int pwn"), "{h}");
    assert!(h.contains("\\x2a\\x2f int pwn = 1; \\x2f\\x2a"), "{h}");
    // A table of format version 1 may hold any UTF-8 in a name: newline, NUL, ESC, a
    // trigraph and a line splice, bidi controls, non-ASCII.
    let names: [&str; 3] = ["car\n#error x", "\u{0}\u{1b}[2J??/\\", "*/\u{202e}vélo"];
    let mut raw = RawTable::small();
    for (c, n) in raw.classes.iter_mut().zip(names) {
        c.name = n.as_bytes().to_vec();
    }
    std::fs::write(d.join("old.mlmap"), raw.encode()).unwrap();
    assert_header_compiles(&d.join("old.mlmap"), None);
    ok(
        d,
        &["export-c", "--table", "old.mlmap", "--output", "old.h"],
    );
    let h = std::fs::read_to_string(d.join("old.h")).unwrap();
    assert!(h.is_ascii());
    // The header's own `#error` (the arena layout guard) is the only directive of that
    // name: the class name's never starts a line.
    assert!(!h.contains("\n#error x") && !h.contains("??") && !h.contains('\u{1b}'));
    assert_eq!(h.matches("\n#error").count(), 1, "{h}");
    assert!(
        h.contains(
            "car\\x0a#error x, \\x00\\x1b[2J\\x3f\\x3f\\x2f\\x5c, \\x2a\\x2f\\u202ev\\u00e9lo"
        ),
        "{h}"
    );
}

#[test]
fn name_must_be_a_plain_c_identifier() {
    let dir = tempdir();
    let d = dir.path();
    let table = bayes_table();
    for (name, why) in [
        ("int", "keyword"),
        ("while", "keyword"),
        ("class", "keyword"),
        ("bool", "keyword"),
        ("_x", "reserved"),
        ("_Table", "reserved"),
        ("__t", "reserved"),
        ("a__b", "reserved"),
        ("main", "reserved"),
        ("uint8_t", "<stdint.h>"),
        ("my-table", "not a C identifier"),
        ("1x", "not a C identifier"),
        ("tåble", "not a C identifier"),
        ("", "not a C identifier"),
        (&"t".repeat(64), "longer than 63"),
    ] {
        refused(
            d,
            &[
                "export-c", "--table", &table, "--output", "t.h", "--name", name,
            ],
            &["--name", why],
        );
    }
}
