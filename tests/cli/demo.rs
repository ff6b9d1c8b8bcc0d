use std::ffi::OsStr;

use serde_json::Value;

use super::*;

#[test]
fn demo_runs_the_whole_job() {
    let dir = tempdir();
    let d = dir.path();
    let data_dir = repo("examples/data");
    let run = ok(
        d,
        &[
            OsStr::new("demo"),
            OsStr::new("--data"),
            data_dir.as_os_str(),
            OsStr::new("--output"),
            OsStr::new("out"),
        ],
    );
    let s = &run.stdout;
    let steps = [
        "\n1. fit (authors' detection settings)\n",
        "\n2. tune lambdas on ",
        "\n3. evaluate on ",
        "\n4. no_std layer: Table<3, 22, 17, 22, 4, 32>::from_bytes(out/tuned.mlmap) scored 10000 test rows: 0 with scores differing from the host's in any bit\n",
        "\nsummary\n",
        "\n  head to ship: ",
    ];
    let mut at = 0;
    for step in steps {
        let found = s[at..]
            .find(step)
            .unwrap_or_else(|| panic!("no {step:?} in order:\n{s}"));
        at += found + step.len();
    }
    let out = d.join("out");
    for f in [
        "fitted.mlmap",
        "tuned.mlmap",
        "tune.txt",
        "eval.txt",
        "eval.json",
        "eval.md",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // The fit uses the defaults: the shipped table.
    assert_eq!(
        std::fs::read(out.join("fitted.mlmap")).unwrap(),
        std::fs::read(repo("tables/default.mlmap")).unwrap()
    );
    let tuned = read_table(&out.join("tuned.mlmap"));
    assert_eq!((tuned.bins_ml(), tuned.bins_map()), (22, 17));
    assert_eq!(tuned.bayes_head().map(|b| b.bins()), Some(22));
    let v: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("eval.json")).unwrap()).unwrap();
    assert_eq!(keys(&v["methods"]), sorted(&methods(true, &tuned)));
    assert!(v["methods"]["map"]["ood_over_0_9"].is_number());
    let plots = std::fs::read_dir(out.join("plots")).unwrap().count();
    assert!(plots >= methods(true, &tuned).len());
    assert!(s.contains(&format!("and {plots} plots into out\n")));
}
