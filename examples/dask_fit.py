#!/usr/bin/env python3
"""Fits an mlmap table from a directory of NPY shards on a dask.distributed cluster.

Each shard is an NPY directory of DESIGN §2 (logits.npy, labels.npy, optionally
objectness.npy and classes.txt). The fit runs as two map passes and two tree
reductions, and gives the bytes of `mlmap.fit` (and of `mlmap fit`) on all the rows:

  1. pass (a): every worker reads its shards and returns their `mlmap.FitStats`;
  2. the statistics are merged pairwise up a tree (exact: any order gives the same);
  3. the merged statistics give the edges of every histogram (`FitStats.edges`), which
     are broadcast to every worker;
  4. pass (b): every worker counts its shards over those edges (`mlmap.FitCounts`);
  5. the counts are merged pairwise up a tree;
  6. `mlmap.finish(stats, counts)` builds the table.

Only statistics, edges and counts (a few KiB each) cross process boundaries; the rows stay
where they are read.

    python examples/dask_fit.py [SHARDS_DIR] [--workers 2] [--output table.mlmap]
    python examples/dask_fit.py --bench-rows 10000000    # 8 shards of tools/bench_data.py rows

Without SHARDS_DIR, the shipped training data (examples/data/train.csv) is written as 8
shards into a temporary directory first. The fit settings are those of `mlmap.fit`
(`--no-bayes`, `--edges matlab`, ...).
"""

import argparse
import csv
import operator
import os
import pathlib
import sys
import tempfile
import time

import numpy as np

import mlmap

ROOT = pathlib.Path(__file__).resolve().parents[1]


def read_shard(path):
    """The arrays of one NPY shard: logits, labels, objectness (or None), class names."""
    path = pathlib.Path(path)
    logits = np.load(path / "logits.npy", mmap_mode="r")
    labels = np.load(path / "labels.npy", mmap_mode="r")
    obj = path / "objectness.npy"
    objectness = np.load(obj, mmap_mode="r") if obj.exists() else None
    names = path / "classes.txt"
    classes = names.read_text().split() if names.exists() else None
    return logits, labels, objectness, classes


def stats_of(path):
    """Pass (a) of one shard."""
    logits, labels, objectness, classes = read_shard(path)
    return mlmap.FitStats(logits, labels, objectness, classes=classes)


def counts_of(path, edges):
    """Pass (b) of one shard over the broadcast edges."""
    logits, labels, objectness, _ = read_shard(path)
    return mlmap.FitCounts(edges, logits, labels, objectness)


def peak_rss_kib():
    """This process's peak resident memory (Linux: KiB)."""
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def tree_reduce(client, futures):
    """Merges futures pairwise, level by level, on the workers."""
    while len(futures) > 1:
        pairs = [client.submit(operator.add, a, b) for a, b in zip(futures[::2], futures[1::2])]
        futures = pairs + futures[len(pairs) * 2:]
    return futures[0]


def fit_shards(client, shards, **settings):
    """The table of every row of `shards` (paths of NPY directories), fitted on the
    cluster of `client` with the settings of `mlmap.fit`."""
    import cloudpickle

    # Workers may not be able to import this file as a module: ship its functions by
    # value (cloudpickle does so by itself for `__main__` and unregistered modules).
    module = sys.modules.get(__name__)
    if module is not None and __name__ != "__main__":
        cloudpickle.register_pickle_by_value(module)
    shards = [str(s) for s in shards]
    stats = tree_reduce(client, client.map(stats_of, shards, pure=False))
    edges = client.submit(lambda s: s.edges(**settings), stats).result()
    [edges_everywhere] = client.scatter([edges], broadcast=True)
    counts = tree_reduce(
        client, client.map(counts_of, shards, edges=edges_everywhere, pure=False))
    return mlmap.finish(stats.result(), counts.result())


