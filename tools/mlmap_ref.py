#!/usr/bin/env python3
"""An independent numpy implementation of mlmap's fit, table format and layer.

It shares no code with the Rust crate: it is written from docs/DESIGN.md and docs/FORMAT.md,
so agreement between the two is evidence for both. Used to write golden values
(tests/golden/) and to cross-check tables written by `mlmap fit`.

    python3 tools/mlmap_ref.py fit examples/data/train.csv OUT.mlmap   # every head (version 3)
    python3 tools/mlmap_ref.py fit --no-bayes examples/data/train.csv OUT.mlmap  # version 1
    python3 tools/mlmap_ref.py fit --objectness-feature examples/data/train.csv OUT.mlmap  # v4
    python3 tools/mlmap_ref.py goldens tests/golden/layer              # layer goldens

`goldens` writes the small tables and the scores of every head: of hand-picked and random
logits (small.csv, default.csv, open.csv), of the tables with recalibration maps or the
objectness feature (maps.csv), of every 20th row of examples/data/test.csv with
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
# Version 4: any of the above plus recalibration maps (DESIGN.md section 1.9); its header
# always holds the Bayes shape ((0, 0) without a Bayes head), the open head's parameters
# are an option after the Bayes section, and the maps follow.
VERSION_4 = 4
# Head codes of the maps, in their order in the file.
MAP_HEADS = ("ml", "map", "bayes", "open")
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


def encode(classes, lambda_ml, lambda_map, edge_mode=0, upper_tail=0, bayes=None, open_=None,
           maps=None):
    """The bytes of a table file (docs/FORMAT.md).

    classes: list of dicts name, rows, mean, var, ml_lo, ml_hi, ml_freqs, map_lo, map_hi,
    map_freqs. bayes: None (a version-1 file) or a dict lambda, rows (per category),
    ranges (K (lo, hi) pairs) and terms (C*K*B log-terms, held category-major here, written
    logit-major): a version-2 file. open_: None, or with a Bayes head a pair
    (temperature, epsilon): a version-3 file. maps: None, or a dict head name ("ml", "map",
    "bayes", "open") -> list of (x, y) knots: a version-4 file.
    """
    k = len(classes)
    bml = len(classes[0]["ml_freqs"])
    bmap = len(classes[0]["map_freqs"])
    b = bytearray(MAGIC)
    version = VERSION_1 if bayes is None else (VERSION_2 if open_ is None else VERSION_3)
    v4 = bool(maps) or (bayes is not None and bayes.get("objectness") is not None)
    if v4:
        version = VERSION_4
    header = [version, k, bml, bmap]
    if bayes is not None:
        cats = len(bayes["rows"])
        header += [len(bayes["terms"]) // (cats * k), cats]
    elif v4:
        header += [0, 0]
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
        if v4:
            feat = bayes.get("objectness")
            if feat is None:
                b += b"\x00"
            else:
                # Held category-major (c, b); written bin-major (b, c).
                lo, hi, fterms = feat
                fm = np.asarray(fterms, dtype=np.float32).reshape(cats, -1).T
                b += b"\x01" + f32(lo) + f32(hi) + varint(fm.size)
                b += b"".join(f32(v) for v in fm.ravel())
            b += b"\x00" if open_ is None else b"\x01" + f32(open_[0]) + f32(open_[1])
        elif open_ is not None:
            b += f32(open_[0]) + f32(open_[1])
    if v4:
        maps = maps or {}
        heads = [h for h in MAP_HEADS if h in maps]
        b += varint(len(heads))
        for h in heads:
            b += bytes([MAP_HEADS.index(h)]) + varint(len(maps[h]))
            b += b"".join(f32(x) + f32(y) for x, y in maps[h])
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


def fit_bayes(names, labels, x, bins, lam, os_=None):
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
    head = dict(**{"lambda": lam}, rows=rows, ranges=ranges, terms=terms)
    if os_ is not None:
        # The objectness feature: linspace bins over the finite objectness logits of the
        # labelled rows; every row counted at its logit clamped into the axis.
        z = np.array([objectness_logit(o) for o in os_], dtype=np.float64).astype(np.float32)
        finite = z[labelled & np.isfinite(z)]
        if len(finite) == 0:
            raise ValueError("every labelled row has an objectness of 0 or 1")
        lo, hi = linspace_range(finite)
        edges = edges_f32(lo, hi, bins)
        fterms = []
        for cat in cats:
            v = np.clip(z[labels == cat], lo, hi)
            counts, _ = np.histogram(v, bins=edges)
            assert counts.sum() == len(v)
            fterms += [np.float32(np.log(c / len(v) + lam64)) for c in counts]
        head["objectness"] = (lo, hi, fterms)
    return head


def fit(path, bins_ml=22, bins_map=17, lambda_ml=0.0055, lambda_map=0.00012,
        bins_bayes=22, lambda_bayes=1e-3, bayes=True, objectness=False):
    """The table `mlmap fit` writes for the CSV file at `path`, as `encode`'s arguments."""
    names, labels, x, os_all = read_csv(path)
    classes = []
    for c, name in enumerate(names):
        v = x[[lab == name for lab in labels], c]
        ml_lo, ml_hi, ml_f = histogram(v, bins_ml)
        map_lo, map_hi, map_f = histogram(v, bins_map)
        var = max(float(np.var(v, ddof=1)) if len(v) > 1 else 0.0, VARIANCE_FLOOR)
        classes.append(dict(name=name, rows=len(v), mean=float(np.mean(v)), var=var,
                            ml_lo=ml_lo, ml_hi=ml_hi, ml_freqs=ml_f,
                            map_lo=map_lo, map_hi=map_hi, map_freqs=map_f))
    head = (fit_bayes(names, labels, x, bins_bayes, lambda_bayes,
                      os_all if objectness else None) if bayes else None)
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
    if version not in (VERSION_1, VERSION_2, VERSION_3, VERSION_4):
        raise ValueError("version")
    has_bayes = version in (VERSION_2, VERSION_3)
    if version >= VERSION_2:
        bins_bayes, cats = r.varint(), r.varint()
        if version == VERSION_4 and bins_bayes == 0 and cats == 0:
            has_bayes = False
        elif bins_bayes == 0 or cats == 0:
            raise ValueError("a header announces an empty Bayes head")
        else:
            has_bayes = True
    edge_mode, upper_tail = r.take(1)[0], r.take(1)[0]
    t = dict(k=k, bins_ml=bml, bins_map=bmap, edge_mode=edge_mode, upper_tail=upper_tail,
             lambda_ml=r.f32(), lambda_map=r.f32(), classes=[], bayes=None, open=None,
             maps={})
    if r.varint() != k:
        raise ValueError("class count")
    for _ in range(k):
        c = dict(name=r.take(r.varint()).decode(), rows=r.varint(), mean=r.f32(), var=r.f32())
        c["ml_lo"], c["ml_hi"], c["ml_freqs"] = r.f32(), r.f32(), r.f32s()
        c["map_lo"], c["map_hi"], c["map_freqs"] = r.f32(), r.f32(), r.f32s()
        t["classes"].append(c)
    if has_bayes:
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
    if version == VERSION_4:
        if has_bayes:
            flag = r.take(1)[0]
            if flag not in (0, 1):
                raise ValueError("objectness option")
            if flag == 1:
                lo, hi = r.f32(), r.f32()
                fterms = r.f32s()
                if len(fterms) != bins_bayes * cats:
                    raise ValueError("objectness shape")
                # Stored bin-major (b, c); held category-major (c, b).
                fterms = list(np.asarray(fterms, dtype=np.float32).reshape(bins_bayes, cats)
                              .T.ravel())
                t["bayes"]["objectness"] = (lo, hi, fterms)
            flag = r.take(1)[0]
            if flag not in (0, 1):
                raise ValueError("open option")
            if flag == 1:
                t["open"] = (r.f32(), r.f32())
        n = r.varint()
        if n == 0 and not (t["bayes"] or {}).get("objectness"):
            raise ValueError("a version-4 table without maps or objectness feature")
        last = -1
        for _ in range(n):
            code = r.take(1)[0]
            if code <= last or code >= len(MAP_HEADS):
                raise ValueError("map head codes")
            last = code
            t["maps"][MAP_HEADS[code]] = [(r.f32(), r.f32()) for _ in range(r.varint())]
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


