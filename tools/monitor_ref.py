#!/usr/bin/env python3
"""An independent numpy implementation of mlmap's drift monitor (docs/DESIGN.md section 7)
and of the sections appended after a table (docs/FORMAT.md).

It shares no code with the Rust crate: the table is decoded by tools/mlmap_ref.py, the
sections are walked from the end of the file as docs/FORMAT.md describes them, and every
metric is computed in float64 from docs/DESIGN.md section 7:

* the training share of logit j's bin b: e[j][b] = sum_c round(n_c (exp(t) - lambda)) / N,
  t the stored log-term of category c, n_c its training rows, N all training rows;
* a window of n detections: per logit, counts below the axis, in each bin, above it;
  o = max(count, 1/2) / n, e' = max(e, 1/(2n)) (0 for below and above), and
  PSI_j = sum (o - e') ln(o / e'); psi_max their maximum (first logit on ties);
  oos_rate the share of detections with a logit in a bin of share 0 or outside the axis;
  q_mean the mean of the open head's q;
* thresholds: R windows of W row indices drawn by SplitMix64 from the seed,
  index = (next * n) >> 64; per level beta = alpha * i / 100 (i = 100 down to 1) the
  ceil((1 - beta) R)-th smallest psi_max and oos_rate and the (floor(beta R) + 1)-th smallest
  q_mean; the first beta whose any-alarm share is at most alpha.

    python3 tools/monitor_ref.py goldens tests/golden/monitor

writes the goldens the Rust tests compare with (tests/monitor.rs).
"""
import json
import math
import os
import struct
import sys
import zlib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mlmap_ref  # noqa: E402

KNOWN = (b"MLMQ", b"MLMW", b"MLMS")
MASK = (1 << 64) - 1


def split_sections(data):
    """(table bytes, {magic: section bytes}) of a file with appended sections."""
    sections = {}
    rest = data
    while len(rest) >= 12:
        length, crc = struct.unpack("<II", rest[-8:])
        if length < 12 or length > len(rest):
            break
        sec = rest[-length:]
        if sec[:4] not in KNOWN or zlib.crc32(sec[:-4]) & 0xFFFFFFFF != crc:
            break
        sections.setdefault(sec[:4], sec)
        rest = rest[:-length]
    return (rest if rest else data), sections


def read_monitor_section(sec):
    magic, version, flags, reserved, k, bins, window, table_crc = struct.unpack_from(
        "<4sBBHHHII", sec, 0)
    alpha, psi, oos, q = struct.unpack_from("<4f", sec, 20)
    ref = np.frombuffer(sec[36:36 + 4 * k * bins], dtype="<f4").astype(np.float64)
    return dict(version=version, has_q=flags == 1, k=k, bins=bins, window=window,
                table_crc=table_crc, alpha=alpha, psi=psi, oos=oos, q=q,
                reference=ref.reshape(k, bins))


def reference(t):
    """e[j][b], float64, shape (K, B)."""
    b = t["bayes"]
    k, nb, rows = t["k"], b["bins"], np.asarray(b["rows"], dtype=np.float64)
    terms = np.asarray(b["terms"], dtype=np.float64).reshape(len(rows), k, nb)
    lam = np.float64(b["lambda"])
    counts = np.maximum(np.round(rows[:, None, None] * (np.exp(terms) - lam)), 0.0)
    return counts.sum(axis=0) / rows.sum()


def row_bins(t, x):
    """Per row and logit: the bin index, -1 below the axis, B above it (float32 logits)."""
    b = t["bayes"]
    nb = b["bins"]
    out = np.empty(x.shape, dtype=np.int64)
    for j, (lo, hi) in enumerate(b["ranges"]):
        edges = mlmap_ref.edges_f32(lo, hi, nb).astype(np.float64)
        v = x[:, j].astype(np.float64)
        i = np.searchsorted(edges, v, side="right") - 1
        i = np.where(v == edges[-1], nb - 1, i)
        i = np.where(v < edges[0], -1, i)
        i = np.where(v > edges[-1], nb, i)
        out[:, j] = i
    return out


def row_q(t, x):
    if t["open"] is None:
        return None
    return np.array([mlmap_ref.open_known(t, row.astype(np.float64)) for row in x])


def row_outside(bins_, ref):
    k, nb = ref.shape
    out = np.zeros(len(bins_), dtype=bool)
    for j in range(k):
        i = bins_[:, j]
        inside = (i >= 0) & (i < nb)
        share = np.where(inside, ref[j, np.clip(i, 0, nb - 1)], 0.0)
        out |= share == 0.0
    return out


