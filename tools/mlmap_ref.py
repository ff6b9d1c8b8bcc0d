#!/usr/bin/env python3
"""An independent numpy implementation of mlmap's fit, table format and layer.

It shares no code with the Rust crate: it is written from docs/DESIGN.md and docs/FORMAT.md,
so agreement between the two is evidence for both. Used to write golden values
(tests/golden/) and to cross-check tables written by `mlmap fit`.

    python3 tools/mlmap_ref.py fit examples/data/train.csv OUT.mlmap   # linspace, 22/17 bins
    python3 tools/mlmap_ref.py goldens tests/golden/layer              # layer goldens

The layer half (decode, likelihood, prior, ML, MAP) follows docs/DESIGN.md section 1.2 in
float64: the table's stored float32 values are widened exactly, the inner bin edges are
computed in float32 exactly as the format defines them (w = (hi - lo) / B,
e_k = lo + k * w, no fused multiply-add), and the bin of a logit is found by
numpy.histogram itself (bins [e_k, e_k+1), the last one closed). Goldens were last
written with numpy 2.4.6 (the version is also recorded in every golden file).
"""
import csv
import struct
import sys
import zlib

import numpy as np

MAGIC = b"MLMP"
VERSION = 1
VARIANCE_FLOOR = 1e-12


def varint(n):
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def f32(v):
    return struct.pack("<f", float(np.float32(v)))


def encode(classes, lambda_ml, lambda_map, edge_mode=0, upper_tail=0):
    """classes: list of dicts name, rows, mean, var, ml_lo, ml_hi, ml_freqs, map_lo, map_hi, map_freqs."""
    k = len(classes)
    bml = len(classes[0]["ml_freqs"])
    bmap = len(classes[0]["map_freqs"])
    b = bytearray(MAGIC)
    for v in (VERSION, k, bml, bmap):
        b += varint(v)
    b += bytes([edge_mode, upper_tail]) + f32(lambda_ml) + f32(lambda_map)
    b += varint(k)
    for c in classes:
        name = c["name"].encode()
        b += varint(len(name)) + name + varint(c["rows"])
        b += f32(c["mean"]) + f32(c["var"])
        b += f32(c["ml_lo"]) + f32(c["ml_hi"]) + varint(len(c["ml_freqs"]))
        b += b"".join(f32(v) for v in c["ml_freqs"])
        b += f32(c["map_lo"]) + f32(c["map_hi"]) + varint(len(c["map_freqs"]))
        b += b"".join(f32(v) for v in c["map_freqs"])
    b += struct.pack("<I", zlib.crc32(bytes(b)) & 0xFFFFFFFF)
    return bytes(b)


def edges_f32(lo, hi, nbins):
    """The inner edges exactly as the format defines them, in float32."""
    lo, hi = np.float32(lo), np.float32(hi)
    w = np.float32((hi - lo) / np.float32(nbins))
    e = [lo] + [np.float32(lo + np.float32(k) * w) for k in range(1, nbins)] + [hi]
    return np.array(e, dtype=np.float32)


def linspace_range(v):
    lo, hi = float(np.min(v)), float(np.max(v))
    if lo == hi:
        lo, hi = lo - 0.5, hi + 0.5
    return np.float32(lo), np.float32(hi)


def histogram(v, nbins):
    lo, hi = linspace_range(v)
    edges = edges_f32(lo, hi, nbins)
    counts, _ = np.histogram(np.asarray(v, dtype=np.float32), bins=edges)
    return lo, hi, counts / len(v)


def read_csv(path):
    with open(path) as fh:
        r = csv.DictReader(fh)
        names = [c for c in r.fieldnames if c not in ("id", "label", "objectness")]
        rows = list(r)
    labels = [row["label"] for row in rows]
    x = np.array([[float(row[c]) for c in names] for row in rows])
    os_ = np.array([float(row.get("objectness") or 1.0) for row in rows])
    return names, labels, x, os_


def fit(path, bins_ml=22, bins_map=17, lambda_ml=0.0055, lambda_map=0.00012):
    names, labels, x, _ = read_csv(path)
    classes = []
    for c, name in enumerate(names):
        v = x[[lab == name for lab in labels], c]
        ml_lo, ml_hi, ml_f = histogram(v, bins_ml)
        map_lo, map_hi, map_f = histogram(v, bins_map)
        var = max(float(np.var(v, ddof=1)) if len(v) > 1 else 0.0, VARIANCE_FLOOR)
        classes.append(dict(name=name, rows=len(v), mean=float(np.mean(v)), var=var,
                            ml_lo=ml_lo, ml_hi=ml_hi, ml_freqs=ml_f,
                            map_lo=map_lo, map_hi=map_hi, map_freqs=map_f))
    return classes, lambda_ml, lambda_map