def objectness_logit(os_):
    """ln(OS) - ln(1 - OS) of the float32 objectness, in float64 (-inf at 0, +inf at 1)."""
    o = float(np.float32(os_))
    with np.errstate(divide="ignore"):
        return float(np.log(np.float64(o)) - np.log(np.float64(1.0 - o)))


def bayes_log_scores(t, x, os_=1.0):
    """The log-scores l[c] of the Bayes categories (DESIGN.md section 1.6), float64; with
    the objectness feature, plus the row of the objectness logit's bin (the logit clamped
    into the feature's axis)."""
    b = t["bayes"]
    k, nb = t["k"], b["bins"]
    rows = np.asarray(b["rows"], dtype=np.float64)
    terms = np.asarray(b["terms"], dtype=np.float64).reshape(len(rows), k, nb)
    log_lambda = np.log(np.float64(b["lambda"]))
    l = np.log(rows / rows.sum())
    for j, (v, (lo, hi)) in enumerate(zip(x, b["ranges"])):
        i = axis_bin(v, lo, hi, nb)
        l = l + (terms[:, j, i] if i is not None else log_lambda)
    feat = b.get("objectness")
    if feat is not None:
        lo, hi, fterms = feat
        z = min(max(objectness_logit(os_), float(lo)), float(hi))
        i = axis_bin(z, lo, hi, nb)
        l = l + np.asarray(fterms, dtype=np.float64).reshape(len(rows), nb)[:, i]
    return l


