#!/usr/bin/env python3
"""An independent numpy implementation of mlmap's fit, table format and layer.

It shares no code with the Rust crate: it is written from docs/DESIGN.md and docs/FORMAT.md,
so agreement between the two is evidence for both. Used to write golden values
(tests/golden/) and to cross-check tables written by `mlmap fit`.

    python3 tools/mlmap_ref.py fit examples/data/train.csv OUT.mlmap   # every head (version 3)
    python3 tools/mlmap_ref.py fit --no-bayes examples/data/train.csv OUT.mlmap  # version 1
    python3 tools/mlmap_ref.py goldens tests/golden/layer              # layer goldens

`goldens` writes the small tables and the scores of every head: of hand-picked and random
logits (small.csv, default.csv, open.csv), of every 20th row of examples/data/test.csv with
the shipped table (test_split.csv), and of quantized codes scored as their dequantized
logits (quantized.csv).

`fit` uses the defaults of `mlmap fit`: linspace edges, 22 ML bins (lambda 0.0055), 17 MAP
bins (lambda 0.00012) and, unless --no-bayes, the Bayes head of docs/DESIGN.md section 1.6 with
22 bins per logit and lambda 0.001, and the open head's parameters of an untuned table
(temperature 1, epsilon 0).

The layer half (decode, likelihood, prior, ML, MAP) follows docs/DESIGN.md section 1.2 in
float64: the table's stored float32 values are widened exactly, the inner bin edges are
computed in float32 exactly as the format defines them (w = (hi - lo) / B,
e_k = lo + k * w, no fused multiply-add), and the bin of a logit is found by
numpy.histogram itself (bins [e_k, e_k+1), the last one closed). The Bayes head
(DESIGN.md section 1.6) is fitted and scored the same way: its axes are linspace edges over
all labelled rows, its counts come from numpy.histogram on the float32 edges, its log-terms
are float32(ln(count / n_c + lambda)) computed in float64, and a detection is scored in
float64 as l[c] = ln pi[c] + sum_j term (ln(lambda) outside axis j), softmax over the
categories, times the objectness. The open head (DESIGN.md section 1.8) is scored in float64
from the same log-scores plus the unknown category's ln(epsilon) + K ln(1/B + lambda), times a
softmax of the logits divided by the temperature. Goldens were last written with numpy 2.4.6 (the version
is also recorded in every golden file).
"""
import csv
import struct
import sys
import zlib

import numpy as np

MAGIC = b"MLMP"
# Version 1: ML and MAP heads only; version 2: the same plus a Bayes head; version 3: the
# same plus the open head's temperature and epsilon.
VERSION_1 = 1
VERSION_2 = 2
VERSION_3 = 3
VARIANCE_FLOOR = 1e-12
# The open head's (temperature, epsilon) of a table no validation data has tuned.
UNTUNED_OPEN = (1.0, 0.0)


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