def window_metrics(bins_, outside, q, ref, idx):
    """The metrics of the window of rows idx."""
    k, nb = ref.shape
    n = len(idx)
    floor = 0.5 / n
    psi = []
    for j in range(k):
        c = np.bincount(bins_[idx, j] + 1, minlength=nb + 2).astype(np.float64)
        e = np.concatenate(([0.0], ref[j], [0.0]))
        e2 = np.maximum(e, floor)
        o = np.maximum(c, 0.5) / n
        psi.append(float(np.sum((o - e2) * np.log(o / e2))))
    psi = np.array(psi)
    return dict(rows=n, psi=psi, psi_max=float(psi.max()), psi_logit=int(np.argmax(psi)),
                oos_rate=float(outside[idx].mean()),
                q_mean=None if q is None else float(q[idx].mean()))


def splitmix(seed):
    state = seed & MASK
    while True:
        state = (state + 0x9E3779B97F4A7C15) & MASK
        z = state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
        yield z ^ (z >> 31)


def fit_thresholds(bins_, outside, q, ref, window, alpha, windows, seed):
    n = len(bins_)
    g = splitmix(seed)
    ms = []
    for _ in range(windows):
        idx = np.array([(next(g) * n) >> 64 for _ in range(window)])
        ms.append(window_metrics(bins_, outside, q, ref, idx))
    psi = np.sort([m["psi_max"] for m in ms])
    oos = np.sort([m["oos_rate"] for m in ms])
    qs = np.sort([m["q_mean"] for m in ms]) if q is not None else None
    r = len(ms)

    def at(beta):
        upper = math.ceil((1.0 - beta) * r)
        lower = math.floor(beta * r)
        tq = -math.inf if qs is None else (qs[lower] if lower < r else -math.inf)
        return (psi[upper - 1] if upper >= 1 else math.inf,
                oos[upper - 1] if upper >= 1 else math.inf, tq)

    def rate(t):
        a = [m["psi_max"] > t[0] or m["oos_rate"] > t[1]
             or (m["q_mean"] is not None and m["q_mean"] < t[2]) for m in ms]
        return float(np.mean(a))

    for i in range(100, 0, -1):
        beta = alpha * i / 100.0
        t = at(beta)
        if rate(t) <= alpha:
            return dict(level=beta, psi=float(t[0]), oos=float(t[1]), q=float(t[2]),
                        alarm_rate=rate(t))
    t = at(alpha / 100.0)
    return dict(level=alpha / 100.0, psi=float(t[0]), oos=float(t[1]), q=float(t[2]),
                alarm_rate=rate(t))


def load(table_path):
    data = open(table_path, "rb").read()
    table, sections = split_sections(data)
    return mlmap_ref.decode(table), sections


def logits_f32(path):
    names, labels, x, os_ = mlmap_ref.read_csv(path)
    return names, labels, x.astype(np.float32), os_


def replay(t, ref, path, window):
    _, _, x, _ = logits_f32(path)
    bins_ = row_bins(t, x)
    outside = row_outside(bins_, ref)
    q = row_q(t, x)
    out = []
    for w, start in enumerate(range(0, len(x), window)):
        idx = np.arange(start, min(start + window, len(x)))
        m = window_metrics(bins_, outside, q, ref, idx)
        m["window"] = w
        m["psi"] = [float(v) for v in m["psi"]]
        out.append(m)
    return out


def goldens(outdir):
    os.makedirs(outdir, exist_ok=True)
    t, _ = load("tables/default.mlmap")
    ref = reference(t)
    meta = dict(numpy=np.__version__, table="tables/default.mlmap")
    with open(os.path.join(outdir, "reference.json"), "w") as fh:
        json.dump(dict(meta, reference=ref.tolist()), fh, indent=1)
    for name in ("ood", "test"):
        wins = replay(t, ref, f"examples/data/{name}.csv", 50)
        with open(os.path.join(outdir, f"windows_{name}.json"), "w") as fh:
            json.dump(dict(meta, window=50, input=f"examples/data/{name}.csv", windows=wins),
                      fh, indent=1)
        # The same windows as CSV, for the C tests (ffi/tests/host.c, the firmware).
        with open(os.path.join(outdir, f"windows_{name}.csv"), "w") as fh:
            fh.write(f"# tools/monitor_ref.py, numpy {np.__version__}: examples/data/{name}.csv, "
                     "W = 50, tables/default.mlmap\n")
            fh.write("window,rows,psi_max,psi_logit,oos_rate,q_mean\n")
            for m in wins:
                fh.write(f"{m['window']},{m['rows']},{m['psi_max']!r},{m['psi_logit']},"
                         f"{m['oos_rate']!r},{m['q_mean']!r}\n")
    _, _, x, _ = logits_f32("examples/data/val.csv")
    bins_ = row_bins(t, x)
    fitted = fit_thresholds(bins_, row_outside(bins_, ref), row_q(t, x), ref,
                            window=50, alpha=0.05, windows=2000, seed=0)
    with open(os.path.join(outdir, "thresholds.json"), "w") as fh:
        json.dump(dict(meta, val="examples/data/val.csv", window=50, alpha=0.05, windows=2000,
                       seed=0, **fitted), fh, indent=1)


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "goldens":
        goldens(sys.argv[2])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