# ---------------------------------------------------------------------------------------
# Decoding (docs/FORMAT.md), written independently of the Rust decoder.


class Reader:
    def __init__(self, data):
        self.data, self.pos = data, 0

    def take(self, n):
        if self.pos + n > len(self.data):
            raise ValueError("truncated")
        out = self.data[self.pos:self.pos + n]
        self.pos += n
        return out

    def varint(self):
        n, shift = 0, 0
        while True:
            b = self.take(1)[0]
            n |= (b & 0x7F) << shift
            shift += 7
            if not b & 0x80:
                return n

    def f32(self):
        return float(struct.unpack("<f", self.take(4))[0])

    def f32s(self):
        return [self.f32() for _ in range(self.varint())]


def decode(data):
    """The table in a .mlmap file as a dict (float32 values widened exactly to float64)."""
    if data[:4] != MAGIC:
        raise ValueError("not a table")
    if zlib.crc32(data[:-4]) & 0xFFFFFFFF != struct.unpack("<I", data[-4:])[0]:
        raise ValueError("bad CRC")
    r = Reader(data[:-4])
    r.take(4)
    version, k, bml, bmap = (r.varint() for _ in range(4))
    if version != VERSION:
        raise ValueError("version")
    edge_mode, upper_tail = r.take(1)[0], r.take(1)[0]
    t = dict(k=k, bins_ml=bml, bins_map=bmap, edge_mode=edge_mode, upper_tail=upper_tail,
             lambda_ml=r.f32(), lambda_map=r.f32(), classes=[])
    if r.varint() != k:
        raise ValueError("class count")
    for _ in range(k):
        c = dict(name=r.take(r.varint()).decode(), rows=r.varint(), mean=r.f32(), var=r.f32())
        c["ml_lo"], c["ml_hi"], c["ml_freqs"] = r.f32(), r.f32(), r.f32s()
        c["map_lo"], c["map_hi"], c["map_freqs"] = r.f32(), r.f32(), r.f32s()
        t["classes"].append(c)
    if r.pos != len(r.data):
        raise ValueError("trailing bytes")
    return t


# ---------------------------------------------------------------------------------------
# Inference (docs/DESIGN.md section 1.2), float64.


class InferenceError(ValueError):
    pass


def likelihood(x, lo, hi, freqs, clamp):
    """L: the frequency of the bin holding x (numpy's rule), 0 outside [e_0, e_B].

    With the clamp policy, x above e_B (+inf included) uses the last bin.
    """
    freqs = np.asarray(freqs, dtype=np.float64)
    if clamp and x > np.float32(hi):
        return float(freqs[-1])
    if not np.isfinite(x):
        return 0.0
    edges = edges_f32(lo, hi, len(freqs)).astype(np.float64)
    counts, _ = np.histogram(np.array([x], dtype=np.float64), bins=edges)
    if counts.sum() == 0:
        return 0.0
    return float(freqs[int(np.argmax(counts))])


def pdf(x, mean, var):
    """N(x | mean, var); 0 for +-inf."""
    if not np.isfinite(x):
        return 0.0
    return float(np.exp(-((x - mean) ** 2) / (2.0 * var)) / np.sqrt(2.0 * np.pi * var))


def check(x, os_):
    for i, v in enumerate(x):
        if np.isnan(v):
            raise InferenceError("nan_logit:%d" % i)
    if not (0.0 <= os_ <= 1.0):
        raise InferenceError("objectness")


def ml(t, x, os_):
    check(x, os_)
    clamp = t["upper_tail"] == 1
    a = np.array([likelihood(v, c["ml_lo"], c["ml_hi"], c["ml_freqs"], clamp) + t["lambda_ml"]
                  for v, c in zip(x, t["classes"])])
    return os_ * a / a.sum()


def map_(t, x, os_):
    check(x, os_)
    clamp = t["upper_tail"] == 1
    a = np.array([likelihood(v, c["map_lo"], c["map_hi"], c["map_freqs"], clamp)
                  * pdf(v, c["mean"], c["var"]) + t["lambda_map"]
                  for v, c in zip(x, t["classes"])])
    return os_ * a / a.sum()


