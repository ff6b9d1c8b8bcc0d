#!/usr/bin/env python3
"""mlmap against numpy on the same NPY inputs: the layer in-process, `mlmap apply` end
to end, `mlmap fit`, and the peak memory of the fit at two row counts.

    python3 tools/bench_vs_numpy.py [--rows 1000000] [--big-rows 10000000]
                                    [--rounds 5] [--data DIR] [--skip-build]

Builds `mlmap` and `examples/batch_timing.rs` (release, features cli,micromath), writes
the inputs with tools/bench_data.py into DIR (default target/bench-data, reused when
present; never committed), checks that mlmap and numpy compute the same scores, then
runs every comparison in ROUNDS rounds, mlmap and numpy alternating within each round,
and reports the median over rounds of each side and of the per-round ratio. The machine
may be shared: only ratios measured in the same round are meaningful.

Comparisons (numpy side: tools/numpy_layer.py, float32 unless said otherwise):
  layer   ml_batch + map_batch over every row, in-process, median of 7 repetitions,
          against numpy's vectorised Algorithm 1 over the same arrays (load excluded);
          goal: mlmap >= 10x faster.
  apply   `mlmap apply` (whole process) against numpy load + compute + CSV write with
          the same columns (whole process).
  fit     `mlmap fit` (whole process: both streaming passes, writing the table) against
          numpy's load + per-class min/max, histograms (22 and 17 bins), mean and
          variance, timed inside the process (interpreter start-up excluded, which
          favours numpy); goal: mlmap <= 0.5x.
  memory  peak RSS of `mlmap fit` at ROWS and BIG_ROWS (goal: flat), and of numpy's fit.
"""
import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOOLS = os.path.join(ROOT, "tools")
TABLE = os.path.join(ROOT, "tables", "default.mlmap")
PY = sys.executable


def run(cmd, **kw):
    """Runs cmd; returns (wall seconds, stdout). Fails loudly."""
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit("bench: %s failed (%d):\n%s%s" % (" ".join(cmd), p.returncode, p.stdout,
                                                   p.stderr))
    return wall, p.stdout


def fields(line):
    """The key=value pairs of a result line."""
    return {k: v for k, v in re.findall(r"(\w+)=(\S+)", line)}


