"""Peak memory of `mlmap.Evaluator` on many rows: the process's peak resident set size
during the evaluation (VmHWM, reset through /proc/self/clear_refs once the arrays are
drawn; `resource.getrusage` elsewhere) minus its resident size before it.

    python python/bench/evaluate_memory.py [ROWS] [--one-shot]

ROWS (default 10_000_000) rows of 3 classes are drawn in pieces (float32 logits,
int64 labels, float32 objectness), then given to one `Evaluator.update` call (or to
`mlmap.evaluate` with `--one-shot`, for comparison).
"""

import resource
import sys
import time

import numpy as np

import mlmap

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]


def status_mb(field):
    """VmRSS or VmHWM of /proc/self/status in MB; `None` off Linux."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return None


def reset_peak():
    """Resets VmHWM to the current resident size (Linux 4.0+); False if impossible."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def peak_mb():
    return status_mb("VmHWM") or resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    n = int(args[0]) if args else 10_000_000
    table = mlmap.Table.load(ROOT / "tables" / "default.mlmap")
    k = table.k
    logits = np.empty((n, k), dtype=np.float32)
    labels = np.empty(n, dtype=np.int64)
    obj = np.empty(n, dtype=np.float32)
    rng = np.random.default_rng(0)
    step = 1 << 20
    for a in range(0, n, step):
        b = min(a + step, n)
        y = rng.integers(-1, k, b - a)
        x = rng.normal(0.0, 2.0, (b - a, k)).astype(np.float32)
        x[y >= 0, y[y >= 0]] += 3.0
        logits[a:b], labels[a:b] = x, y
        obj[a:b] = rng.uniform(0.05, 1.0, b - a)
    data_mb = (logits.nbytes + labels.nbytes + obj.nbytes) / 2**20
    reset = reset_peak()
    before = status_mb("VmRSS") if reset else peak_mb()
    t0 = time.perf_counter()
    if "--one-shot" in sys.argv:
        report = mlmap.evaluate(table, logits, labels, obj)
    else:
        ev = mlmap.Evaluator(table)
        ev.update(logits, labels, obj)
        report = ev.report()
    dt = time.perf_counter() - t0
    after = peak_mb()
    print(f"rows {n}, arrays {data_mb:.0f} MB, RSS before {before:.0f} MB, peak during "
          f"{after:.0f} MB: +{after - before:.0f} MB in {dt:.1f} s; "
          f"ml ece {report['methods']['ml']['ece']:.4f}")


if __name__ == "__main__":
    main()