def encode(classes, lambda_ml, lambda_map, edge_mode=0, upper_tail=0, bayes=None, open_=None):
    """The bytes of a table file (docs/FORMAT.md).

    classes: list of dicts name, rows, mean, var, ml_lo, ml_hi, ml_freqs, map_lo, map_hi,
    map_freqs. bayes: None (a version-1 file) or a dict lambda, rows (per category),
    ranges (K (lo, hi) pairs) and terms (C*K*B log-terms, held category-major here, written
    logit-major): a version-2 file. open_: None, or with a Bayes head a pair
    (temperature, epsilon): a version-3 file.
    """
    k = len(classes)
    bml = len(classes[0]["ml_freqs"])
    bmap = len(classes[0]["map_freqs"])
    b = bytearray(MAGIC)
    version = VERSION_1 if bayes is None else (VERSION_2 if open_ is None else VERSION_3)
    header = [version, k, bml, bmap]
    if bayes is not None:
        cats = len(bayes["rows"])
        header += [len(bayes["terms"]) // (cats * k), cats]
    for v in header:
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
    if bayes is not None:
        b += f32(bayes["lambda"])
        b += varint(len(bayes["rows"])) + b"".join(varint(n) for n in bayes["rows"])
        b += varint(len(bayes["ranges"]))
        b += b"".join(f32(lo) + f32(hi) for lo, hi in bayes["ranges"])
        # Held category-major here (c, j, b); written logit-major (j, b, c), docs/FORMAT.md.
        cats, k = len(bayes["rows"]), len(bayes["ranges"])
        lm = np.asarray(bayes["terms"], dtype=np.float32).reshape(cats, k, -1).transpose(1, 2, 0)
        b += varint(lm.size) + b"".join(f32(v) for v in lm.ravel())
        if open_ is not None:
            b += f32(open_[0]) + f32(open_[1])
    b += struct.pack("<I", zlib.crc32(bytes(b)) & 0xFFFFFFFF)
    return bytes(b)


def edges_f32(lo, hi, nbins):
    """The inner edges exactly as the format defines them, in float32."""
    lo, hi = np.float32(lo), np.float32(hi)
    w = np.float32((hi - lo) / np.float32(nbins))
    e = [lo] + [np.float32(lo + np.float32(k) * w) for k in range(1, nbins)] + [hi]
    return np.array(e, dtype=np.float32)


def linspace_range(v):
    """[min, max] in float32; widened to [min - 0.5, max + 0.5] when empty in float32."""
    vmin, vmax = float(np.min(v)), float(np.max(v))
    lo, hi = np.float32(vmin), np.float32(vmax)
    if not lo < hi:
        lo, hi = np.float32(vmin - 0.5), np.float32(vmax + 0.5)
    return lo, hi


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


def fit_bayes(names, labels, x, bins, lam):
    """The Bayes head (DESIGN.md section 1.6) of the labelled rows, as `encode` takes it.

    Categories: the classes, then `background` when some row has that label (rows without
    a label are not used). Logit j's axis: linspace edges over logit j of every labelled
    row. Counts per category and logit by numpy.histogram on the float32 edges; log-terms
    float32(ln(count / n_c + lambda)) with lambda the float32 value the table stores.
    """
    labels = np.asarray(labels)
    cats = list(names) + (["background"] if np.any(labels == "background") else [])
    labelled = np.isin(labels, cats)
    ranges = [linspace_range(x[labelled, j]) for j in range(len(names))]
    lam64 = float(np.float32(lam))
    rows, terms = [], []
    for cat in cats:
        v = x[labels == cat].astype(np.float32)
        n = len(v)
        if n == 0:
            raise ValueError("category %s has no rows" % cat)
        rows.append(n)
        for j, (lo, hi) in enumerate(ranges):
            counts, _ = np.histogram(v[:, j], bins=edges_f32(lo, hi, bins))
            assert counts.sum() == n
            terms += [np.float32(np.log(c / n + lam64)) for c in counts]
    return dict(**{"lambda": lam}, rows=rows, ranges=ranges, terms=terms)


def fit(path, bins_ml=22, bins_map=17, lambda_ml=0.0055, lambda_map=0.00012,
        bins_bayes=22, lambda_bayes=1e-3, bayes=True):
    """The table `mlmap fit` writes for the CSV file at `path`, as `encode`'s arguments."""
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
    head = fit_bayes(names, labels, x, bins_bayes, lambda_bayes) if bayes else None
    return classes, lambda_ml, lambda_map, head


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
    """The table in a .mlmap file as a dict (float32 values widened exactly to float64).

    Reads versions 1 and 2; `bayes` is None for a version-1 file, else a dict with the
    header's bins and categories and the section's lambda, rows, ranges and terms.
    """
    if data[:4] != MAGIC:
        raise ValueError("not a table")
    if zlib.crc32(data[:-4]) & 0xFFFFFFFF != struct.unpack("<I", data[-4:])[0]:
        raise ValueError("bad CRC")
    r = Reader(data[:-4])
    r.take(4)
    version, k, bml, bmap = (r.varint() for _ in range(4))
    if version not in (VERSION_1, VERSION_2, VERSION_3):
        raise ValueError("version")
    if version >= VERSION_2:
        bins_bayes, cats = r.varint(), r.varint()
        if bins_bayes == 0 or cats == 0:
            raise ValueError("a version-2 header announces an empty Bayes head")
    edge_mode, upper_tail = r.take(1)[0], r.take(1)[0]
    t = dict(k=k, bins_ml=bml, bins_map=bmap, edge_mode=edge_mode, upper_tail=upper_tail,
             lambda_ml=r.f32(), lambda_map=r.f32(), classes=[], bayes=None, open=None)
    if r.varint() != k:
        raise ValueError("class count")
    for _ in range(k):
        c = dict(name=r.take(r.varint()).decode(), rows=r.varint(), mean=r.f32(), var=r.f32())
        c["ml_lo"], c["ml_hi"], c["ml_freqs"] = r.f32(), r.f32(), r.f32s()
        c["map_lo"], c["map_hi"], c["map_freqs"] = r.f32(), r.f32(), r.f32s()
        t["classes"].append(c)
    if version >= VERSION_2:
        lam = r.f32()
        rows = [r.varint() for _ in range(r.varint())]
        ranges = [(r.f32(), r.f32()) for _ in range(r.varint())]
        terms = r.f32s()
        if len(rows) != cats or len(ranges) != k or len(terms) != cats * k * bins_bayes:
            raise ValueError("Bayes shape")
        # Stored logit-major (j, b, c); held category-major (c, j, b).
        terms = list(np.asarray(terms, dtype=np.float32).reshape(k, bins_bayes, cats)
                     .transpose(2, 0, 1).ravel())
        t["bayes"] = dict(bins=bins_bayes, rows=rows, ranges=ranges, terms=terms,
                          **{"lambda": lam})
    if version == VERSION_3:
        t["open"] = (r.f32(), r.f32())
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


def axis_bin(x, lo, hi, nbins):
    """The bin of x on the float32 edges of [lo, hi] (numpy's rule), None outside."""
    if not np.isfinite(x):
        return None
    edges = edges_f32(lo, hi, nbins).astype(np.float64)
    counts, _ = np.histogram(np.array([x], dtype=np.float64), bins=edges)
    if counts.sum() == 0:
        return None
    return int(np.argmax(counts))


def bayes_log_scores(t, x):
    """The log-scores l[c] of the Bayes categories (DESIGN.md section 1.6), float64."""
    b = t["bayes"]
    k, nb = t["k"], b["bins"]
    rows = np.asarray(b["rows"], dtype=np.float64)
    terms = np.asarray(b["terms"], dtype=np.float64).reshape(len(rows), k, nb)
    log_lambda = np.log(np.float64(b["lambda"]))
    l = np.log(rows / rows.sum())
    for j, (v, (lo, hi)) in enumerate(zip(x, b["ranges"])):
        i = axis_bin(v, lo, hi, nb)
        l = l + (terms[:, j, i] if i is not None else log_lambda)
    return l


def bayes_posterior(t, x):
    """The posterior p over the Bayes categories (DESIGN.md section 1.6), float64."""
    l = bayes_log_scores(t, x)
    e = np.exp(l - l.max())
    return e / e.sum()


def temperature_softmax(x, temp):
    """softmax(x / T) in float64; infinite logits as their limit (equal shares of the
    largest)."""
    z = np.asarray(x, dtype=np.float64) / temp
    m = z.max()
    if np.isinf(m):
        top = (z == m).astype(np.float64)
        return top / top.sum()
    e = np.exp(z - m)
    return e / e.sum()


def open_known(t, x):
    """q: the probability that the detection is of a known class (DESIGN.md section 1.8),
    the K classes' share of the posterior over the categories and the unknown one."""
    b = t["bayes"]
    temp, eps = t["open"]
    k = t["k"]
    l = bayes_log_scores(t, x)
    m = l.max()
    e = np.exp(l - m)
    if eps == 0.0:
        unknown = 0.0
    else:
        lam = np.float64(b["lambda"])
        log_u = np.log(np.float64(eps)) + k * np.log(1.0 / b["bins"] + lam)
        unknown = np.exp(log_u - m)
    return e[:k].sum() / (e.sum() + unknown)


def open_(t, x, os_):
    """Open-head class scores: OS * q * softmax(x / T)."""
    check(x, os_)
    return os_ * open_known(t, x) * temperature_softmax(x, t["open"][0])


def bayes(t, x, os_):
    """Bayes class scores: OS * p[c] for the K classes (the background share is dropped)."""
    check(x, os_)
    return os_ * bayes_posterior(t, x)[:t["k"]]


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

# Hand-checkable Bayes heads over the small table's classes: 4 bins per logit on round
# edges (logit 0: -4,-2,0,2,4; logit 1: -2,-1,0,1,2; logit 2: -4,-3,-2,-1,0) and, per
# category and logit, frequencies that are counts over the category's rows.
SMALL_BAYES_RANGES = [(-4.0, 4.0), (-2.0, 2.0), (-4.0, 0.0)]
SMALL_BAYES_FREQS = {
    # category: frequencies of logit 0, logit 1, logit 2
    "car": [[0.0, 0.1, 0.3, 0.6], [0.4, 0.4, 0.2, 0.0], [0.2, 0.2, 0.3, 0.3]],
    "cyclist": [[0.2, 0.5, 0.2, 0.1], [0.0, 0.1, 0.3, 0.6], [0.3, 0.3, 0.2, 0.2]],
    "pedestrian": [[0.3, 0.4, 0.2, 0.1], [0.25, 0.25, 0.25, 0.25], [0.0, 0.1, 0.3, 0.6]],
    "background": [[0.1, 0.2, 0.5, 0.2], [0.2, 0.3, 0.3, 0.2], [0.1, 0.4, 0.4, 0.1]],
}


def bayes_head(rows, lam, ranges=SMALL_BAYES_RANGES, freqs=SMALL_BAYES_FREQS):
    """A Bayes head for `encode`: rows per category (the first len(rows) categories of
    `freqs`), log-terms float32(ln(h + lambda)) computed in float64."""
    cats = list(freqs)[:len(rows)]
    lam64 = float(np.float32(lam))
    terms = [np.float32(np.log(h + lam64)) for c in cats for hist in freqs[c] for h in hist]
    return dict(**{"lambda": lam}, rows=list(rows), ranges=list(ranges), terms=terms)


# With background (categories car 40, cyclist 20, pedestrian 20, background 20 rows), and
# without (car 40, cyclist 20, pedestrian 20).
SMALL_BAYES = bayes_head([40, 20, 20, 20], 0.01)
SMALL_BAYES_NOBG = bayes_head([40, 20, 20], 0.001)
# The open head's (temperature, epsilon) on each: an unknown category of weight 0.05 and a
# temperature above 1; no unknown and a temperature below 1.
SMALL_OPEN = (1.75, 0.05)
SMALL_OPEN_NOBG = (0.8, 0.0)


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

# Cases aimed at the small Bayes heads' axes (scored with every small table).
BAYES_CASES = [
    ("bayes inside bins", [3.0, 0.5, -3.5], 1.0),
    ("bayes inside bins", [-3.0, -1.5, -0.5], 1.0),
    ("bayes inside bins", [1.0, 1.5, -2.5], 0.8),
    ("bayes inside zero-frequency bins", [-3.0, 1.5, -3.5], 1.0),
    ("bayes on inner edges", [0.0, 0.0, -2.0], 1.0),
    ("bayes on inner edges", [-2.0, -1.0, -3.0], 0.9),
    ("bayes on inner edges", [2.0, 1.0, -1.0], 1.0),
    ("bayes on first edges", [-4.0, -2.0, -4.0], 1.0),
    ("bayes on closed last edges", [4.0, 2.0, 0.0], 1.0),
    ("bayes just below inner edges", [down(2.0), down(1.0), down(-1.0)], 1.0),
    ("bayes just above last edges", [up(4.0), up(2.0), up(0.0)], 1.0),
    ("bayes just below first edges", [down(-4.0), down(-2.0), down(-4.0)], 1.0),
    ("bayes every logit outside", [10.0, 10.0, 10.0], 1.0),
    ("bayes every logit outside", [-10.0, 5.0, 1e30], 0.7),
    ("bayes every logit outside", [INF, -INF, INF], 1.0),
    ("bayes every logit outside", [-INF, INF, -INF], 0.3),
    ("bayes every logit outside at objectness 0", [10.0, 10.0, 10.0], 0.0),
    ("bayes one logit outside", [10.0, 0.5, -3.5], 1.0),
    ("bayes one logit outside", [3.0, -1e30, -3.5], 1.0),
    ("bayes infinity and inside", [INF, 0.5, -0.5], 1.0),
    ("bayes infinity and inside", [-1.0, -INF, -0.5], 0.6),
    ("bayes objectness 0", [3.0, 0.5, -3.5], 0.0),
    ("bayes objectness between", [3.0, 0.5, -3.5], 0.37),
    ("bayes objectness smallest subnormal", [3.0, 0.5, -3.5], 1e-45),
    ("bayes NaN logit", [3.0, NAN, -3.5], 1.0),
    ("bayes NaN logit and outside", [10.0, 10.0, NAN], 1.0),
    ("bayes objectness above 1", [3.0, 0.5, -3.5], 1.5),
]

# Cases for the open head beyond the Bayes ones: tied and near-tied logits, large logits
# (the softmax at a temperature), and logits far outside every axis (q from the unknown).
OPEN_CASES = [
    ("open tied logits", [0.5, 0.5, -3.5], 1.0),
    ("open tied logits outside", [50.0, 50.0, 50.0], 0.6),
    ("open large logits", [30.0, -20.0, 25.0], 1.0),
    ("open near-tied logits", [1.0, up(1.0), -1.0], 1.0),
    ("open every logit far outside", [1e6, -1e6, 1e6], 1.0),
    ("open inside every axis", [1.0, 0.2, -1.5], 0.9),
]


def fmt(v):
    """A float as text that parses back to the same value (f32 inputs stay exact)."""
    if np.isnan(v):
        return "NaN"
    if np.isinf(v):
        return "inf" if v > 0 else "-inf"
    return repr(float(v))


def golden_rows(name, t, cases):
    """One CSV row per case: inputs, ML, MAP and Bayes scores (the Bayes columns empty
    for a table without that head), or the error."""
    k = len(cases[0][1])
    rows = []
    for case, x, os_ in cases:
        x = [float(np.float32(v)) for v in x]
        os_ = float(np.float32(os_))
        try:
            scores = list(ml(t, x, os_)) + list(map_(t, x, os_))
            scores += list(bayes(t, x, os_)) if t["bayes"] is not None else [None] * k
            err = ""
        except InferenceError as e:
            scores, err = [None] * (3 * k), str(e)
        rows.append([name, case, fmt(os_)] + [fmt(v) for v in x]
                    + ["" if s is None else fmt(s) for s in scores] + [err])
    return rows


def write_csv(path, k, rows, regenerate):
    head = ["table", "case", "objectness"] + ["x%d" % i for i in range(k)] \
        + ["ml%d" % i for i in range(k)] + ["map%d" % i for i in range(k)] \
        + ["bayes%d" % i for i in range(k)] + ["error"]
    with open(path, "w") as fh:
        fh.write("# Expected ML, MAP and Bayes scores (float64) from tools/mlmap_ref.py, "
                 "numpy %s.\n" % np.__version__)
        fh.write("# Regenerate: %s\n" % regenerate)
        fh.write("# bayes*: empty for a table without a Bayes head.\n")
        fh.write("# error: empty, nan_logit:<first NaN class> or objectness.\n")
        fh.write(",".join(head) + "\n")
        for r in rows:
            fh.write(",".join(r) + "\n")


def open_rows(name, t, cases):
    """One CSV row per case for the open head: inputs, scores and q, or the error."""
    rows = []
    for case, x, os_ in cases:
        x = [float(np.float32(v)) for v in x]
        os_ = float(np.float32(os_))
        try:
            scores = list(open_(t, x, os_)) + [open_known(t, x)]
            err = ""
        except InferenceError as e:
            scores, err = [None] * (t["k"] + 1), str(e)
        rows.append([name, case, fmt(os_)] + [fmt(v) for v in x]
                    + ["" if v is None else fmt(v) for v in scores] + [err])
    return rows


def write_open_csv(path, k, rows, regenerate):
    head = ["table", "case", "objectness"] + ["x%d" % i for i in range(k)] \
        + ["open%d" % i for i in range(k)] + ["q", "error"]
    with open(path, "w") as fh:
        fh.write("# Expected open-head scores and q (float64) from tools/mlmap_ref.py, "
                 "numpy %s.\n" % np.__version__)
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


def bayes_cases(t, n, seed):
    """n random logit vectors aimed at every region of the Bayes head's axes."""
    rng = np.random.default_rng(seed)
    b = t["bayes"]
    cases = []
    for _ in range(n):
        x = []
        for lo, hi in b["ranges"]:
            kind = rng.integers(0, 10)
            span = hi - lo
            if kind < 5:  # inside or near the axis
                v = rng.uniform(lo - 0.05 * span, hi + 0.05 * span)
            elif kind < 8:  # exactly on an edge (float32, as the format defines it)
                v = float(edges_f32(lo, hi, b["bins"])[rng.integers(0, b["bins"] + 1)])
            else:  # far outside or infinite
                v = [INF, -INF, hi + 5 * span, lo - 5 * span][rng.integers(0, 4)]
            x.append(v)
        r = rng.uniform()
        os_ = 1.0 if r < 0.3 else (0.0 if r < 0.35 else rng.uniform())
        cases.append(("random bayes", x, os_))
    return cases


# Every TEST_SPLIT_STEP-th row of examples/data/test.csv, scored with the shipped table:
# the goldens of the layer's fronts (fixed-size table, run-time table, batch, the CLI).
TEST_SPLIT_STEP = 20


def test_split_cases(path, step=TEST_SPLIT_STEP):
    """(case, logits, objectness) of every `step`-th row of a data CSV, case = its id."""
    with open(path) as fh:
        r = csv.DictReader(fh)
        names = [c for c in r.fieldnames if c not in ("id", "label", "objectness")]
        rows = list(r)[::step]
    return [("id %s" % row["id"], [float(row[c]) for c in names], float(row["objectness"]))
            for row in rows]


# The quantized heads (docs/FORMAT.md, "The quantized section") score the dequantized
# logit x = float32(float32(q - zero_point) * scale) of each code q. Per table: the
# parameters (bits, scales, zero points) and the codes scored.
QUANT_PARAMS = [
    (8, [0.08, 0.08, 0.08], [0, 0, 0]),
    (8, [0.05, 0.04, 0.06], [3, -7, 0]),
    (8, [0.5, 0.5, 0.5], [-100, 20, 127]),
    (16, [0.0004, 0.0003, 0.0005], [0, 1000, -2000]),
]


def dequantize(q, scale, zp):
    """The dequantized logit of code q, in float32 as the format defines it."""
    return float(np.float32(np.float32(q - zp) * np.float32(scale)))


def quant_cases(bits, n, seed):
    """n code vectors of a `bits`-bit table: the range ends, zero, and random codes."""
    lo, hi = (-128, 127) if bits == 8 else (-32768, 32767)
    rng = np.random.default_rng(seed)
    fixed = [[lo, lo, lo], [hi, hi, hi], [0, 0, 0], [lo, 0, hi], [hi, lo, 0]]
    rand = [list(rng.integers(lo, hi + 1, size=3)) for _ in range(n - len(fixed))]
    out = []
    for i, q in enumerate(fixed + rand):
        r = rng.uniform()
        os_ = 1.0 if r < 0.3 else (0.0 if r < 0.35 else rng.uniform())
        out.append(([int(v) for v in q], float(np.float32(os_))))
    return out


def quant_rows(name, t, n, seed):
    """One CSV row per (parameters, codes): every head the table has, scored by the
    reference on the dequantized logits."""
    k = t["k"]
    rows = []
    for p, (bits, scales, zps) in enumerate(QUANT_PARAMS):
        for q, os_ in quant_cases(bits, n, seed + p):
            x = [dequantize(v, s, z) for v, s, z in zip(q, scales, zps)]
            scores = list(ml(t, x, os_)) + list(map_(t, x, os_))
            scores += list(bayes(t, x, os_)) if t["bayes"] is not None else [None] * k
            scores += list(open_(t, x, os_)) if t["open"] is not None else [None] * k
            rows.append([name, str(bits)] + [fmt(np.float32(s)) for s in scales]
                        + [str(z) for z in zps] + [str(v) for v in q] + [fmt(os_)]
                        + ["" if s is None else fmt(s) for s in scores])
    return rows


def write_quant_csv(path, k, rows, regenerate):
    head = ["table", "bits"] + ["scale%d" % i for i in range(k)] \
        + ["zp%d" % i for i in range(k)] + ["q%d" % i for i in range(k)] + ["objectness"] \
        + ["%s%d" % (h, i) for h in ("ml", "map", "bayes", "open") for i in range(k)]
    with open(path, "w") as fh:
        fh.write("# Expected scores (float64) of quantized codes from tools/mlmap_ref.py, "
                 "numpy %s.\n" % np.__version__)
        fh.write("# Regenerate: %s\n" % regenerate)
        fh.write("# Each code q scores as the logit float32(float32(q - zp) * scale).\n")
        fh.write("# bayes*, open*: empty for a table without that head.\n")
        fh.write(",".join(head) + "\n")
        for r in rows:
            fh.write(",".join(r) + "\n")


def goldens(outdir):
    import os
    os.makedirs(outdir, exist_ok=True)
    regen = "python3 tools/mlmap_ref.py goldens tests/golden/layer"
    small = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, edge_mode=0, upper_tail=0)
    clamp = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, edge_mode=0, upper_tail=1)
    with_bg = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, bayes=SMALL_BAYES)
    no_bg = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, bayes=SMALL_BAYES_NOBG)
    # The open head on both Bayes heads: with background, a temperature and an unknown
    # category; without, epsilon 0 (then the head is the temperature layer exactly).
    open_bg = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, bayes=SMALL_BAYES,
                     open_=SMALL_OPEN)
    open_nobg = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, bayes=SMALL_BAYES_NOBG,
                       open_=SMALL_OPEN_NOBG)
    files = (("small", small), ("small_clamp", clamp), ("small_bayes", with_bg),
             ("small_bayes_nobg", no_bg), ("small_open", open_bg),
             ("small_open_nobg", open_nobg))
    rows, open_table_rows = [], []
    for name, data in files:
        with open(os.path.join(outdir, name + ".mlmap"), "wb") as fh:
            fh.write(data)
        t = decode(data)
        assert encode(t["classes"], t["lambda_ml"], t["lambda_map"], t["edge_mode"],
                      t["upper_tail"], t["bayes"], t["open"]) == data
        cases = SMALL_CASES + (BAYES_CASES if t["bayes"] is not None else [])
        if t["open"] is not None:
            open_table_rows += open_rows(name, t, cases + OPEN_CASES)
        else:
            rows += golden_rows(name, t, cases)
    write_csv(os.path.join(outdir, "small.csv"), 3, rows, regen)
    here = os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(here, "..", "tables", "default.mlmap"), "rb") as fh:
        t = decode(fh.read())
    cases = default_cases(t, 300, seed=2) + bayes_cases(t, 200, seed=3)
    rows = golden_rows("default", t, cases)
    write_csv(os.path.join(outdir, "default.csv"), t["k"], rows, regen)
    if t["open"] is not None:
        open_table_rows += open_rows("default", t, cases)
    write_open_csv(os.path.join(outdir, "open.csv"), 3, open_table_rows, regen)
    split = test_split_cases(os.path.join(here, "..", "examples", "data", "test.csv"))
    write_csv(os.path.join(outdir, "test_split.csv"), t["k"],
              golden_rows("default", t, split), regen)
    quant = quant_rows("default", t, 40, seed=4)
    for name, data in files:
        if name in ("small_clamp", "small_open", "small_open_nobg"):
            quant += quant_rows(name, decode(data), 20, seed=5)
    write_quant_csv(os.path.join(outdir, "quantized.csv"), 3, quant, regen)
    print("numpy %s: wrote %s" % (np.__version__, outdir))


def main():
    args = sys.argv[1:]
    if len(args) in (3, 4) and args[0] == "fit" and args[1:-2] in ([], ["--no-bayes"]):
        classes, lml, lmap, head = fit(args[-2], bayes=len(args) == 3)
        # An untuned open head (temperature 1, epsilon 0) comes with the Bayes head.
        open_ = None if head is None else UNTUNED_OPEN
        with open(args[-1], "wb") as fh:
            fh.write(encode(classes, lml, lmap, bayes=head, open_=open_))
    elif len(args) == 2 and args[0] == "goldens":
        goldens(args[1])
    else:
        print(__doc__)
        sys.exit(2)


if __name__ == "__main__":
    main()