def bayes_posterior(t, x, os_=1.0):
    """The posterior p over the Bayes categories (DESIGN.md section 1.6), float64."""
    l = bayes_log_scores(t, x, os_)
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


def open_known(t, x, os_=1.0):
    """q: the probability that the detection is of a known class (DESIGN.md section 1.8),
    the K classes' share of the posterior over the categories and the unknown one (its
    flat share on every axis: the K logits', and the objectness feature's when present)."""
    b = t["bayes"]
    temp, eps = t["open"]
    k = t["k"]
    axes = k + (1 if b.get("objectness") is not None else 0)
    l = bayes_log_scores(t, x, os_)
    m = l.max()
    e = np.exp(l - m)
    if eps == 0.0:
        unknown = 0.0
    else:
        lam = np.float64(b["lambda"])
        log_u = np.log(np.float64(eps)) + axes * np.log(1.0 / b["bins"] + lam)
        unknown = np.exp(log_u - m)
    return e[:k].sum() / (e.sum() + unknown)


def open_(t, x, os_):
    """Open-head class scores: OS * q * softmax(x / T)."""
    check(x, os_)
    return os_ * open_known(t, x, os_) * temperature_softmax(x, t["open"][0])


def bayes(t, x, os_):
    """Bayes class scores: OS * p[c] for the K classes (the background share is dropped)."""
    check(x, os_)
    return os_ * bayes_posterior(t, x, os_)[:t["k"]]


def recal_g(knots, top):
    """The map g of DESIGN.md section 1.9 at top, in float64: linear between the knots
    around it (the last knot at or below top starts the segment)."""
    xs = np.array([k[0] for k in knots])
    ys = np.array([k[1] for k in knots])
    i = min(max(int(np.searchsorted(xs, top, side="right")) - 1, 0), len(xs) - 2)
    f = min(max((top - xs[i]) / (xs[i + 1] - xs[i]), 0.0), 1.0)
    return ys[i] + (ys[i + 1] - ys[i]) * f


