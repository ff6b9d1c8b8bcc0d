#!/usr/bin/env python3
"""Writes the synthetic detector dataset shipped in examples/data/ (seeded, reproducible).

The data is SYNTHETIC. It mimics the setting of the ML/MAP paper on KITTI with a
YOLOv4-like detector: three road-user classes with strong class imbalance (car >>
pedestrian > cyclist), an objectness score per detection, confusions between cyclist and
pedestrian, background false positives whose logits a Sigmoid maps to high confidence,
and an out-of-distribution set of never-seen objects (animals, debris, ...) whose logits
fall outside what the training true positives produced.

    python3 tools/gen_data.py            # rewrites examples/data/{train,val,test,ood}.csv

Columns: id,label,objectness,car,cyclist,pedestrian (DESIGN §2).
"""
import csv
import os
import sys

import numpy as np

CLASSES = ["car", "cyclist", "pedestrian"]
# Share of true objects per class (KITTI-like imbalance) and their own-logit Gaussians.
SHARE = np.array([0.70, 0.10, 0.20])
OWN_MU = np.array([4.2, 2.6, 3.1])
OWN_SD = np.array([1.1, 1.2, 1.0])
SEED = 20261122


def true_objects(rng, n):
    label = rng.choice(3, size=n, p=SHARE)
    logits = rng.normal(-3.5, 1.3, size=(n, 3))
    own = rng.normal(OWN_MU[label], OWN_SD[label])
    # Heavy upper tail: a few very confident true positives.
    own += rng.exponential(0.4, size=n) * (rng.random(n) < 0.15)
    logits[np.arange(n), label] = own
    # Cyclists and pedestrians look alike: the other one's logit is raised.
    cp = (label == 1) | (label == 2)
    other = np.where(label == 1, 2, 1)
    raise_ = cp & (rng.random(n) < 0.35)
    logits[np.where(raise_)[0], other[raise_]] = rng.normal(1.0, 1.4, size=raise_.sum())
    # Some of them are outright confused (argmax wrong): a false positive for eval.
    swap = cp & (rng.random(n) < 0.06)
    idx = np.where(swap)[0]
    a, b = label[idx], other[idx]
    tmp = logits[idx, a].copy()
    logits[idx, a] = logits[idx, b]
    logits[idx, b] = tmp
    os_ = rng.beta(9.0, 1.8, size=n)
    return [CLASSES[i] for i in label], os_, logits


def background(rng, n):
    """False positives: one class gets a high-ish logit, Sigmoid says 0.8-0.99."""
    logits = rng.normal(-3.0, 1.5, size=(n, 3))
    which = rng.choice(3, size=n, p=[0.6, 0.15, 0.25])
    logits[np.arange(n), which] = rng.normal(1.8, 1.6, size=n)
    os_ = rng.beta(4.0, 2.5, size=n)
    return ["background"] * n, os_, logits


def unseen(rng, n):
    """Never-seen objects: logits outside the training true positives' range."""
    logits = rng.normal(-9.0, 1.5, size=(n, 3))
    which = rng.choice(3, size=n)
    hi = rng.random(n) < 0.5
    # Half: one logit far above anything seen for that class (Sigmoid says 0.9999);
    # half: every logit far below (all classes unlike training).
    logits[np.where(hi)[0], which[hi]] = rng.normal(11.0, 1.0, size=hi.sum())
    os_ = rng.beta(7.0, 2.0, size=n)
    return ["background"] * n, os_, logits


def write(path, parts, rng, start_id):
    labels, os_, logits = [], [], []
    for lab, o, x in parts:
        labels += lab
        os_.append(o)
        logits.append(x)
    os_ = np.concatenate(os_)
    logits = np.concatenate(logits)
    order = rng.permutation(len(labels))
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(["id", "label", "objectness"] + CLASSES)
        for j, i in enumerate(order):
            w.writerow([start_id + j, labels[i], f"{os_[i]:.4f}"] + [f"{v:.4f}" for v in logits[i]])
    return start_id + len(labels)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "examples", "data")
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(SEED)
    nid = 1
    nid = write(os.path.join(out, "train.csv"), [true_objects(rng, 16000), background(rng, 4000)], rng, nid)
    nid = write(os.path.join(out, "val.csv"), [true_objects(rng, 4000), background(rng, 1000)], rng, nid)
    nid = write(os.path.join(out, "test.csv"), [true_objects(rng, 8000), background(rng, 2000)], rng, nid)
    write(os.path.join(out, "ood.csv"), [unseen(rng, 2000)], rng, nid)


if __name__ == "__main__":
    main()
