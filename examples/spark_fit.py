#!/usr/bin/env python3
"""Fits an mlmap table from a CSV data file (DESIGN §2) on Spark, with mlmap's mergeable
statistics; the table is byte for byte the one `mlmap fit` writes on the same file.

The fit is two passes of `mapInPandas` and two tree reductions:

  1. pass (a): every partition folds its Arrow batches into one `mlmap.FitStats` and
     yields its bytes; the driver merges them with `treeReduce` (exact: any order and
     any partitioning give the same statistics);
  2. the merged statistics give the edges of every histogram for the fit settings
     (`FitStats.edges`), broadcast to the executors;
  3. pass (b): every partition counts its rows over those edges (`mlmap.FitCounts`),
     merged the same way;
  4. `mlmap.finish(stats, counts)` builds the table.

The class list is the data file's logit columns, in order (what `mlmap fit` reads): the
labels are encoded from that same list (index in it, -1 for `background`), and the same
list names the statistics' classes. Before the passes, one Spark job checks every row:
a label that names no class, a missing logit, an objectness that is missing or outside
[0, 1] stop the fit with the rows' count and an example. Rows with no label are skipped,
as `mlmap fit` skips them.

    python examples/spark_fit.py [TRAIN.csv] [--output spark-fit.mlmap] [--partitions 7]
        [--bins-ml 22] [--lambda-ml 0.0055] [--bins-map 17] [--lambda-map 0.00012]
        [--edges linspace|matlab] [--upper-tail zero|clamp]
        [--bins-bayes 22] [--lambda-bayes 0.001] [--no-bayes]
    python examples/spark_fit.py --bench-rows 4000000    # tools/bench_data.py rows

Without TRAIN.csv, the shipped training data (examples/data/train.csv) is fitted. The fit
settings are `mlmap fit`'s flags, with its defaults. The executors run this interpreter
(`PYSPARK_PYTHON`), which needs the mlmap package (`pip install ./python`), pyspark and
pyarrow; Spark needs Java 17 or later.
"""

import argparse
import csv
import functools
import operator
import os
import pathlib
import sys
import time

import numpy as np
import pandas as pd

import mlmap

ROOT = pathlib.Path(__file__).resolve().parents[1]
# Columns of a data file that are not class logits (DESIGN §2).
NOT_CLASSES = ("id", "label", "objectness")


def columns_of(path):
    """The header of a data CSV: its columns, and the class names (the other columns,
    in order)."""
    with open(path, newline="", encoding="utf-8-sig") as f:
        header = [c.strip() for c in next(csv.reader(f))]
    return header, [c for c in header if c not in NOT_CLASSES]


def session(partitions):
    """A local Spark session on two cores whose executors run this interpreter."""
    os.environ.setdefault("PYSPARK_PYTHON", sys.executable)
    os.environ.setdefault("PYSPARK_DRIVER_PYTHON", sys.executable)
    from pyspark.sql import SparkSession

    spark = (SparkSession.builder.master("local[2]").appName("mlmap-fit")
             .config("spark.sql.shuffle.partitions", str(partitions))
             .config("spark.ui.enabled", "false")
             .config("spark.ui.showConsoleProgress", "false")
             .config("spark.sql.execution.arrow.pyspark.enabled", "true")
             # mlmap's own thread pool: one thread per Python worker, the tasks are the
             # parallelism.
             .config("spark.executorEnv.RAYON_NUM_THREADS", "1")
             .getOrCreate())
    spark.sparkContext.setLogLevel("ERROR")
    return spark


def read_rows(spark, path):
    """The rows of a data CSV as a DataFrame with an explicit schema: `id` and `label` as
    text, `objectness` and every class logit as doubles; malformed rows fail the read."""
    from pyspark.sql import types as T

    header, classes = columns_of(path)
    fields = [T.StructField(c, T.StringType() if c in ("id", "label") else T.DoubleType())
              for c in header]
    df = spark.read.csv(str(path), header=True, schema=T.StructType(fields), mode="FAILFAST",
                        escape="\"",
                        enforceSchema=False, ignoreLeadingWhiteSpace=True,
                        ignoreTrailingWhiteSpace=True)
    return df, classes, "objectness" in header


