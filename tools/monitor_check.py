#!/usr/bin/env python3
"""A held-out check of the drift monitor (docs/DESIGN.md §7) through the `mlmap` CLI: the
false-alarm rate of in-distribution windows and the detection rate of shifted ones, for
the thresholds `mlmap monitor fit` chooses on examples/data/val.csv.

For each false-alarm rate alpha (0.01, 0.05) and window W (200, 1000), it fits the
thresholds on val.csv (`mlmap monitor fit`, its default 2000 resampled windows, seed 0)
and replays (`mlmap monitor --format jsonl`) these streams, counting the full windows
with an alarm:

* in distribution: examples/data/test.csv in file order (10000 rows: 50 windows of 200,
  10 of 1000), and windows resampled from it (REPS windows of W rows drawn with
  replacement, so W = 1000 gets more than 10 windows; the share's 95 % Wilson interval
  is printed with it);
* out of distribution: examples/data/ood.csv in file order (unseen objects: 10 windows
  of 200, 2 of 1000);
* unseen objects mixed in: resampled windows whose rows come from ood.csv with
  probability 10 %, 30 % or 50 % and from test.csv otherwise;
* a shifted detector: test.csv with every logit raised by a constant (0.25, 0.5, 1.0),
  in file order.

For every stream it prints the share of windows with an alarm and the index (from 1) of
the first one (`-` for none). Then, for each W, the Spearman correlation between each
window metric (`psi_max`, `oos_rate`, `1 - q_mean`) and the window's error rate on a mixed
stream of MIXED windows whose unseen share is drawn uniformly from [0, 0.5] per window: a
row is an error when it is an unseen object, a background row, or a row whose label is
not the detector's decision (its largest logit). The resampling is numpy's PCG64 with a fixed seed, so the
table is reproducible.

    cargo build --release --features cli --bin mlmap
    python3 tools/monitor_check.py [--mlmap target/release/mlmap] [--reps 500]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TABLE = os.path.join(ROOT, "tables", "default.mlmap")
DATA = os.path.join(ROOT, "examples", "data")
ALPHAS = (0.01, 0.05)
WINDOWS = (200, 1000)
MIXES = (0.1, 0.3, 0.5)
SHIFTS = (0.25, 0.5, 1.0)


def read(path):
    """(header, rows as lists of strings, logits as float64, index of the first logit)."""
    with open(path) as fh:
        header = fh.readline().strip().split(",")
        rows = [line.rstrip("\n").split(",") for line in fh if line.strip()]
    first = header.index("objectness") + 1
    x = np.array([[float(v) for v in r[first:]] for r in rows])
    return header, rows, x, first


def write(path, header, rows):
    with open(path, "w") as fh:
        fh.write(",".join(header) + "\n")
        for r in rows:
            fh.write(",".join(r) + "\n")


def run(cmd):
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({done.returncode}):\n{done.stderr}")
    return done.stdout


def replay(mlmap, table, path, window):
    """(full windows, of which with an alarm, index from 1 of the first alarm or None)."""
    out = run([mlmap, "monitor", "--table", table, "--input", path, "--format", "jsonl"])
    full = [json.loads(line) for line in out.splitlines() if line.strip()]
    full = [w for w in full if w["rows"] == window]
    alarms = [w["alarm"] for w in full]
    first = next((i + 1 for i, a in enumerate(alarms) if a), None)
    return len(full), sum(alarms), first


def windows(mlmap, table, path, window):
    """The full windows' JSON reports, in order."""
    out = run([mlmap, "monitor", "--table", table, "--input", path, "--format", "jsonl"])
    full = [json.loads(line) for line in out.splitlines() if line.strip()]
    return [w for w in full if w["rows"] == window]


def ranks(v):
    """Ranks from 1, ties sharing their mean rank."""
    v = np.asarray(v, dtype=np.float64)
    order = np.argsort(v, kind="mergesort")
    r = np.empty(len(v))
    i = 0
    while i < len(v):
        j = i
        while j + 1 < len(v) and v[order[j + 1]] == v[order[i]]:
            j += 1
        r[order[i:j + 1]] = (i + j) / 2 + 1
        i = j + 1
    return r


def spearman(a, b):
    ra, rb = ranks(a), ranks(b)
    if ra.std() == 0 or rb.std() == 0:
        return math.nan
    return float(np.corrcoef(ra, rb)[0, 1])