# ---------------------------------------------------------------------------------------
# Golden files for tests/layer.rs and tests/format.rs.

# A hand-checkable K = 3 table: round edges (bin width 1 for ML, 2 for MAP) and round
# frequencies. ML edges: car 0,1,2,3,4; cyclist -2,-1,0,1,2; pedestrian -4,-3,-2,-1,0.
SMALL = [
    dict(name="car", rows=1000, mean=2.0, var=1.0,
         ml_lo=0.0, ml_hi=4.0, ml_freqs=[0.1, 0.2, 0.3, 0.4],
         map_lo=0.0, map_hi=4.0, map_freqs=[0.25, 0.75]),
    dict(name="cyclist", rows=250, mean=0.0, var=0.25,
         ml_lo=-2.0, ml_hi=2.0, ml_freqs=[0.4, 0.3, 0.2, 0.1],
         map_lo=-2.0, map_hi=2.0, map_freqs=[0.5, 0.5]),
    dict(name="pedestrian", rows=40, mean=-2.0, var=4.0,
         ml_lo=-4.0, ml_hi=0.0, ml_freqs=[0.25, 0.25, 0.25, 0.25],
         map_lo=-4.0, map_hi=0.0, map_freqs=[0.6, 0.4]),
]
SMALL_LAMBDA_ML = 0.01
SMALL_LAMBDA_MAP = 0.001


def up(v):
    return float(np.nextafter(np.float32(v), np.float32(np.inf)))


def down(v):
    return float(np.nextafter(np.float32(v), np.float32(-np.inf)))


INF, NAN = float("inf"), float("nan")

# (case, logits, objectness): every case is scored with both small tables.
SMALL_CASES = [
    ("inside bins", [0.5, 0.5, 0.5], 1.0),
    ("inside bins", [2.5, -1.5, -3.5], 1.0),
    ("inside bins", [3.25, 1.75, -0.5], 0.7),
    ("on inner edges", [1.0, 0.0, -2.0], 1.0),
    ("on inner edges", [3.0, -1.0, -3.0], 0.5),
    ("on first edges", [0.0, -2.0, -4.0], 1.0),
    ("on closed last edges", [4.0, 2.0, 0.0], 1.0),
    ("last edge and inner edge", [4.0, 1.0, -1.0], 0.25),
    ("just below last edges", [down(4.0), down(2.0), down(0.0)], 1.0),
    ("just below inner edges", [down(1.0), down(0.0), down(-2.0)], 1.0),
    ("just above last edges", [up(4.0), up(2.0), up(0.0)], 1.0),
    ("just below first edges", [down(0.0), down(-2.0), down(-4.0)], 0.8),
    ("far outside", [1e30, -1e30, 50.0], 1.0),
    ("far outside", [-100.0, 100.0, 100.0], 0.6),
    ("far outside one class", [0.5, 0.5, 1e30], 1.0),
    ("infinities", [INF, -INF, INF], 1.0),
    ("infinities", [-INF, INF, -INF], 0.9),
    ("infinity and inside", [INF, 0.5, -3.0], 1.0),
    ("subnormal logits", [1e-40, -1e-40, 1e-40], 1.0),
    ("negative zero", [-0.0, -0.0, -0.0], 1.0),
    ("objectness 0", [0.5, 0.5, 0.5], 0.0),
    ("objectness -0", [2.5, -1.5, -3.5], -0.0),
    ("objectness 0 outside", [1e30, -1e30, 50.0], 0.0),
    ("objectness between", [0.5, 0.5, 0.5], 0.93),
    ("objectness between", [2.5, -1.5, -3.5], 0.001),
    ("objectness 1", [3.5, 1.5, -1.5], 1.0),
    ("objectness largest below 1", [3.5, 1.5, -1.5], down(1.0)),
    ("objectness smallest subnormal", [3.5, 1.5, -1.5], 1e-45),
    ("NaN logit", [NAN, 0.5, 0.5], 1.0),
    ("NaN logit", [0.5, NAN, 0.5], 1.0),
    ("NaN logit", [0.5, 0.5, NAN], 0.5),
    ("NaN logits", [0.5, NAN, NAN], 0.5),
    ("objectness NaN", [0.5, 0.5, 0.5], NAN),
    ("objectness below 0", [0.5, 0.5, 0.5], -0.1),
    ("objectness above 1", [0.5, 0.5, 0.5], 1.1),
    ("objectness just above 1", [0.5, 0.5, 0.5], up(1.0)),
    ("objectness just below 0", [0.5, 0.5, 0.5], -1e-45),
    ("objectness +inf", [0.5, 0.5, 0.5], INF),
]