def encode(df, classes, has_objectness, path):
    """The columns the fit reads: the logits in class order, `y` (the label's index in
    `classes`, -1 for background), `objectness` when the data has it. Checks every row
    first (one Spark job) and raises `ValueError` on a row `mlmap fit` would refuse.
    Rows without a label are left out."""
    from pyspark.sql import functions as F

    label = F.col("label") if "label" in df.columns else None
    if label is None:
        raise ValueError("the data has no `label` column: a fit needs labelled rows")
    known = F.array(*[F.lit(c) for c in classes])
    y = F.when(label == "background", F.lit(-1)).otherwise(F.array_position(known, label) - 1)
    bad_logit = functools.reduce(operator.or_, [
        F.col(c).isNull() | F.isnan(c) | (F.abs(c) == float("inf")) for c in classes])
    checks = {
        "a label that names no class (nor `background`)":
            label.isNotNull() & (label != "background") & (F.array_position(known, label) == 0),
        "a missing or non-finite logit": bad_logit,
    }
    if has_objectness:
        o = F.col("objectness")
        checks["an objectness that is missing or outside [0, 1]"] = (
            o.isNull() | F.isnan(o) | (o < 0) | (o > 1))
    found = df.agg(*[F.count(F.when(c, 1)).alias(f"n{i}")
                     for i, c in enumerate(checks.values())]).first()
    for i, (what, c) in enumerate(checks.items()):
        if found[f"n{i}"]:
            example = df.filter(c).first().asDict()
            raise ValueError(f"{path}: {found[f'n{i}']} row(s) with {what}, e.g. {example}")
    cols = [F.col(c) for c in classes] + [y.cast("long").alias("y")]
    if has_objectness:
        cols.append(F.col("objectness"))
    return df.filter(label.isNotNull()).select(*cols)


def fit(df, classes, has_objectness, **settings):
    """The table of the encoded rows `df` (see `encode`) for the settings of
    `FitStats.edges`."""
    spark = df.sparkSession

    def arrays(batch):
        logits = batch[classes].to_numpy(np.float64)
        labels = batch["y"].to_numpy(np.int64)
        objectness = batch["objectness"].to_numpy(np.float64) if has_objectness else None
        return logits, labels, objectness

    def stats_of(batches):
        acc = mlmap.FitStats.empty(classes)
        for batch in batches:
            acc = acc + mlmap.FitStats(*arrays(batch), classes=classes)
        yield pd.DataFrame({"stats": [acc.to_bytes()]})

    stats = (df.mapInPandas(stats_of, "stats binary").rdd
             .map(lambda r: mlmap.FitStats.from_bytes(r.stats))
             .treeReduce(operator.add))
    edges = spark.sparkContext.broadcast(stats.edges(**settings).to_bytes())

    def counts_of(batches):
        e = mlmap.FitEdges.from_bytes(edges.value)
        acc = mlmap.FitCounts.empty(e)
        for batch in batches:
            acc = acc + mlmap.FitCounts(e, *arrays(batch))
        yield pd.DataFrame({"counts": [acc.to_bytes()]})

    counts = (df.mapInPandas(counts_of, "counts binary").rdd
              .map(lambda r: mlmap.FitCounts.from_bytes(r.counts))
              .treeReduce(operator.add))
    return mlmap.finish(stats, counts)


def settings_of(a):
    """The `FitStats.edges` settings of `mlmap fit`'s flags."""
    s = {"bins_ml": a.bins_ml, "lambda_ml": a.lambda_ml, "bins_map": a.bins_map,
         "lambda_map": a.lambda_map, "edges": a.edges, "tail": a.upper_tail}
    s["bayes"] = None if a.no_bayes else {"bins": a.bins_bayes, "lambda": a.lambda_bayes}
    return s