def wilson(k, n, z=1.96):
    if n == 0:
        return (math.nan, math.nan)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mlmap", default=os.path.join(ROOT, "target", "release", "mlmap"))
    ap.add_argument("--reps", type=int, default=500, help="resampled in-distribution windows")
    ap.add_argument("--mixed", type=int, default=100, help="resampled windows per mix")
    ap.add_argument("--seed", type=int, default=18)
    a = ap.parse_args()
    if not os.access(a.mlmap, os.X_OK):
        sys.exit(f"{a.mlmap}: no mlmap binary (cargo build --release --features cli --bin mlmap)")
    header, test, x_test, first = read(os.path.join(DATA, "test.csv"))
    header_ood, ood, _, _ = read(os.path.join(DATA, "ood.csv"))
    if header_ood != header:
        sys.exit("test.csv and ood.csv have other columns")
    rng = np.random.default_rng(a.seed)
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        streams = {}
        for w in WINDOWS:
            # The streams do not depend on alpha: written once per window.
            idx = rng.integers(0, len(test), size=(a.reps, w)).ravel()
            p = os.path.join(tmp, f"boot_{w}.csv")
            write(p, header, [test[i] for i in idx])
            streams[(w, "in distribution, resampled")] = p
            for mix in MIXES:
                unseen = rng.random(a.mixed * w) < mix
                ti = rng.integers(0, len(test), size=a.mixed * w)
                oi = rng.integers(0, len(ood), size=a.mixed * w)
                rows = [ood[o] if u else test[t] for u, t, o in zip(unseen, ti, oi)]
                p = os.path.join(tmp, f"mix_{w}_{mix}.csv")
                write(p, header, rows)
                streams[(w, f"{int(mix * 100)} % unseen objects, resampled")] = p
        for shift in SHIFTS:
            rows = [r[:first] + [repr(float(np.float32(v + shift))) for v in x]
                    for r, x in zip(test, x_test)]
            p = os.path.join(tmp, f"shift_{shift}.csv")
            write(p, header, rows)
            streams[(None, f"test.csv, logits + {shift}")] = p
        for alpha in ALPHAS:
            for w in WINDOWS:
                table = os.path.join(tmp, f"t_{alpha}_{w}.mlmap")
                run([a.mlmap, "monitor", "fit", "--table", TABLE, "--val",
                     os.path.join(DATA, "val.csv"), "--window", str(w), "--false-alarm",
                     str(alpha), "-o", table])
                rows = [("test.csv in order", os.path.join(DATA, "test.csv"), True),
                        ("in distribution, resampled",
                         streams[(w, "in distribution, resampled")], True),
                        ("ood.csv in order (unseen objects)", os.path.join(DATA, "ood.csv"),
                         False)]
                rows += [(f"{int(m * 100)} % unseen objects, resampled",
                          streams[(w, f"{int(m * 100)} % unseen objects, resampled")], False)
                         for m in MIXES]
                rows += [(f"test.csv, logits + {s}", streams[(None, f"test.csv, logits + {s}")],
                          False) for s in SHIFTS]
                for name, path, in_dist in rows:
                    n, k, first_alarm = replay(a.mlmap, table, path, w)
                    results.append((alpha, w, name, in_dist, n, k, first_alarm))
        # The correlation of the window metrics with the window error rate.
        label_at = header.index("label")
        classes = header[first:]
        wrong_test = [r[label_at] not in classes or classes.index(r[label_at]) != int(np.argmax(x))
                      for r, x in zip(test, x_test)]
        corr = []
        for w in WINDOWS:
            rows, errors = [], []
            for _ in range(a.mixed):
                mix = rng.uniform(0.0, 0.5)
                unseen = rng.random(w) < mix
                ti = rng.integers(0, len(test), size=w)
                oi = rng.integers(0, len(ood), size=w)
                rows += [ood[o] if u else test[t] for u, t, o in zip(unseen, ti, oi)]
                errors.append(float(np.mean([u or wrong_test[t] for u, t in zip(unseen, ti)])))
            p = os.path.join(tmp, f"corr_{w}.csv")
            write(p, header, rows)
            table = os.path.join(tmp, f"c_{w}.mlmap")
            run([a.mlmap, "monitor", "fit", "--table", TABLE, "--val",
                 os.path.join(DATA, "val.csv"), "--window", str(w), "--false-alarm", "0.05",
                 "-o", table])
            reports = windows(a.mlmap, table, p, w)
            errors = errors[:len(reports)]
            for name, values in (("psi_max", [r["psi_max"] for r in reports]),
                                 ("oos_rate", [r["oos_rate"] for r in reports]),
                                 ("1 - q_mean", [1.0 - r["q_mean"] for r in reports])):
                corr.append((w, name, len(reports), spearman(values, errors)))
    print("| alpha | W | stream | windows | with an alarm | share | 95 % interval "
          "| first alarm |")
    print("|---:|---:|---|---:|---:|---:|---|---:|")
    for alpha, w, name, in_dist, n, k, first_alarm in results:
        lo, hi = wilson(k, n)
        share = k / n if n else math.nan
        goal = ""
        if in_dist:
            goal = " (≤ α + 0.02: " + ("met" if share <= alpha + 0.02 else "missed") + ")"
        print(f"| {alpha} | {w} | {name} | {n} | {k} | {share:.3f}{goal} | "
              f"[{lo:.3f}, {hi:.3f}] | {first_alarm if first_alarm else '-'} |")
    print()
    print("| W | window metric | windows | Spearman with the window error rate |")
    print("|---:|---|---:|---:|")
    for w, name, n, rho in corr:
        goal = "met" if rho >= 0.5 else "missed"
        print(f"| {w} | {name} | {n} | {rho:.3f} (≥ 0.5: {goal}) |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