def peak_rss_kib(cmd):
    """Peak resident set size of cmd, in KiB (/usr/bin/time -v, else getrusage)."""
    if os.path.exists("/usr/bin/time"):
        p = subprocess.run(["/usr/bin/time", "-v"] + cmd, stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True)
        m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
        if p.returncode == 0 and m:
            return int(m.group(1)), "/usr/bin/time -v"
    probe = ("import resource, subprocess, sys\n"
             "subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, check=True)\n"
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n")
    _, out = run([PY, "-c", probe] + cmd)
    return int(out.split()[-1]), "getrusage(RUSAGE_CHILDREN)"


def med(v):
    return statistics.median(v)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--big-rows", type=int, default=10_000_000)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--data", default=os.path.join(ROOT, "target", "bench-data"))
    ap.add_argument("--skip-build", action="store_true")
    a = ap.parse_args()

    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    mlmap = os.path.join(target, "release", "mlmap")
    timing = os.path.join(target, "release", "examples", "batch_timing")
    if not a.skip_build:
        print("building: cargo build --release --features cli,micromath --bin mlmap "
              "--example batch_timing", flush=True)
        subprocess.run(["cargo", "build", "--quiet", "--release", "--features", "cli,micromath",
                        "--bin", "mlmap", "--example", "batch_timing"], cwd=ROOT, check=True)

    def data(n):
        d = os.path.join(a.data, str(n))
        if not os.path.exists(os.path.join(d, "classes.txt")):
            print("writing %d rows to %s" % (n, d), flush=True)
            run([PY, os.path.join(TOOLS, "bench_data.py"), str(n), d])
        return d

    small, big = data(a.rows), data(a.big_rows)
    work = tempfile.mkdtemp(prefix="mlmap-bench-")
    try:
        report(a, mlmap, timing, small, big, work)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def report(a, mlmap, timing, small, big, work):
    numpy_layer = os.path.join(TOOLS, "numpy_layer.py")
    scores = os.path.join(work, "scores.f32")
    run([timing, small, "--table", TABLE, "--reps", "1", "--dump", scores])
    _, out = run([PY, numpy_layer, "check", small, scores, "--table", TABLE])
    print(out.strip())

    rows = {}
    keys = ["mlmap_ns", "mlmap_fast_ns", "np32_ns", "np64_ns", "layer_x32", "layer_x64",
            "apply_mlmap_s", "apply_numpy_s", "apply_x", "fit_mlmap_s", "fit_numpy_s",
            "fit_numpy_wall_s", "fit_ratio", "fit_ratio_wall"]
    for k in keys:
        rows[k] = []
    n = None
    for r in range(a.rounds):
        print("round %d/%d" % (r + 1, a.rounds), flush=True)
        # Layer, in-process.
        _, out = run([timing, small, "--table", TABLE, "--reps", "7"])
        m = fields(out)
        n = int(m["rows"])
        ml_ns = float(m["total_s"]) / n * 1e9
        _, out = run([PY, numpy_layer, "time", small, "--table", TABLE, "--reps", "7",
                      "--dtype", "float32"])
        np32 = float(fields(out)["total_s"]) / n * 1e9
        _, out = run([PY, numpy_layer, "time", small, "--table", TABLE, "--reps", "7",
                      "--dtype", "float64"])
        np64 = float(fields(out)["total_s"]) / n * 1e9
        rows["mlmap_ns"].append(ml_ns)
        if "map_fast_s" in m:
            fast = (float(m["ml_s"]) + float(m["map_fast_s"])) / n * 1e9
            rows["mlmap_fast_ns"].append(fast)
        rows["np32_ns"].append(np32)
        rows["np64_ns"].append(np64)
        rows["layer_x32"].append(np32 / ml_ns)
        rows["layer_x64"].append(np64 / ml_ns)
        # apply, end to end.
        t_m, _ = run([mlmap, "apply", "--table", TABLE, "--input", small,
                      "--output", os.path.join(work, "mlmap.csv")])
        t_n, _ = run([PY, numpy_layer, "apply", small, os.path.join(work, "numpy.csv"),
                      "--table", TABLE])
        rows["apply_mlmap_s"].append(t_m)
        rows["apply_numpy_s"].append(t_n)
        rows["apply_x"].append(t_n / t_m)
        # fit.
        t_m, _ = run([mlmap, "fit", "--train", small, "--output", os.path.join(work, "t.mlmap")])
        t_w, out = run([PY, numpy_layer, "fit", small])
        t_n = float(fields(out)["total_s"])
        rows["fit_mlmap_s"].append(t_m)
        rows["fit_numpy_s"].append(t_n)
        rows["fit_numpy_wall_s"].append(t_w)
        rows["fit_ratio"].append(t_m / t_n)
        rows["fit_ratio_wall"].append(t_m / t_w)

    with open(os.path.join(work, "mlmap.csv")) as fa, open(os.path.join(work, "numpy.csv")) as fb:
        same_header = fa.readline() == fb.readline()

    rss = {}
    for name, d in (("small", small), ("big", big)):
        rss["mlmap_" + name], how = peak_rss_kib([mlmap, "fit", "--train", d, "--output",
                                                  os.path.join(work, "t.mlmap")])
        rss["numpy_" + name], _ = peak_rss_kib([PY, numpy_layer, "fit", d])

    import numpy  # noqa: F401  (version only)
    ok = lambda b: "met" if b else "MISSED"  # noqa: E731
    print()
    print("mlmap against numpy %s (%s), %d rows, %d rounds, medians over rounds"
          % (numpy.__version__, sys.version.split()[0], n, a.rounds))
    x32, x64 = med(rows["layer_x32"]), med(rows["layer_x64"])
    print("layer in-process: mlmap %.1f ns/detection (ML + MAP), numpy float32 %.1f, "
          "float64 %.1f" % (med(rows["mlmap_ns"]), med(rows["np32_ns"]), med(rows["np64_ns"])))
    if rows["mlmap_fast_ns"]:
        print("  (mlmap ML + fast-math MAP: %.1f ns/detection)" % med(rows["mlmap_fast_ns"]))
    print("  ratio numpy/mlmap: %.1fx (float32), %.1fx (float64); goal >= 10x: %s"
          % (x32, x64, ok(min(x32, x64) >= 10)))
    print("apply end to end: mlmap %.3f s, numpy %.3f s (same columns: %s); ratio %.1fx"
          % (med(rows["apply_mlmap_s"]), med(rows["apply_numpy_s"]),
             "yes" if same_header else "NO", med(rows["apply_x"])))
    fr = med(rows["fit_ratio"])
    print("fit: mlmap %.3f s (whole command), numpy %.3f s (load + histograms + moments, "
          "in-process; %.3f s as a whole process)"
          % (med(rows["fit_mlmap_s"]), med(rows["fit_numpy_s"]), med(rows["fit_numpy_wall_s"])))
    print("  mlmap/numpy: %.2fx in-process numpy, %.2fx whole-process numpy; goal <= 0.5x: %s"
          % (fr, med(rows["fit_ratio_wall"]), ok(fr <= 0.5)))
    print("peak RSS (%s): mlmap fit %d KiB at %d rows, %d KiB at %d rows (x%.2f for x%d rows); "
          "goal flat: %s" % (how, rss["mlmap_small"], a.rows, rss["mlmap_big"], a.big_rows,
                             rss["mlmap_big"] / rss["mlmap_small"], a.big_rows // a.rows,
                             ok(rss["mlmap_big"] <= 1.1 * rss["mlmap_small"])))
    print("  numpy fit: %d KiB at %d rows, %d KiB at %d rows"
          % (rss["numpy_small"], a.rows, rss["numpy_big"], a.big_rows))
    print("per round: " + " ".join("%s=%s" % (k, ",".join("%.3g" % v for v in rows[k]))
                                   for k in ("layer_x32", "apply_x", "fit_ratio")))


if __name__ == "__main__":
    main()
