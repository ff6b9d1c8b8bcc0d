#!/usr/bin/env python3
"""Writes a big synthetic NPY directory (DESIGN §2) for the benchmarks against numpy.

The rows are drawn like the shipped training data (tools/gen_data.py, imported): 80 %
true objects of the three road-user classes, 20 % background false positives, shuffled.
They are written chunk by chunk into memory-mapped arrays, so 10 million rows need about
as little memory as one.

    python3 tools/bench_data.py 1000000 /tmp/mlmap-bench/1m      # ~17 MB
    python3 tools/bench_data.py 10000000 /tmp/mlmap-bench/10m    # ~170 MB

Files: logits.npy (float32, N x 3), labels.npy (int64, -1 = background),
objectness.npy (float32), classes.txt (car, cyclist, pedestrian). Seeded: the same N
gives the same bytes. Big outputs belong outside the repository (/tmp or target/).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gen_data  # noqa: E402

CHUNK = 1_000_000
TRUE_SHARE = 0.8
SEED = 4_2026


def chunk(rng, n):
    """n shuffled rows: (logits float32 n x 3, labels int64, objectness float32)."""
    n_true = int(round(n * TRUE_SHARE))
    index = {name: i for i, name in enumerate(gen_data.CLASSES)}
    index["background"] = -1
    labels, os_, logits = [], [], []
    for lab, o, x in (gen_data.true_objects(rng, n_true), gen_data.background(rng, n - n_true)):
        labels.append(np.fromiter((index[s] for s in lab), dtype=np.int64, count=len(lab)))
        os_.append(o)
        logits.append(x)
    order = rng.permutation(n)
    return (np.concatenate(logits)[order].astype(np.float32),
            np.concatenate(labels)[order],
            np.concatenate(os_)[order].astype(np.float32))


def write(n, out):
    os.makedirs(out, exist_ok=True)
    mm = np.lib.format.open_memmap
    logits = mm(os.path.join(out, "logits.npy"), mode="w+", dtype=np.float32, shape=(n, 3))
    labels = mm(os.path.join(out, "labels.npy"), mode="w+", dtype=np.int64, shape=(n,))
    objectness = mm(os.path.join(out, "objectness.npy"), mode="w+", dtype=np.float32,
                    shape=(n,))
    for i, start in enumerate(range(0, n, CHUNK)):
        stop = min(n, start + CHUNK)
        x, lab, o = chunk(np.random.default_rng([SEED, i]), stop - start)
        logits[start:stop], labels[start:stop], objectness[start:stop] = x, lab, o
    for a in (logits, labels, objectness):
        a.flush()
    del logits, labels, objectness
    with open(os.path.join(out, "classes.txt"), "w") as fh:
        fh.write("".join(c + "\n" for c in gen_data.CLASSES))


def main():
    if len(sys.argv) != 3:
        print(__doc__)
        sys.exit(2)
    n = int(sys.argv[1])
    if n < 1:
        sys.exit("bench_data: N must be at least 1")
    write(n, sys.argv[2])
    print("wrote %d rows to %s" % (n, sys.argv[2]))


if __name__ == "__main__":
    main()
