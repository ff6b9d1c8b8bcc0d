#!/usr/bin/env python3
"""Every method on a data set, as docs/CALIBRATION.md reports it; and the goals checked.

    python3 tools/calibration.py examples/data            # the shipped data
    python3 tools/calibration.py mlmap-holdout/digits     # any DIR with train/val/test/ood.csv

For DIR it runs the release `mlmap` binary (build it first:
`cargo build --release --features cli`):

1. `mlmap tune --train train.csv --val val.csv --ood ood.csv -o DIR-tuned.mlmap`
   (every head searched, the accuracy and mAP guards on), in a temporary directory;
2. `mlmap eval` of that table on test + unseen: test.csv and ood.csv concatenated, the
   never-seen rows labelled `background`, so ECE, NLL, Brier and mAP count a confident
   answer on an unseen object as the mistake it is; `ood_mean` comes from ood.csv alone;
   temperature scaling is fitted on val.csv.

It prints one markdown table (method x ECE, NLL, Brier, accuracy, mAP, AUROC, unseen
mean) and, with --check, the goals of the Bayes head against the baselines, exiting 1 if
one is missed. Standard library only.
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


def evaluate(data, extra_tune=()):
    with tempfile.TemporaryDirectory() as tmp:
        table = os.path.join(tmp, "tuned.mlmap")
        files = {n: os.path.join(data, f"{n}.csv") for n in ("train", "val", "test", "ood")}
        run(["tune", "--train", files["train"], "--val", files["val"], "--ood", files["ood"],
             "-o", table, *extra_tune])
        both = os.path.join(tmp, "test_and_unseen.csv")
        concat(files["test"], files["ood"], both)
        report = json.loads(run(["eval", "--table", table, "--test", both, "--val", files["val"],
                                 "--ood", files["ood"], "--format", "json"]))
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
    """The goals of docs/CALIBRATION.md for the Bayes head; returns the missed ones."""
    bayes, soft, temp = results.get("bayes"), results["softmax"], results["temperature"]
    ml, map_ = results["ml"], results["map"]
    missed = []
    if background:
        if bayes is None:
            return ["no Bayes head in the tuned table"]
        goals = [
            ("ECE below temperature scaling", bayes["ece"] < temp["ece"]),
            ("mAP within 1 point of softmax", bayes["map"] >= soft["map"] - 0.01),
            ("accuracy within 0.5 points of softmax", bayes["accuracy"] >= soft["accuracy"] - 0.005),
            ("unseen mean 0.1 below temperature scaling", bayes["ood_mean"] <= temp["ood_mean"] - 0.1),
        ]
    else:
        goals = [
            ("ML accuracy within 0.5 points of softmax", ml["accuracy"] >= soft["accuracy"] - 0.005),
            ("MAP accuracy within 0.5 points of softmax", map_["accuracy"] >= soft["accuracy"] - 0.005),
        ]
    for name, ok in goals:
        print(f"  {'met   ' if ok else 'MISSED'} {name}")
        if not ok:
            missed.append(name)
    return missed


def main():
    args = [a for a in sys.argv[1:] if a != "--check"]
    if not args:
        sys.exit(__doc__)
    missed = []
    for data in args:
        results = evaluate(data)
        print(f"\n### {data}\n")
        print(table(results))
        if "--check" in sys.argv:
            with open(os.path.join(data, "train.csv"), newline="") as f:
                background = any(r.get("label") == "background" for r in csv.DictReader(f))
            missed += check(results, background)
    sys.exit(1 if missed else 0)


if __name__ == "__main__":
    main()
