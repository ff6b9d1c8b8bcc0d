#!/usr/bin/env python3
"""Writes data sets that mlmap's defaults were never chosen on, to check its claims.

    python3 tools/holdout_data.py OUT_DIR

writes, each as train.csv, val.csv, test.csv and ood.csv (DESIGN §2):

* OUT_DIR/detector-<seed>/ for three seeds: detector-like data from the generators of
  tools/gen_data.py with their parameters perturbed per seed (class shares, the own-logit
  means and spreads, the background rate), so no setting can be tuned to one draw;
* OUT_DIR/digits/: the logits of a real classifier, scikit-learn's multinomial logistic
  regression on the bundled 8x8 digits, trained on digits 0-6; its test rows are held-out
  digits 0-6 and its never-seen objects are the digits 7-9. No objectness, no background
  rows: the case where tie-safe decisions matter most.

Everything is seeded; scikit-learn and numpy are the only dependencies.
"""
import csv
import importlib.util
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = (101, 202, 303)


def load_gen_data():
    spec = importlib.util.spec_from_file_location("gen_data", os.path.join(HERE, "gen_data.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def detector(out, seed):
    g = load_gen_data()
    rng = np.random.default_rng(seed)
    share = g.SHARE * rng.uniform(0.6, 1.4, size=3)
    g.SHARE = share / share.sum()
    g.OWN_MU = g.OWN_MU + rng.normal(0.0, 0.5, size=3)
    g.OWN_SD = g.OWN_SD * rng.uniform(0.8, 1.25, size=3)
    bg = rng.uniform(0.15, 0.35)  # share of background rows
    n_train, n_val, n_test = 16000, 5000, 10000
    os.makedirs(out, exist_ok=True)
    nid = 1
    for name, n in (("train", n_train), ("val", n_val), ("test", n_test)):
        nb = int(n * bg)
        nid = g.write(os.path.join(out, f"{name}.csv"),
                      [g.true_objects(rng, n - nb), g.background(rng, nb)], rng, nid)
    g.write(os.path.join(out, "ood.csv"), [g.unseen(rng, 2000)], rng, nid)


def write_plain(path, names, labels, logits, start):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["id", "label"] + names)
        for i, (lab, row) in enumerate(zip(labels, logits)):
            w.writerow([start + i, lab] + [f"{v:.6f}" for v in row])
    return start + len(labels)


def digits(out):
    from sklearn.datasets import load_digits
    from sklearn.linear_model import LogisticRegression

    x, y = load_digits(return_X_y=True)
    rng = np.random.default_rng(7)
    order = rng.permutation(len(y))
    x, y = x[order] / 16.0, y[order]
    known = y <= 6
    xk, yk = x[known], y[known]
    n = len(yk)
    tr, va = int(0.5 * n), int(0.7 * n)
    clf = LogisticRegression(C=10.0, max_iter=5000)
    clf.fit(xk[:tr], yk[:tr])
    names = [f"digit{d}" for d in range(7)]
    os.makedirs(out, exist_ok=True)
    nid = 1
    for name, sl in (("train", slice(0, tr)), ("val", slice(tr, va)), ("test", slice(va, n))):
        logits = clf.decision_function(xk[sl])
        nid = write_plain(os.path.join(out, f"{name}.csv"), names,
                          [names[c] for c in yk[sl]], logits, nid)
    logits = clf.decision_function(x[~known])
    write_plain(os.path.join(out, "ood.csv"), names, ["background"] * len(logits), logits, nid)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "mlmap-holdout"
    for seed in SEEDS:
        detector(os.path.join(out, f"detector-{seed}"), seed)
    digits(os.path.join(out, "digits"))
    print(f"wrote {out}/detector-{{{','.join(map(str, SEEDS))}}} and {out}/digits")


if __name__ == "__main__":
    main()