def fmt(v):
    """A float as text that parses back to the same value (f32 inputs stay exact)."""
    if np.isnan(v):
        return "NaN"
    if np.isinf(v):
        return "inf" if v > 0 else "-inf"
    return repr(float(v))


def golden_rows(name, t, cases):
    rows = []
    for case, x, os_ in cases:
        x = [float(np.float32(v)) for v in x]
        os_ = float(np.float32(os_))
        try:
            scores = list(ml(t, x, os_)) + list(map_(t, x, os_))
            err = ""
        except InferenceError as e:
            scores, err = [None] * (2 * len(x)), str(e)
        rows.append([name, case, fmt(os_)] + [fmt(v) for v in x]
                    + ["" if s is None else fmt(s) for s in scores] + [err])
    return rows


def write_csv(path, k, rows, regenerate):
    head = ["table", "case", "objectness"] + ["x%d" % i for i in range(k)] \
        + ["ml%d" % i for i in range(k)] + ["map%d" % i for i in range(k)] + ["error"]
    with open(path, "w") as fh:
        fh.write("# Expected ML and MAP scores (float64) from tools/mlmap_ref.py, numpy %s.\n"
                 % np.__version__)
        fh.write("# Regenerate: %s\n" % regenerate)
        fh.write("# error: empty, nan_logit:<first NaN class> or objectness.\n")
        fh.write(",".join(head) + "\n")
        for r in rows:
            fh.write(",".join(r) + "\n")


def default_cases(t, n, seed):
    """n random logit vectors over the shipped table, aimed at every region of every class."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(n):
        x = []
        for c in t["classes"]:
            kind = rng.integers(0, 10)
            head = "ml" if rng.integers(0, 2) == 0 else "map"
            lo, hi, nb = c[head + "_lo"], c[head + "_hi"], len(c[head + "_freqs"])
            span = hi - lo
            if kind < 5:  # inside or near the support
                v = rng.uniform(lo - 0.1 * span, hi + 0.1 * span)
            elif kind < 7:  # exactly on an edge (float32, as the format defines it)
                v = float(edges_f32(lo, hi, nb)[rng.integers(0, nb + 1)])
            elif kind < 9:  # around the prior's mean
                v = rng.normal(c["mean"], np.sqrt(c["var"]))
            else:  # far outside or infinite
                v = [INF, -INF, 1e30, -1e30, hi + 5 * span, lo - 5 * span][rng.integers(0, 6)]
            x.append(v)
        r = rng.uniform()
        os_ = 1.0 if r < 0.3 else (0.0 if r < 0.35 else rng.uniform())
        cases.append(("random", x, os_))
    return cases


def goldens(outdir):
    import os
    os.makedirs(outdir, exist_ok=True)
    regen = "python3 tools/mlmap_ref.py goldens tests/golden/layer"
    small = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, edge_mode=0, upper_tail=0)
    clamp = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, edge_mode=0, upper_tail=1)
    for fname, data in (("small.mlmap", small), ("small_clamp.mlmap", clamp)):
        with open(os.path.join(outdir, fname), "wb") as fh:
            fh.write(data)
    rows = golden_rows("small", decode(small), SMALL_CASES) \
        + golden_rows("small_clamp", decode(clamp), SMALL_CASES)
    write_csv(os.path.join(outdir, "small.csv"), 3, rows, regen)
    here = os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(here, "..", "tables", "default.mlmap"), "rb") as fh:
        t = decode(fh.read())
    rows = golden_rows("default", t, default_cases(t, 300, seed=2))
    write_csv(os.path.join(outdir, "default.csv"), t["k"], rows, regen)
    print("numpy %s: wrote %s" % (np.__version__, outdir))


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "fit":
        classes, lml, lmap = fit(sys.argv[2])
        with open(sys.argv[3], "wb") as fh:
            fh.write(encode(classes, lml, lmap))
    elif len(sys.argv) == 3 and sys.argv[1] == "goldens":
        goldens(sys.argv[2])
    else:
        print(__doc__)
        sys.exit(2)


if __name__ == "__main__":
    main()
