#!/usr/bin/env python3
"""The paper's Algorithm 1 (ML and MAP layers) vectorised with numpy, as a Python user
would write it, and the numpy side of the benchmarks against mlmap
(tools/bench_vs_numpy.sh).

The table is read from a `.mlmap` file with the decoder of tools/mlmap_ref.py. Per class,
the bin of every logit is found with `np.digitize` against the table's own float32 edges
(docs/FORMAT.md: w = (hi - lo) / B, e_k = lo + k w), so a logit falls in exactly the bin
the layer finds; the likelihood is a lookup in the frequencies padded with a 0 on each
side (0 outside [e_0, e_B]; with the `clamp` upper tail, the last bin above e_B). The
prior is the Gaussian pdf, then ML = OS (L + lambda_ML) / sum, MAP = OS (L P + lambda_MAP)
/ sum. No input checks (NaN, objectness range): a numpy user would not write them.

Precision: `--dtype float32` (the default; logits as loaded, every array float32, the
layer's own precision) or `--dtype float64` (numpy's default precision; logits widened).

    numpy_layer.py time  DIR [--table T] [--reps N] [--dtype D]   # in-process, excludes load
    numpy_layer.py apply DIR OUT.csv [--table T] [--dtype D]      # load + compute + CSV
    numpy_layer.py fit   DIR [--reps N]        # load + per-class min/max, histograms, moments
    numpy_layer.py check DIR SCORES.f32 [--table T]   # compare with examples/batch_timing.rs

`time` and `fit` print one line `key=value ...` (times in seconds, medians of N
repetitions); `apply` and `fit --reps 1` are meant to be timed as whole processes.
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mlmap_ref  # noqa: E402  (table decoder and the float32 edge rule)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_TABLE = os.path.join(ROOT, "tables", "default.mlmap")


class Layer:
    """ML and MAP of one table, for N x K logits at once."""

    def __init__(self, path, dtype=np.float32):
        with open(path, "rb") as fh:
            t = mlmap_ref.decode(fh.read())
        self.dtype = dtype
        self.names = [c["name"] for c in t["classes"]]
        clamp = t["upper_tail"] == 1
        self.lambda_ml = dtype(t["lambda_ml"])
        self.lambda_map = dtype(t["lambda_map"])
        self.ml = [self._head(c["ml_lo"], c["ml_hi"], c["ml_freqs"], clamp)
                   for c in t["classes"]]
        self.map = [self._head(c["map_lo"], c["map_hi"], c["map_freqs"], clamp)
                    for c in t["classes"]]
        mean = np.array([c["mean"] for c in t["classes"]], dtype=np.float64)
        var = np.array([c["var"] for c in t["classes"]], dtype=np.float64)
        self.mean = mean.astype(dtype)
        self.neg_half_inv_var = (-0.5 / var).astype(dtype)
        self.norm = (1.0 / np.sqrt(2.0 * np.pi * var)).astype(dtype)

    def _head(self, lo, hi, freqs, clamp):
        edges = mlmap_ref.edges_f32(lo, hi, len(freqs)).astype(self.dtype)
        f = np.asarray(freqs, dtype=self.dtype)
        # digitize: 0 below e_0, k + 1 in [e_k, e_k+1), B + 1 at or above e_B.
        padded = np.concatenate([[0.0], f, [f[-1] if clamp else 0.0]]).astype(self.dtype)
        return edges, padded

    def likelihood(self, x, heads):
        """L: N x K bin frequencies (numpy.histogram's rule, the last bin closed)."""
        out = np.empty_like(x)
        for c, (edges, padded) in enumerate(heads):
            col = x[:, c]
            idx = np.digitize(col, edges)
            idx[col == edges[-1]] = len(padded) - 2
            out[:, c] = padded[idx]
        return out

    def prior(self, x):
        d = x - self.mean
        return self.norm * np.exp(d * d * self.neg_half_inv_var)

    def scores(self, x, objectness):
        """(ML, MAP), each N x K, summing to the objectness per row."""
        os_col = objectness[:, None]
        ml = self.likelihood(x, self.ml) + self.lambda_ml
        ml *= os_col / ml.sum(axis=1, keepdims=True)
        mp = self.likelihood(x, self.map) * self.prior(x) + self.lambda_map
        mp *= os_col / mp.sum(axis=1, keepdims=True)
        return ml, mp


def load(d, dtype, objectness=True):
    x = np.load(os.path.join(d, "logits.npy")).astype(dtype, copy=False)
    labels = np.load(os.path.join(d, "labels.npy"))
    os_ = np.load(os.path.join(d, "objectness.npy")).astype(dtype, copy=False) \
        if objectness else None
    return x, labels, os_


def cmd_time(a):
    dtype = np.dtype(a.dtype).type
    layer = Layer(a.table, dtype)
    x, _, os_ = load(a.dir, dtype)
    total, ml_t, map_t = [], [], []
    for _ in range(a.reps):
        t0 = time.perf_counter()
        ml = layer.likelihood(x, layer.ml) + layer.lambda_ml
        ml *= os_[:, None] / ml.sum(axis=1, keepdims=True)
        t1 = time.perf_counter()
        mp = layer.likelihood(x, layer.map) * layer.prior(x) + layer.lambda_map
        mp *= os_[:, None] / mp.sum(axis=1, keepdims=True)
        t2 = time.perf_counter()
        ml_t.append(t1 - t0)
        map_t.append(t2 - t1)
        total.append(t2 - t0)
    n = len(x)
    print("numpy_layer rows=%d reps=%d dtype=%s numpy=%s ml_s=%.6f map_s=%.6f total_s=%.6f "
          "ns_per_detection=%.2f" % (n, a.reps, a.dtype, np.__version__, np.median(ml_t),
                                     np.median(map_t), np.median(total),
                                     np.median(total) / n * 1e9))


def cmd_apply(a):
    dtype = np.dtype(a.dtype).type
    layer = Layer(a.table, dtype)
    x, labels, os_ = load(a.dir, dtype)
    ml, mp = layer.scores(x, os_)
    names = np.array(layer.names + ["background"], dtype=object)
    k = len(layer.names)
    rows = np.empty((len(x), 2 * k + 3), dtype=object)
    rows[:, 0] = names[labels]  # -1 (background) is the last name
    rows[:, 1:1 + k] = ml
    rows[:, 1 + k:1 + 2 * k] = mp
    rows[:, 1 + 2 * k] = names[ml.argmax(axis=1)]
    rows[:, 2 + 2 * k] = names[mp.argmax(axis=1)]
    header = ",".join(["label"] + ["ml_" + n for n in layer.names]
                      + ["map_" + n for n in layer.names] + ["ml_pred", "map_pred"])
    fmt = ["%s"] + ["%.9g"] * (2 * k) + ["%s", "%s"]
    np.savetxt(a.output, rows, fmt=fmt, delimiter=",", header=header, comments="")


def fit_stats(x, labels, bins=(22, 17)):
    """Per class: count, min, max, the histograms with each bin count, mean, var (ddof 1)."""
    out = []
    for c in range(x.shape[1]):
        v = x[labels == c, c]
        lo, hi = v.min(), v.max()
        hists = [np.histogram(v, bins=b, range=(lo, hi))[0] / len(v) for b in bins]
        out.append((len(v), lo, hi, hists, v.mean(dtype=np.float64), v.var(dtype=np.float64, ddof=1)))
    return out


def cmd_fit(a):
    load_t, stats_t, total = [], [], []
    for _ in range(a.reps):
        t0 = time.perf_counter()
        x = np.load(os.path.join(a.dir, "logits.npy"))
        labels = np.load(os.path.join(a.dir, "labels.npy"))
        t1 = time.perf_counter()
        stats = fit_stats(x, labels)
        t2 = time.perf_counter()
        load_t.append(t1 - t0)
        stats_t.append(t2 - t1)
        total.append(t2 - t0)
        del x, labels
    print("numpy_fit rows=%s reps=%d numpy=%s load_s=%.6f stats_s=%.6f total_s=%.6f "
          "counts=%s" % (sum(s[0] for s in stats) if stats else 0, a.reps, np.__version__,
                         np.median(load_t), np.median(stats_t), np.median(total),
                         "/".join(str(s[0]) for s in stats)))


def cmd_check(a):
    """Compares mlmap's batch scores (ML then MAP, N x K float32 each) with numpy's."""
    layer = Layer(a.table, np.float64)
    x, _, os_ = load(a.dir, np.float64)
    ml, mp = layer.scores(x, os_)
    got = np.fromfile(a.scores, dtype="<f4")
    if got.size != 2 * ml.size:
        sys.exit("check: %s holds %d values, expected %d" % (a.scores, got.size, 2 * ml.size))
    g_ml, g_map = got[:ml.size].reshape(ml.shape), got[ml.size:].reshape(mp.shape)
    worst = max(np.abs(g_ml - ml).max(), np.abs(g_map - mp).max())
    same = np.mean(g_ml.argmax(1) == ml.argmax(1)), np.mean(g_map.argmax(1) == mp.argmax(1))
    print("check rows=%d max_abs_diff=%.3g argmax_agreement_ml=%.6f argmax_agreement_map=%.6f"
          % (len(x), worst, same[0], same[1]))
    if not worst <= 1e-5:
        sys.exit("check: mlmap and numpy disagree")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("time")
    s.add_argument("dir")
    s.add_argument("--table", default=DEFAULT_TABLE)
    s.add_argument("--reps", type=int, default=7)
    s.add_argument("--dtype", choices=["float32", "float64"], default="float32")
    s.set_defaults(run=cmd_time)
    s = sub.add_parser("apply")
    s.add_argument("dir")
    s.add_argument("output")
    s.add_argument("--table", default=DEFAULT_TABLE)
    s.add_argument("--dtype", choices=["float32", "float64"], default="float32")
    s.set_defaults(run=cmd_apply)
    s = sub.add_parser("fit")
    s.add_argument("dir")
    s.add_argument("--reps", type=int, default=1)
    s.set_defaults(run=cmd_fit)
    s = sub.add_parser("check")
    s.add_argument("dir")
    s.add_argument("scores")
    s.add_argument("--table", default=DEFAULT_TABLE)
    s.set_defaults(run=cmd_check)
    a = p.parse_args()
    a.run(a)


if __name__ == "__main__":
    main()
