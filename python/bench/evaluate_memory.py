"""Peak memory of `mlmap.Evaluator` on many rows: the process's peak resident set size
during the evaluation (VmHWM, reset through /proc/self/clear_refs once the arrays are
read; `resource.getrusage` elsewhere) minus its resident size before it.

    python python/bench/evaluate_memory.py [ROWS] [--one-shot]

ROWS (default 10_000_000) rows of 3 classes (float32 logits, int64 labels, float32
objectness) are drawn once into NPY files under target/bench-data/, read whole by a
fresh process, then given to one `Evaluator.update` call (or to `mlmap.evaluate` with
`--one-shot`, for comparison).
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


def write_data(d, n, k):
    """Draws the rows into NPY files under `d` a piece at a time (once per size)."""
    if (d / "done").exists():
        return
    d.mkdir(parents=True, exist_ok=True)
    fmt = np.lib.format
    logits = fmt.open_memmap(d / "logits.npy", "w+", np.float32, (n, k))
    labels = fmt.open_memmap(d / "labels.npy", "w+", np.int64, (n,))
    obj = fmt.open_memmap(d / "objectness.npy", "w+", np.float32, (n,))
    rng = np.random.default_rng(0)
    step = 1 << 20
    for a in range(0, n, step):
        b = min(a + step, n)
        y = rng.integers(-1, k, b - a)
        x = rng.normal(0.0, 2.0, (b - a, k)).astype(np.float32)
        x[y >= 0, y[y >= 0]] += 3.0
        logits[a:b], labels[a:b] = x, y
        obj[a:b] = rng.uniform(0.05, 1.0, b - a)
    for m in (logits, labels, obj):
        m.flush()
    del logits, labels, obj
    (d / "done").write_text("")


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    n = int(args[0]) if args else 10_000_000
    table = mlmap.Table.load(ROOT / "tables" / "default.mlmap")
    k = table.k
    d = ROOT / "target" / "bench-data" / f"evaluate-{n}"
    if "--child" not in sys.argv and "--write" not in sys.argv:
        # The rows are drawn by another process, so that this one holds nothing but
        # the arrays when it starts evaluating.
        import subprocess
        subprocess.run([sys.executable, __file__, str(n), "--write"], check=True)
        subprocess.run([sys.executable, __file__, str(n), "--child",
                        *[a for a in sys.argv[1:] if a == "--one-shot"]], check=True)
        return
    if "--write" in sys.argv:
        write_data(d, n, k)
        return
    logits = np.load(d / "logits.npy")
    labels = np.load(d / "labels.npy")
    obj = np.load(d / "objectness.npy")
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
