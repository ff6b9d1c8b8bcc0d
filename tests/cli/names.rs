//! Class names (DESIGN §6.15): every reader refuses a name that is not printable, with
//! the rule it breaks and the name escaped; names of older tables that break the rule
//! reach the terminal escaped; CSV headers quote names holding commas and quotes.

use mlmap::host::fit::FitStats;

use super::*;
use crate::support::RawTable;

/// Names the rule refuses, each with the words of its message.
const HOSTILE: [(&str, &str); 6] = [
    ("red\u{1b}[0m", "control character, U+001B, at byte 3"),
    ("a\u{202e}b", "bidirectional formatting character, U+202E"),
    ("a\u{200b}b", "invisible"),
    ("a\u{a0}b", "separator other than the space, U+00A0"),
    ("a\u{2028}b", "separator other than the space, U+2028"),
    ("a\tb", "control character, U+0009"),
];

/// True when `text` holds a character a terminal would interpret (besides the line
/// ends of the output itself).
fn has_raw_controls(text: &str) -> bool {
    text.chars()
        .any(|c| c != '\n' && mlmap::refused_char(c).is_some())
}

#[test]
fn csv_headers_with_unprintable_names_are_refused() {
    let dir = tempdir();
    let d = dir.path();
    for (name, why) in HOSTILE {
        write(d, "t.csv", &format!("label,car,{name}\ncar,1.0,2.0\n"));
        let run = mlmap(d, &["fit", "--train", "t.csv", "--output", "t.mlmap"]);
        assert_eq!(run.code, 2, "{name:?}: {run:?}");
        assert!(run.stderr.contains("t.csv:1:"), "{name:?}: {}", run.stderr);
        assert!(run.stderr.contains(why), "{name:?}: {}", run.stderr);
        assert!(
            run.stderr.contains("not a valid class name"),
            "{}",
            run.stderr
        );
        assert!(!has_raw_controls(&run.stderr), "{:?}", run.stderr);
        assert!(!d.join("t.mlmap").exists());
    }
}

#[test]
fn classes_txt_with_unprintable_names_is_refused() {
    let dir = tempdir();
    let d = dir.path();
    let npy = d.join("npy");
    std::fs::create_dir(&npy).unwrap();
    write_npy(&npy.join("logits.npy"), &[2, 2], &[1.0f32, 0.0, 0.0, 1.0]);
    write_npy(&npy.join("labels.npy"), &[2], &[0i64, 1]);
    for (name, why) in HOSTILE {
        std::fs::write(npy.join("classes.txt"), format!("car\n{name}\n")).unwrap();
        refused(
            d,
            &["fit", "--train", "npy", "--output", "t.mlmap"],
            &["classes.txt:2:", why],
        );
    }
}

#[test]
fn statistics_files_with_unprintable_names_are_refused() {
    let dir = tempdir();
    let d = dir.path();
    for (name, why) in HOSTILE {
        let bytes = FitStats::new(&["car", name]).to_bytes();
        std::fs::write(d.join("bad.stats"), bytes).unwrap();
        let run = mlmap(d, &["merge", "bad.stats", "bad.stats", "-o", "m.stats"]);
        assert_eq!(run.code, 2, "{name:?}: {run:?}");
        assert!(run.stderr.contains(why), "{name:?}: {}", run.stderr);
        assert!(!has_raw_controls(&run.stderr), "{:?}", run.stderr);
        assert!(!d.join("m.stats").exists());
    }
}

/// A table of format version 1 holding names with control characters: `inspect`
/// shows them escaped, and `apply`'s message about other classes too.
#[test]
fn names_of_older_tables_reach_the_terminal_escaped() {
    let dir = tempdir();
    let d = dir.path();
    let mut raw = RawTable::small();
    let names = ["car\u{1b}[2J", "nul\u{0}\nline", "rac\u{202e}"];
    for (c, n) in raw.classes.iter_mut().zip(names) {
        c.name = n.as_bytes().to_vec();
    }
    std::fs::write(d.join("old.mlmap"), raw.encode()).unwrap();
    let run = ok(d, &["inspect", "old.mlmap"]);
    assert!(!has_raw_controls(&run.stdout), "{:?}", run.stdout);
    assert!(
        run.stdout
            .contains("car\\u{1b}[2J, nul\\0\\nline, rac\\u{202e}"),
        "{}",
        run.stdout
    );
    // JSON keeps the names as they are, escaped by JSON itself.
    let j = ok_json(d, &["inspect", "old.mlmap", "--format", "json"]);
    let got: Vec<&str> = j["classes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    assert_eq!(got, names);
    write(d, "x.csv", "car,b,c\n1,2,3\n");
    let run = mlmap(d, &apply_args("old.mlmap", "x.csv", "out.csv"));
    assert_eq!(run.code, 2, "{run:?}");
    assert!(!has_raw_controls(&run.stderr), "{:?}", run.stderr);
    assert!(run.stderr.contains("car\\u{1b}[2J"), "{}", run.stderr);
}

/// Printable names may hold commas and quotes: `apply` quotes them in its header.
#[test]
fn csv_headers_quote_names() {
    let dir = tempdir();
    let d = dir.path();
    let csv = std::fs::read_to_string(data("train"))
        .unwrap()
        .replacen("cyclist", "\"cy,c \"\"l\"\"\"", 1)
        .replace(",cyclist,", ",\"cy,c \"\"l\"\"\",");
    write(d, "train.csv", &csv);
    ok(d, &["fit", "--train", "train.csv", "--output", "t.mlmap"]);
    let name = "cy,c \"l\"";
    assert_eq!(
        read_table(&d.join("t.mlmap")).class_names().nth(1),
        Some(name)
    );
    ok(d, &apply_args("t.mlmap", "train.csv", "out.csv"));
    let (header, records) = read_csv(&d.join("out.csv"));
    assert!(header.contains(&format!("ml_{name}")), "{header:?}");
    assert!(header.contains(&format!("map_{name}")), "{header:?}");
    assert!(records.iter().any(|r| r.iter().any(|f| f == name)));
}