def recal(knots, scores):
    """A detection's scores after the map: each times g(top) / top (zeros stay zero; the
    device also keeps every score below the top strictly below g(top), a clamp that in
    float64 never binds)."""
    scores = np.asarray(scores, dtype=np.float64)
    top = scores.max()
    if not top > 0:
        return scores
    return scores / top * recal_g(knots, top)


def head_scores(t, head, x, os_):
    """A head's scores, after its map when the table holds one."""
    s = {"ml": ml, "map": map_, "bayes": bayes, "open": open_}[head](t, x, os_)
    if head in t["maps"]:
        s = recal(t["maps"][head], s)
    return s


# ---------------------------------------------------------------------------------------
# Golden files for tests/layer/ and tests/format/.

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

# Recalibration maps for the small tables (DESIGN.md section 1.9): round knots, one map
# per head; and a table without a Bayes head with maps for ML and MAP only.
SMALL_MAPS = {
    "ml": [(0.0, 0.0625), (0.25, 0.125), (0.5, 0.5), (1.0, 0.75)],
    "map": [(0.0, 0.1), (0.5, 0.1), (0.75, 0.6), (1.0, 1.0)],
    "bayes": [(0.0, 0.05), (0.125, 0.25), (0.375, 0.25), (0.625, 0.5), (0.875, 0.875),
              (1.0, 0.9375)],
    "open": [(0.0, 0.03125), (0.5, 0.25), (1.0, 1.0)],
}
# The objectness feature on the small Bayes head with background: an axis over the
# objectness logit from -4 to 4 (edges -4, -2, 0, 2, 4) and per category frequencies
# (category-major, as bayes_head holds its terms), for SMALL_BAYES's lambda.
SMALL_OSF_FREQS = {
    "car": [0.0, 0.1, 0.3, 0.6],
    "cyclist": [0.1, 0.2, 0.3, 0.4],
    "pedestrian": [0.05, 0.15, 0.4, 0.4],
    "background": [0.5, 0.3, 0.15, 0.05],
}


def small_osf():
    """SMALL_BAYES with the objectness feature."""
    head = dict(SMALL_BAYES)
    lam64 = float(np.float32(head["lambda"]))
    fterms = [np.float32(np.log(h + lam64)) for c in SMALL_OSF_FREQS for h in SMALL_OSF_FREQS[c]]
    head["objectness"] = (-4.0, 4.0, fterms)
    return head


# Objectness values aimed at the feature's bins (their logits away from the edges),
# both ends, and the clamp.
OSF_CASES = [
    ("osf objectness 0.1 (bin 0)", [3.0, 0.5, -3.5], 0.1),
    ("osf objectness 0.3 (bin 1)", [3.0, 0.5, -3.5], 0.3),
    ("osf objectness 0.5 (bin 2 from its first edge 0)", [3.0, 0.5, -3.5], 0.5),
    ("osf objectness 0.75 (bin 2)", [-3.0, -1.5, -0.5], 0.75),
    ("osf objectness 0.9 (bin 3)", [1.0, 1.5, -2.5], 0.9),
    ("osf objectness 0.999 (clamped to the last bin)", [1.0, 1.5, -2.5], 0.999),
    ("osf objectness 1 (+inf so the last bin)", [0.5, 0.5, 0.5], 1.0),
    ("osf objectness 0 (-inf so the first bin)", [0.5, 0.5, 0.5], 0.0),
    ("osf objectness 0.02 (clamped to the first bin)", [10.0, 10.0, 10.0], 0.02),
    ("osf every logit outside", [-10.0, 5.0, 1e30], 0.6),
]

SMALL_MAPS_NOBAYES = {
    "ml": [(0.0, 0.2), (1.0, 0.8)],
    "map": [(0.0, 0.015625), (0.3, 0.6), (1.0, 0.7)],
}


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


