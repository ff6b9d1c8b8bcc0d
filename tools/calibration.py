#!/usr/bin/env python3
"""Every method on a data set, as docs/CALIBRATION.md reports it; and the goals checked.

    python3 tools/calibration.py examples/data            # the shipped data
    python3 tools/calibration.py mlmap-holdout/digits     # any DIR with train/val/test/ood.csv

For DIR it runs the release `mlmap` binary (build it first:
`cargo build --release --features cli`):

ood.csv is split in two halves, row by row in file order (odd rows, even rows): the
first half is given to `tune --ood` (known unknowns that choose the settings), the
second half is evaluated; no evaluated row chooses a setting.

1. `mlmap tune --train train.csv --val val.csv --ood OOD_TUNE -o DIR-tuned.mlmap`
   (every head searched, the accuracy and mAP guards on), in a temporary directory;
2. `mlmap eval` of that table on test + unseen: test.csv and OOD_EVAL concatenated, the
   never-seen rows labelled `background`, so ECE, NLL, Brier and mAP count a confident
   answer on an unseen object as the mistake it is; `ood_mean` comes from OOD_EVAL alone;
   temperature scaling is fitted on val.csv.

`--tune-flag=FLAG` (repeatable) passes FLAG to `mlmap tune` (e.g.
`--tune-flag=--objectness-feature`, `--tune-flag=--no-maps`).

It prints one markdown table (method x ECE, NLL, Brier, accuracy, mAP, AUROC, unseen
mean) and, with --check, the goals of docs/CALIBRATION.md, exiting 1 if one is missed.
Standard library only.
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
BIN = os.path.join(ROOT, "target", "release", "mlmap")
COLUMNS = ["ece", "nll", "brier", "accuracy", "map", "auroc", "ood_mean"]


def run(args):
    out = subprocess.run([BIN] + args, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"mlmap {' '.join(args)} failed:\n{out.stderr}")
    return out.stdout


def concat(test, ood, path):
    """test.csv then ood.csv's rows with the label `background`."""
    with open(test, newline="") as f:
        rows = list(csv.reader(f))
    with open(ood, newline="") as f:
        unseen = list(csv.reader(f))
    header = rows[0]
    if unseen[0] != header:
        sys.exit(f"{ood}: columns differ from {test}")
    label = header.index("label")
    for r in unseen[1:]:
        r[label] = "background"
        rows.append(r)
    with open(path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


def split(ood, first, second):
    """ood's rows alternately into two files with its header: rows 1, 3, 5, ... into
    `first`, rows 2, 4, 6, ... into `second`."""
    with open(ood, newline="") as f:
        rows = list(csv.reader(f))
    for path, part in ((first, rows[1::2]), (second, rows[2::2])):
        with open(path, "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows([rows[0]] + part)


def evaluate(data, extra_tune=()):
    with tempfile.TemporaryDirectory() as tmp:
        table = os.path.join(tmp, "tuned.mlmap")
        files = {n: os.path.join(data, f"{n}.csv") for n in ("train", "val", "test", "ood")}
        ood_tune, ood_eval = os.path.join(tmp, "ood_tune.csv"), os.path.join(tmp, "ood_eval.csv")
        split(files["ood"], ood_tune, ood_eval)
        run(["tune", "--train", files["train"], "--val", files["val"], "--ood", ood_tune,
             "-o", table, *extra_tune])
        both = os.path.join(tmp, "test_and_unseen.csv")
        concat(files["test"], ood_eval, both)
        report = json.loads(run(["eval", "--table", table, "--test", both, "--val", files["val"],
                                 "--ood", ood_eval, "--format", "json"]))
    out = {}
    for method, m in report["methods"].items():
        aps = [v for k, v in m.items() if k.startswith("ap_") and v is not None]
        row = dict(m)
        row["map"] = sum(aps) / len(aps) if aps else None
        out[method] = row
    return out


def table(results):
    lines = ["| method | " + " | ".join(COLUMNS) + " |",
             "|---|" + "---:|" * len(COLUMNS)]
    for method, row in results.items():
        cells = ["-" if row.get(c) is None else f"{row[c]:.4f}" for c in COLUMNS]
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def check(results, background):
    """The goals of docs/CALIBRATION.md for the open head; returns the missed ones."""
    open_, soft, temp = results.get("open"), results["softmax"], results["temperature"]
    if open_ is None:
        return ["no open head in the tuned table"]
    missed = []
    if background:
        # A detector with background rows.
        goals = [
            ("open ECE at most temperature scaling's", open_["ece"] <= temp["ece"]),
            ("open mAP at least softmax's - 1 point", open_["map"] >= soft["map"] - 0.01),
            ("open accuracy equal to softmax's", open_["accuracy"] == soft["accuracy"]),
            ("open unseen mean at most temperature scaling's - 0.15",
             open_["ood_mean"] <= temp["ood_mean"] - 0.15),
        ]
    else:
        # A classifier without background rows.
        goals = [
            ("open ECE at most 0.5 x temperature scaling's", open_["ece"] <= 0.5 * temp["ece"]),
            ("open accuracy equal to softmax's", open_["accuracy"] == soft["accuracy"]),
            ("open mAP at least softmax's - 1 point", open_["map"] >= soft["map"] - 0.01),
            ("open unseen mean at most 0.35 (where softmax's is at least 0.93)",
             soft["ood_mean"] < 0.93 or open_["ood_mean"] <= 0.35),
        ]
    for name, ok in goals:
        print(f"  {'met   ' if ok else 'MISSED'} {name}")
        if not ok:
            missed.append(name)
    return missed


def main():
    # `--tune-flag=FLAG` (repeatable) passes FLAG to `mlmap tune`, e.g.
    # `--tune-flag=--objectness-feature` or `--tune-flag=--no-maps`.
    extra = [a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--tune-flag=")]
    args = [a for a in sys.argv[1:] if a != "--check" and not a.startswith("--tune-flag=")]
    if not args:
        sys.exit(__doc__)
    missed = []
    for data in args:
        results = evaluate(data, extra)
        print(f"\n### {data}\n")
        print(table(results))
        if "--check" in sys.argv:
            with open(os.path.join(data, "train.csv"), newline="") as f:
                background = any(r.get("label") == "background" for r in csv.DictReader(f))
            missed += check(results, background)
    sys.exit(1 if missed else 0)


if __name__ == "__main__":
    main()