def bench(spark, rows, partitions, settings):
    """Times the fit of `rows` rows of tools/bench_data.py, cached in Spark, against the
    same two passes doing nothing but receive their Arrow batches as pandas, and
    against `mlmap.fit` in this process on the same arrays."""
    sys.path.insert(0, str(ROOT / "tools"))
    import bench_data
    import pyarrow as pa
    import pyarrow.parquet as pq

    whole = ROOT / "target" / "bench-data" / f"{rows}"
    if not (whole / "classes.txt").exists():
        bench_data.write(rows, str(whole))
    logits = np.load(whole / "logits.npy").astype(np.float64)
    labels = np.load(whole / "labels.npy")
    objectness = np.load(whole / "objectness.npy").astype(np.float64)
    classes = (whole / "classes.txt").read_text().split()
    parquet = whole / "rows.parquet"
    if not parquet.exists():
        cols = {c: logits[:, i] for i, c in enumerate(classes)}
        cols.update(y=labels, objectness=objectness)
        pq.write_table(pa.table(cols), parquet)
    df = spark.read.parquet(str(parquet)).repartition(partitions).cache()
    df.count()

    def passes(f):
        t0 = time.perf_counter()
        out = f()
        return out, time.perf_counter() - t0

    def nothing(batches):
        n = 0
        for batch in batches:
            n += len(batch[classes].to_numpy(np.float64)) + len(batch["y"].to_numpy(np.int64))
        yield pd.DataFrame({"n": [n]})

    table, took = passes(lambda: fit(df, classes, True, **settings))
    _, arrow = passes(lambda: [df.mapInPandas(nothing, "n long").rdd.map(lambda r: r.n)
                               .treeReduce(operator.add) for _ in range(2)])
    one, alone = passes(lambda: mlmap.fit(logits, labels, objectness, classes=classes,
                                          **settings))
    same = one.to_bytes() == table.to_bytes()
    print(f"{rows} rows, {partitions} partitions, local[2]: Spark fit {took:.2f} s "
          f"({rows / took / 2 / 1e6:.2f} M rows/s per core); the two passes receiving "
          f"their batches only {arrow:.2f} s ({100 * arrow / took:.0f} % of the fit); "
          f"mlmap.fit in one process {alone:.2f} s; same bytes: {same}")
    if not same:
        raise SystemExit("the Spark table differs from mlmap.fit's")
    return table


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("train", nargs="?", default=str(ROOT / "examples" / "data" / "train.csv"),
                   help="a data CSV (DESIGN §2); default: examples/data/train.csv")
    p.add_argument("--output", default="spark-fit.mlmap")
    p.add_argument("--partitions", type=int, default=7,
                   help="partitions of the rows (more than rows gives empty partitions)")
    p.add_argument("--bins-ml", type=int, default=22)
    p.add_argument("--lambda-ml", type=float, default=0.0055)
    p.add_argument("--bins-map", type=int, default=17)
    p.add_argument("--lambda-map", type=float, default=0.00012)
    p.add_argument("--edges", default="linspace", choices=["linspace", "matlab"])
    p.add_argument("--upper-tail", default="zero", choices=["zero", "clamp"])
    p.add_argument("--bins-bayes", type=int, default=22)
    p.add_argument("--lambda-bayes", type=float, default=0.001)
    p.add_argument("--no-bayes", action="store_true")
    p.add_argument("--bench-rows", type=int, default=0,
                   help="time a fit of N rows of tools/bench_data.py (written under target/)")
    a = p.parse_args(argv)
    settings = settings_of(a)
    spark = session(a.partitions)
    try:
        if a.bench_rows:
            table = bench(spark, a.bench_rows, a.partitions, settings)
        else:
            df, classes, has_objectness = read_rows(spark, a.train)
            rows = encode(df, classes, has_objectness, a.train).repartition(a.partitions)
            t0 = time.perf_counter()
            table = fit(rows, classes, has_objectness, **settings)
            print(f"fitted {a.train} on {a.partitions} partitions in "
                  f"{time.perf_counter() - t0:.2f} s")
        table.save(a.output)
        print(f"{a.output} ({table.size} bytes), classes {table.classes}, "
              f"training rows {table.training_rows}")
    except ValueError as e:
        raise SystemExit(f"spark_fit: {e}")
    finally:
        spark.stop()
    return table


if __name__ == "__main__":
    main()