# Cases aimed at the maps: top scores on and between knots, and all-zero scores.
MAP_CASES = [
    ("maps objectness on a knot", [3.5, -1.9, -3.9], 0.5),
    ("maps objectness between knots", [3.5, -1.9, -3.9], 0.3),
    ("maps objectness quarter", [0.5, 0.5, 0.5], 0.25),
    ("maps objectness 0", [3.5, -1.9, -3.9], 0.0),
    ("maps objectness 1 inside", [2.5, 0.5, -1.5], 1.0),
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
            scores = list(open_(t, x, os_)) + [open_known(t, x, os_)]
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


def maps_rows(name, t, cases):
    """One CSV row per case for a table with maps: inputs, every head's mapped scores
    (empty for a head the table lacks), or the error."""
    k = t["k"]
    rows = []
    for case, x, os_ in cases:
        x = [float(np.float32(v)) for v in x]
        os_ = float(np.float32(os_))
        try:
            scores = []
            for head in MAP_HEADS:
                has = {"bayes": t["bayes"] is not None, "open": t["open"] is not None}
                if has.get(head, True):
                    scores += list(head_scores(t, head, x, os_))
                else:
                    scores += [None] * k
            err = ""
        except InferenceError as e:
            scores, err = [None] * (4 * k), str(e)
        rows.append([name, case, fmt(os_)] + [fmt(v) for v in x]
                    + ["" if v is None else fmt(v) for v in scores] + [err])
    return rows


def write_maps_csv(path, k, rows, regenerate):
    head = ["table", "case", "objectness"] + ["x%d" % i for i in range(k)]
    for h in MAP_HEADS:
        head += ["%s%d" % (h, i) for i in range(k)]
    head += ["error"]
    with open(path, "w") as fh:
        fh.write("# Expected scores of every head, after its recalibration map when the table "
                 "has one, of the tables with maps or the objectness feature (float64) from "
                 "tools/mlmap_ref.py, numpy %s.\n" % np.__version__)
        fh.write("# Regenerate: %s\n" % regenerate)
        fh.write("# A head's columns are empty when the table lacks it.\n")
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
    # Recalibration maps: on the open table with background (every head has one), and on
    # the table without a Bayes head (ML and MAP only).
    maps_all = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, bayes=SMALL_BAYES,
                      open_=SMALL_OPEN, maps=SMALL_MAPS)
    maps_nobayes = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, maps=SMALL_MAPS_NOBAYES)
    # The objectness feature on the open table with background (version 4, no map).
    osf = encode(SMALL, SMALL_LAMBDA_ML, SMALL_LAMBDA_MAP, bayes=small_osf(), open_=SMALL_OPEN)
    files = (("small", small), ("small_clamp", clamp), ("small_bayes", with_bg),
             ("small_bayes_nobg", no_bg), ("small_open", open_bg),
             ("small_open_nobg", open_nobg), ("small_maps", maps_all),
             ("small_maps_nobayes", maps_nobayes), ("small_osf", osf))
    rows, open_table_rows, map_table_rows = [], [], []
    for name, data in files:
        with open(os.path.join(outdir, name + ".mlmap"), "wb") as fh:
            fh.write(data)
        t = decode(data)
        assert encode(t["classes"], t["lambda_ml"], t["lambda_map"], t["edge_mode"],
                      t["upper_tail"], t["bayes"], t["open"], t["maps"] or None) == data
        cases = SMALL_CASES + (BAYES_CASES if t["bayes"] is not None else [])
        if t["bayes"] is not None and t["bayes"].get("objectness") is not None:
            map_table_rows += maps_rows(name, t, cases + OPEN_CASES + OSF_CASES)
        elif t["maps"]:
            map_table_rows += maps_rows(name, t, cases + OPEN_CASES + MAP_CASES)
        elif t["open"] is not None:
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
    write_maps_csv(os.path.join(outdir, "maps.csv"), 3, map_table_rows, regen)
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
    if (len(args) in (3, 4) and args[0] == "fit"
            and args[1:-2] in ([], ["--no-bayes"], ["--objectness-feature"])):
        classes, lml, lmap, head = fit(args[-2], bayes=args[1:-2] != ["--no-bayes"],
                                       objectness=args[1:-2] == ["--objectness-feature"])
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