def write_shards(out, parts=8, source=ROOT / "examples" / "data" / "train.csv"):
    """Writes the rows of a data CSV (DESIGN §2) as `parts` NPY shards; returns their
    paths. Logits stay float64, as the CSV reader reads them, so the table is the CLI's."""
    with open(source, newline="") as f:
        rows = list(csv.DictReader(f))
    classes = [c for c in rows[0] if c not in ("id", "label", "objectness")]
    logits = np.array([[float(r[c]) for c in classes] for r in rows])
    labels = np.array([classes.index(r["label"]) if r["label"] in classes else -1
                       for r in rows])
    objectness = np.array([float(r["objectness"]) for r in rows])
    paths = []
    for i, idx in enumerate(np.array_split(np.arange(len(rows)), parts)):
        p = pathlib.Path(out) / f"shard-{i:03d}"
        p.mkdir(parents=True, exist_ok=True)
        np.save(p / "logits.npy", logits[idx])
        np.save(p / "labels.npy", labels[idx])
        np.save(p / "objectness.npy", objectness[idx])
        (p / "classes.txt").write_text("".join(c + "\n" for c in classes))
        paths.append(p)
    return paths


def bench_shards(rows, parts=8):
    """`parts` shards of `rows` rows drawn like the training data (tools/bench_data.py),
    written once under target/bench-data/."""
    sys.path.insert(0, str(ROOT / "tools"))
    import bench_data

    whole = ROOT / "target" / "bench-data" / f"{rows}"
    if not (whole / "classes.txt").exists():
        bench_data.write(rows, str(whole))
    out = ROOT / "target" / "bench-data" / f"shards-{rows}"
    paths = [out / f"shard-{i:03d}" for i in range(parts)]
    if not all((p / "classes.txt").exists() for p in paths):
        arrays = {n: np.load(whole / n, mmap_mode="r")
                  for n in ("logits.npy", "labels.npy", "objectness.npy")}
        for i, p in enumerate(paths):
            p.mkdir(parents=True, exist_ok=True)
            lo, hi = i * rows // parts, (i + 1) * rows // parts
            for name, a in arrays.items():
                np.save(p / name, a[lo:hi])
            (p / "classes.txt").write_text((whole / "classes.txt").read_text())
    return paths


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("shards", nargs="?", help="a directory of NPY shard directories")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--output", default="dask-fit.mlmap")
    p.add_argument("--no-bayes", action="store_true")
    p.add_argument("--edges", default="linspace", choices=["linspace", "matlab"])
    p.add_argument("--bench-rows", type=int, default=0,
                   help="write 8 shards of N rows of tools/bench_data.py (under target/) and fit them")
    a = p.parse_args(argv)

    from dask.distributed import Client, LocalCluster

    with tempfile.TemporaryDirectory() as tmp:
        if a.bench_rows:
            shards = bench_shards(a.bench_rows)
        elif a.shards:
            shards = sorted(q for q in pathlib.Path(a.shards).iterdir() if q.is_dir())
        else:
            shards = write_shards(tmp)
            print(f"wrote {len(shards)} shards of examples/data/train.csv to {tmp}")
        # One thread per worker process, and mlmap's own pool to one thread in each:
        # the workers are the parallelism.
        with LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                          env={"RAYON_NUM_THREADS": "1"}) as cluster, Client(cluster) as client:
            idle = client.run(peak_rss_kib)
            t0 = time.perf_counter()
            settings = {"edges": a.edges}
            if a.no_bayes:
                settings["bayes"] = None
            table = fit_shards(client, shards, **settings)
            took = time.perf_counter() - t0
            peaks = client.run(peak_rss_kib)
        table.save(a.output)
        rows = sum(len(np.load(pathlib.Path(q) / "labels.npy", mmap_mode="r")) for q in shards)
        print(f"fitted {len(shards)} shards ({rows} rows) on {a.workers} workers in "
              f"{took:.2f} s: {rows / took / a.workers / 1e6:.2f} M rows/s per worker; "
              f"peak RSS per worker {sorted(peaks.values())} KiB "
              f"(before the fit {sorted(idle.values())} KiB)")
        print(f"{a.output} ({table.size} bytes), training rows {table.training_rows}")
    return table


if __name__ == "__main__":
    main()
