"""The Python package against the numpy code a user would write, on the same arrays.

    python python/bench/bench_vs_numpy.py score [--rows N] [--repeat R]
    python python/bench/bench_vs_numpy.py fit   [--rows N] [--repeat R]

Data: `tools/bench_data.py` (rows drawn like the shipped training data), written once
under `target/bench-data/`; the arrays are loaded into memory before
anything is timed. numpy's side is `tools/numpy_layer.py`, the repository's reference
"as a Python user would write it": `Layer` (Algorithm 1 vectorised, float32) for scoring,
`fit_stats` (per class `np.histogram` per head, mean, var) for fitting, plus the same for
the Bayes head's histograms (per category and logit) when the fit has that head.

Every figure is the best of R wall times in this process; mlmap and numpy alternate.
`RAYON_NUM_THREADS=1` pins the package to one core. Peak memory: `fit --memory` runs
`mlmap.fit` in a child process that holds the arrays, and reports how far its peak RSS
rises above the RSS it had before the fit, against the size of the input arrays.
"""

import argparse
import os
import subprocess
import sys
import time

import numpy as np

import mlmap

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import bench_data  # noqa: E402
import numpy_layer  # noqa: E402

TABLE = os.path.join(ROOT, "tables", "default.mlmap")


def arrays(rows):
    """logits (N x 3 float32), labels (int64), objectness (float32), in memory."""
    d = os.path.join(ROOT, "target", "bench-data", f"{rows}")
    if not os.path.exists(os.path.join(d, "classes.txt")):
        bench_data.write(rows, d)
    load = lambda name: np.load(os.path.join(d, name))  # noqa: E731
    return load("logits.npy"), load("labels.npy"), load("objectness.npy")


def best(f, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def header(what, rows, repeat):
    threads = os.environ.get("RAYON_NUM_THREADS", "all")
    print(f"{what}: {rows} rows x 3 classes, {os.cpu_count()} cores "
          f"(RAYON_NUM_THREADS={threads}), numpy {np.__version__}, best of {repeat}")


def cmd_score(a):
    x, _, os_ = arrays(a.rows)
    table = mlmap.Table.load(TABLE)
    layer = numpy_layer.Layer(TABLE, np.float32)

    def np_ml():
        ml = layer.likelihood(x, layer.ml) + layer.lambda_ml
        ml *= os_[:, None] / ml.sum(axis=1, keepdims=True)
        return ml

    def np_map():
        mp = layer.likelihood(x, layer.map) * layer.prior(x) + layer.lambda_map
        mp *= os_[:, None] / mp.sum(axis=1, keepdims=True)
        return mp

    # Same formulas: equal within float32 rounding.
    check = slice(0, 100_000)
    np.testing.assert_allclose(table.ml(x[check], os_[check]), np_ml()[check], atol=1e-5)
    np.testing.assert_allclose(table.map(x[check], os_[check]), np_map()[check], atol=1e-5)
    header("score", a.rows, a.repeat)
    print(f"{'head':6} {'mlmap s':>8} {'ns/row':>7} {'numpy s':>8} {'ns/row':>7} {'speed-up':>8}")
    for head, ref in (("ml", np_ml), ("map", np_map), ("bayes", None)):
        t = best(lambda: table.scores(head, x, os_), a.repeat)
        ns = t / a.rows * 1e9
        if ref is None:
            print(f"{head:6} {t:8.3f} {ns:7.1f} {'-':>8} {'-':>7} {'-':>8}")
            continue
        tn = best(ref, a.repeat)
        print(f"{head:6} {t:8.3f} {ns:7.1f} {tn:8.3f} {tn / a.rows * 1e9:7.1f} {tn / t:7.1f}x")


def numpy_bayes_counts(x, labels, bins=22):
    """The Bayes head's statistics as numpy would compute them: per logit the range over
    every row, then per category (classes, background) and logit a histogram."""
    out = []
    for j in range(x.shape[1]):
        col = x[:, j]
        lo, hi = col.min(), col.max()
        out.append([np.histogram(col[labels == c], bins=bins, range=(lo, hi))[0]
                    for c in range(-1, x.shape[1])])
    return out


def cmd_fit(a):
    x, labels, os_ = arrays(a.rows)
    if a.memory:
        return fit_memory(a, x, labels, os_)
    header("fit", a.rows, a.repeat)
    for bayes in (False, True):
        kw = {} if bayes else {"bayes": None}
        t = best(lambda: mlmap.fit(x, labels, os_, classes=bench_data.gen_data.CLASSES, **kw),
                 a.repeat)
        ref = (lambda: (numpy_layer.fit_stats(x, labels), numpy_bayes_counts(x, labels))) \
            if bayes else (lambda: numpy_layer.fit_stats(x, labels))
        tn = best(ref, a.repeat)
        what = "ML + MAP + Bayes" if bayes else "ML + MAP"
        print(f"{what:17} mlmap {t:7.3f} s ({t / a.rows * 1e9:5.1f} ns/row)   "
              f"numpy {tn:7.3f} s ({tn / a.rows * 1e9:6.1f} ns/row)   {tn / t:5.1f}x")


def fit_memory(a, x, labels, os_):
    """Peak RSS of a child while it fits: the arrays are loaded, the peak is reset
    (Linux: `/proc/self/clear_refs`), `mlmap.fit` runs, and the new peak is read
    (`VmHWM`); against the input arrays' size."""
    code = f"""
import sys, numpy as np, mlmap
sys.path.insert(0, {os.path.join(ROOT, 'tools')!r})
import bench_data
d = {os.path.join(ROOT, 'target', 'bench-data', str(a.rows))!r}
x, y, o = (np.load(d + '/' + n) for n in ('logits.npy', 'labels.npy', 'objectness.npy'))
def status(key):
    for line in open('/proc/self/status'):
        if line.startswith(key + ':'):
            return int(line.split()[1])
with open('/proc/self/clear_refs', 'w') as f:
    f.write('5')
before = status('VmRSS')
t = mlmap.fit(x, y, o, classes=bench_data.gen_data.CLASSES)
print(before, status('VmHWM'))
"""
    before, peak = map(int, subprocess.check_output([sys.executable, "-c", code]).split())
    size = (x.nbytes + labels.nbytes + os_.nbytes) / 1024
    print(f"fit memory: {a.rows} rows; input arrays {size:,.0f} KiB; RSS before mlmap.fit "
          f"{before:,} KiB (interpreter, numpy and the arrays), peak during it {peak:,} KiB: "
          f"+{peak - before:,} KiB ({(peak - before) / size:.2%} of the input arrays)")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    for name, run in (("score", cmd_score), ("fit", cmd_fit)):
        s = sub.add_parser(name)
        s.add_argument("--rows", type=int, default=10_000_000)
        s.add_argument("--repeat", type=int, default=3)
        if name == "fit":
            s.add_argument("--memory", action="store_true")
        s.set_defaults(run=run)
    a = p.parse_args()
    a.run(a)


if __name__ == "__main__":
    main()
