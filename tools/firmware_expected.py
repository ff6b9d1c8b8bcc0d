#!/usr/bin/env python3
"""Writes firmware/src/expected.rs: the inputs the firmware example scores on the emulated
Cortex-M4F and the scores it must get, computed here in float64.

This shares no code with the Rust crate: the table files (format version 3, with a Bayes
head and the open head's temperature and epsilon) are decoded here from docs/FORMAT.md (and
checked by re-encoding them with tools/mlmap_ref.py), bins are found by comparing against
the float32 edges the format defines, and ML and MAP are evaluated in float64 from
docs/DESIGN.md §1.2. The Bayes head's scores come from the numpy reference
(`mlmap_ref.bayes`, docs/DESIGN.md §1.6, float64). The open head's (docs/DESIGN.md §1.8) are
computed here in float64 from the decoded terms, rows, temperature and epsilon, and must
agree with the numpy reference (`mlmap_ref.open_`) to 1e-12. The firmware checks its
float32 results against these values within a tolerance, exactly where the answer is
`OS / K`, and the open head's decision against the largest logit.

Two tables are scored: the shipped one (`tables/default.mlmap`, temperature 1, epsilon 0),
and a small one with an unknown category (`tests/golden/layer/small_open.mlmap`: K = 3,
4 Bayes bins, a background category, temperature 1.75, epsilon 0.05), which the firmware
decodes from its bytes.

The recalibration maps (docs/DESIGN.md §1.9) are checked on
`tests/golden/layer/small_maps.mlmap` (the small table above with a map on every head):
its cases and every head's mapped float64 scores are copied from
`tests/golden/layer/maps.csv`, which the numpy reference (`tools/mlmap_ref.py goldens`)
wrote.

It also writes the quantized cases: int8 codes for the section of
`tables/default_q8.mlmap` (whose scales and zero points are read here from the section's
bytes, by docs/FORMAT.md), each with its dequantized logits `float32(q - zp) * scale` in
float32 and the float64 scores of those logits, as above.

The drift monitor (docs/DESIGN.md §7) is checked by a replay on the monitor section of
`tests/golden/monitor_small.mlmap` (W = 50): a short stream of rows of examples/data/test.csv
and ood.csv (an in-distribution window, an out-of-distribution one, a mixed one and a
partial last window) whose window metrics (per-logit PSI, psi_max, oos_rate, q_mean) come
from the numpy reference `tools/monitor_ref.py`, and whose alarms are those metrics against
the thresholds read here from the section's bytes. A metric closer to its threshold than
the firmware's tolerance is refused here, so the expected alarms cannot depend on rounding.

The conformal class sets (docs/DESIGN.md §8) are checked on the section of
`tests/golden/conformal_small.mlmap` (the open head at alpha 0.1): the thresholds read here
from the section's bytes must be those of `tests/golden/conformal/sets_open_0.1.csv`
(written by `tools/conformal_ref.py`), whose sets of the first test rows the firmware must
give bit for bit wherever no score lies within 1e-5 of its threshold.

    python3 tools/firmware_expected.py [TABLE] [OUT]     # defaults: tables/default.mlmap,
                                                         #           firmware/src/expected.rs
    python3 tools/firmware_expected.py --check           # exit 1 if OUT is out of date

`--check` compares the text it would write with OUT: everything but the floating-point
literals must be identical, and each literal within `TOLERANCE / 1000` of the committed one,
where TOLERANCE is the firmware's own bound on |score - expected| (read from
firmware/src/main.rs). numpy's float64 `exp` and `log` may differ in the last ulp between
CPUs (AVX-512 or not); a difference a thousand times below what the firmware accepts cannot
change its verdict, and anything larger means OUT is really out of date.
"""
import csv
import json
import math
import os
import re
import struct
import sys
import zlib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mlmap_ref  # noqa: E402  (encode and the float32 edge rule only)
import monitor_ref  # noqa: E402  (the drift monitor's windows)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_TABLE = os.path.join(ROOT, "tables", "default.mlmap")
DEFAULT_OUT = os.path.join(ROOT, "firmware", "src", "expected.rs")
TEST_CSV = os.path.join(ROOT, "examples", "data", "test.csv")
QUANTIZED = os.path.join(ROOT, "tables", "default_q8.mlmap")
SMALL_OPEN = os.path.join(ROOT, "tests", "golden", "layer", "small_open.mlmap")
SMALL_MAPS = os.path.join(ROOT, "tests", "golden", "layer", "small_maps.mlmap")
MAPS_CSV = os.path.join(ROOT, "tests", "golden", "layer", "maps.csv")
MONITOR_FILE = os.path.join(ROOT, "tests", "golden", "monitor_small.mlmap")
CONFORMAL_FILE = os.path.join(ROOT, "tests", "golden", "conformal_small.mlmap")
SETS_CSV = os.path.join(ROOT, "tests", "golden", "conformal", "sets_open_0.1.csv")
OOD_CSV = os.path.join(ROOT, "examples", "data", "ood.csv")

# Rows of examples/data/test.csv scored besides the synthetic cases.
CSV_ROWS = 16
# Below this margin between the two largest scores, the predicted class is not checked
# (float32 rounding could legitimately pick the other one).
ARGMAX_MARGIN = 1e-4
TAIL_NAMES = {0: "zero", 1: "clamp"}


class Reader:
    def __init__(self, data):
        self.data = data
        self.pos = 0

    def take(self, n):
        if self.pos + n > len(self.data):
            raise ValueError("truncated table")
        out = self.data[self.pos:self.pos + n]
        self.pos += n
        return out

    def varint(self):
        value, shift = 0, 0
        while True:
            b = self.take(1)[0]
            value |= (b & 0x7F) << shift
            shift += 7
            if not b & 0x80:
                return value

    def f32(self):
        return np.float32(struct.unpack("<f", self.take(4))[0])

    def u8(self):
        return self.take(1)[0]


# The open head's stored ranges (docs/DESIGN.md §1.8).
MIN_TEMPERATURE, MAX_TEMPERATURE = np.float32(1e-6), np.float32(1e6)
MIN_EPSILON, MAX_EPSILON = np.float32(2.0 ** -126), np.float32(1e30)


def decode(data):
    """The table as a dict, from the bytes of a version-2 or version-3 `.mlmap` file
    (`open` is None for version 2, else the pair (temperature, epsilon))."""
    body, crc = data[:-4], struct.unpack("<I", data[-4:])[0]
    if zlib.crc32(body) & 0xFFFFFFFF != crc:
        raise ValueError("CRC mismatch")
    r = Reader(body)
    if r.take(4) != mlmap_ref.MAGIC:
        raise ValueError("not a table")
    version, k, bins_ml, bins_map = (r.varint() for _ in range(4))
    if version not in (mlmap_ref.VERSION_2, mlmap_ref.VERSION_3):
        raise ValueError(f"format version {version}: the firmware checks a table with a "
                         "Bayes head (version 2 or 3)")
    bins_bayes, categories = r.varint(), r.varint()
    edge_mode, upper_tail = r.u8(), r.u8()
    lambda_ml, lambda_map = r.f32(), r.f32()
    if r.varint() != k:
        raise ValueError("class count")
    classes = []
    for _ in range(k):
        name = r.take(r.varint()).decode()
        rows = r.varint()
        mean, var = r.f32(), r.f32()
        ml_lo, ml_hi = r.f32(), r.f32()
        ml_freqs = [r.f32() for _ in range(r.varint())]
        map_lo, map_hi = r.f32(), r.f32()
        map_freqs = [r.f32() for _ in range(r.varint())]
        assert len(ml_freqs) == bins_ml and len(map_freqs) == bins_map
        classes.append(dict(name=name, rows=rows, mean=mean, var=var,
                            ml_lo=ml_lo, ml_hi=ml_hi, ml_freqs=ml_freqs,
                            map_lo=map_lo, map_hi=map_hi, map_freqs=map_freqs))
    bayes = {"lambda": r.f32(), "bins": bins_bayes}
    bayes["rows"] = [r.varint() for _ in range(r.varint())]
    bayes["ranges"] = [(r.f32(), r.f32()) for _ in range(r.varint())]
    # Stored logit-major (logit, bin, category); held category-major as in mlmap_ref.
    stored = [r.f32() for _ in range(r.varint())]
    bayes["terms"] = list(np.asarray(stored, dtype=np.float32)
                          .reshape(k, bins_bayes, categories).transpose(2, 0, 1).ravel())
    assert len(bayes["rows"]) == categories and len(bayes["ranges"]) == k
    assert len(bayes["terms"]) == categories * k * bins_bayes
    open_ = None
    if version == mlmap_ref.VERSION_3:
        temperature, epsilon = r.f32(), r.f32()
        if not MIN_TEMPERATURE <= temperature <= MAX_TEMPERATURE:
            raise ValueError(f"temperature {temperature} out of range")
        if np.signbit(epsilon) or not (epsilon == 0 or MIN_EPSILON <= epsilon <= MAX_EPSILON):
            raise ValueError(f"epsilon {epsilon} out of range")
        open_ = (temperature, epsilon)
    if r.pos != len(body):
        raise ValueError("trailing bytes")
    # The decoder and the independent encoder must agree byte for byte.
    again = mlmap_ref.encode(classes, lambda_ml, lambda_map, edge_mode, upper_tail, bayes,
                             open_)
    if again != bytes(data):
        raise ValueError("re-encoding the decoded table gives other bytes")
    return dict(k=k, bins_ml=bins_ml, bins_map=bins_map, edge_mode=edge_mode,
                upper_tail=upper_tail, lambda_ml=lambda_ml, lambda_map=lambda_map,
                classes=classes, bayes=bayes, open=open_, crc=crc)


def likelihood(x, lo, hi, freqs, upper_tail):
    """Frequency of the bin holding float32 `x` (numpy's rule, last bin closed), else 0."""
    edges = mlmap_ref.edges_f32(lo, hi, len(freqs))
    if x > edges[-1] and upper_tail == 1:
        return float(freqs[-1])
    if not (edges[0] <= x <= edges[-1]):
        return 0.0
    for b in range(len(freqs)):
        if edges[b] <= x < edges[b + 1] or (b == len(freqs) - 1 and x == edges[-1]):
            return float(freqs[b])
    raise AssertionError("unreachable")


def gaussian(x, mean, var):
    if not math.isfinite(x):
        return 0.0
    mean, var = float(mean), float(var)
    return math.exp(-((x - mean) ** 2) / (2.0 * var)) / math.sqrt(2.0 * math.pi * var)


def layer(table, logits, os_):
    """float64 ML and MAP scores, and whether each head had no evidence at all."""
    ml_a, map_a = [], []
    for c, x in zip(table["classes"], logits):
        x = float(x)
        l_ml = likelihood(np.float32(x), c["ml_lo"], c["ml_hi"], c["ml_freqs"], table["upper_tail"])
        l_map = likelihood(np.float32(x), c["map_lo"], c["map_hi"], c["map_freqs"],
                           table["upper_tail"])
        ml_a.append(l_ml)
        map_a.append(l_map * gaussian(x, c["mean"], c["var"]) if l_map > 0 else 0.0)
    os_ = float(os_)
    out = []
    for a, lam in ((ml_a, float(table["lambda_ml"])), (map_a, float(table["lambda_map"]))):
        uniform = all(v == 0.0 for v in a)
        total = sum(v + lam for v in a)
        out.append(([os_ * (v + lam) / total for v in a], uniform))
    return out


def bayes_scores(table, logits, os_):
    """float64 Bayes scores from the numpy reference (mlmap_ref.bayes)."""
    return [float(v) for v in mlmap_ref.bayes(table, [float(x) for x in logits], float(os_))]


def bayes_bin(x, lo, hi, bins):
    """The Bayes bin holding float32 `x` on the axis [lo, hi] (numpy's rule, last bin
    closed), None outside the axis (no tail rule: outside is outside)."""
    edges = mlmap_ref.edges_f32(lo, hi, bins)
    if not (edges[0] <= x <= edges[-1]):
        return None
    for b in range(bins):
        if edges[b] <= x < edges[b + 1] or (b == bins - 1 and x == edges[-1]):
            return b
    raise AssertionError("unreachable")


def open_scores(table, logits, os_):
    """float64 open-head scores (docs/DESIGN.md §1.8): OS * q * softmax(z / T), with q the
    K classes' share of the posterior over the Bayes categories and the unknown one."""
    b = table["bayes"]
    temperature, epsilon = (float(v) for v in table["open"])
    k, bins = table["k"], b["bins"]
    lam = float(b["lambda"])
    cats = len(b["rows"])
    total = float(sum(b["rows"]))
    terms = np.asarray(b["terms"], dtype=np.float64).reshape(cats, k, bins)
    # l[c] = ln pi[c] + sum_j ln(h[c][j](z_j) + lambda), the stored terms inside an axis
    # and ln(lambda) (h = 0) outside it.
    l = []
    for c in range(cats):
        v = math.log(b["rows"][c] / total)
        for j, (x, (lo, hi)) in enumerate(zip(logits, b["ranges"])):
            i = bayes_bin(np.float32(x), lo, hi, bins)
            v += math.log(lam) if i is None else float(terms[c, j, i])
        l.append(v)
    m = max(l)
    e = [math.exp(v - m) for v in l]
    unknown = 0.0
    if epsilon > 0.0:
        log_u = math.log(epsilon) + k * math.log(1.0 / bins + lam)
        # Beyond e^700 the unknown outweighs the categories by more than 1e300: q is
        # then below 1e-300, 0 for every tolerance used here.
        unknown = math.exp(min(log_u - m, 700.0))
    q = sum(e[:k]) / (sum(e) + unknown)
    # softmax(z / T); infinite logits as their limit: equal shares of the largest.
    z = [float(x) / temperature for x in logits]
    top = max(z)
    if math.isinf(top):
        p = [1.0 if v == top else 0.0 for v in z]
    else:
        p = [math.exp(v - top) for v in z]
    total_p = sum(p)
    scores = [float(os_) * q * v / total_p for v in p]
    # The numpy reference of the same definition must agree.
    ref = mlmap_ref.open_(table, [float(x) for x in logits], float(os_))
    for a, r in zip(scores, ref):
        assert abs(a - float(r)) <= 1e-12 * max(1.0, abs(a)), (logits, os_, scores, list(ref))
    return scores


def decision(logits):
    """The open head's decision (docs/DESIGN.md §1.8): the largest logit, the lower index
    among equal ones."""
    best = 0
    for i, x in enumerate(logits):
        if x > logits[best]:
            best = i
    return best


def argmax(scores):
    order = sorted(range(len(scores)), key=lambda i: (-scores[i], i))
    if len(scores) > 1 and scores[order[0]] - scores[order[1]] < ARGMAX_MARGIN:
        return None
    return order[0]


def cases(table):
    """(label, logits, objectness) triples, float32 values."""
    f = np.float32
    cls = table["classes"]
    k = table["k"]
    out = []

    def add(label, logits, os_):
        out.append((label, [f(v) for v in logits], f(os_)))

    ml_edges = [mlmap_ref.edges_f32(c["ml_lo"], c["ml_hi"], table["bins_ml"]) for c in cls]
    map_edges = [mlmap_ref.edges_f32(c["map_lo"], c["map_hi"], table["bins_map"]) for c in cls]
    for b in (0, table["bins_ml"] // 2, table["bins_ml"] - 1):
        add(f"inside ML bin {b} of every class", [(e[b] + e[b + 1]) / 2 for e in ml_edges], 1.0)
    for b in (1, table["bins_ml"] // 3, table["bins_ml"] - 1):
        add(f"on inner ML edge {b} of every class", [e[b] for e in ml_edges], 0.9)
    for b in (1, table["bins_map"] // 2):
        add(f"on inner MAP edge {b} of every class", [e[b] for e in map_edges], 0.8)
    add("on the first ML edge of every class", [e[0] for e in ml_edges], 1.0)
    add("on the closed last ML edge of every class", [e[-1] for e in ml_edges], 1.0)
    add("on the closed last MAP edge of every class", [e[-1] for e in map_edges], 0.75)
    for i in range(k):
        xs = [(e[3] + e[4]) / 2 for e in ml_edges]
        xs[i] = np.nextafter(f(ml_edges[i][-1]), f(np.inf))
        add(f"class {i} one ulp above its last ML edge", xs, 1.0)
        xs = [(e[3] + e[4]) / 2 for e in ml_edges]
        xs[i] = np.nextafter(f(ml_edges[i][0]), f(-np.inf))
        add(f"class {i} one ulp below its first ML edge", xs, 1.0)
        xs = [-1e4] * k
        xs[i] = cls[i]["mean"]
        add(f"only class {i} in support, at its mean", xs, 0.6)
    far = max(max(c["ml_hi"], c["map_hi"]) for c in cls) + 100.0
    add("far above every support", [far] * k, 0.7)
    add("far below every support", [-far] * k, 0.7)
    add("alternating far outside", [far if i % 2 else -far for i in range(k)], 1.0)
    add("+inf everywhere", [np.inf] * k, 1.0)
    add("-inf everywhere", [-np.inf] * k, 0.5)
    add("largest finite values", [3.4e38 if i % 2 else -3.4e38 for i in range(k)], 1.0)
    mid = [(e[5] + e[6]) / 2 for e in ml_edges]
    add("+inf in class 0, others inside", [np.inf] + mid[1:], 1.0)
    add("-inf in the last class, others inside", mid[:-1] + [-np.inf], 0.9)
    for os_ in (0.0, 1.0, 0.37, 1e-6):
        add(f"objectness {os_}", [c["mean"] for c in cls], os_)
    add("objectness 0, outside every support", [far] * k, 0.0)
    b = table["bayes"]
    bayes_edges = [mlmap_ref.edges_f32(lo, hi, b["bins"]) for lo, hi in b["ranges"]]
    for i in (0, b["bins"] // 2, b["bins"] - 1):
        add(f"inside Bayes bin {i} of every logit",
            [(e[i] + e[i + 1]) / 2 for e in bayes_edges], 1.0)
    for i in (1, b["bins"] // 3):
        add(f"on inner Bayes edge {i} of every logit", [e[i] for e in bayes_edges], 0.9)
    add("on the first Bayes edge of every logit", [e[0] for e in bayes_edges], 1.0)
    add("on the closed last Bayes edge of every logit", [e[-1] for e in bayes_edges], 0.8)
    add("one ulp outside every Bayes axis",
        [np.nextafter(e[-1] if i % 2 else e[0], f(np.inf) if i % 2 else f(-np.inf))
         for i, e in enumerate(bayes_edges)], 1.0)
    add("one ulp outside every Bayes axis, objectness 0.25",
        [np.nextafter(e[-1], f(np.inf)) for e in bayes_edges], 0.25)
    mid = [(e[b["bins"] // 2] + e[b["bins"] // 2 + 1]) / 2 for e in bayes_edges]
    add("logit 0 below its Bayes axis, others inside",
        [np.nextafter(bayes_edges[0][0], f(-np.inf))] + mid[1:], 1.0)
    with open(TEST_CSV) as fh:
        for row in list(csv.DictReader(fh))[:CSV_ROWS]:
            add(f"test.csv id {row['id']} ({row['label']})",
                [float(row[c["name"]]) for c in cls], float(row["objectness"]))
    return out


def small_cases(table):
    """(label, logits, objectness) triples for the small table with an unknown category:
    every Bayes bin and edge, outside the axes (where the unknown category dominates),
    infinite and tied logits, and a fixed pseudo-random grid. Logits stay within a few
    units, where the float32 `z / T` of a temperature other than 1 rounds far below the
    firmware's tolerance."""
    f = np.float32
    b = table["bayes"]
    k, bins = table["k"], b["bins"]
    edges = [mlmap_ref.edges_f32(lo, hi, bins) for lo, hi in b["ranges"]]
    out = []

    def add(label, logits, os_):
        out.append((label, [f(v) for v in logits], f(os_)))

    for i in range(bins):
        add(f"inside Bayes bin {i} of every logit", [(e[i] + e[i + 1]) / 2 for e in edges], 1.0)
        add(f"inside Bayes bin {i} of logit 0, bin {bins - 1 - i} of the others",
            [(edges[0][i] + edges[0][i + 1]) / 2]
            + [(e[bins - 1 - i] + e[bins - i]) / 2 for e in edges[1:]], 0.9)
    for i in range(bins + 1):
        add(f"on Bayes edge {i} of every logit", [e[i] for e in edges], 0.8)
    add("one ulp below every Bayes axis", [np.nextafter(e[0], f(-np.inf)) for e in edges], 1.0)
    add("one ulp above every Bayes axis", [np.nextafter(e[-1], f(np.inf)) for e in edges], 1.0)
    mid = [(e[1] + e[2]) / 2 for e in edges]
    for j in range(k):
        xs = list(mid)
        xs[j] = np.nextafter(edges[j][-1], f(np.inf))
        add(f"logit {j} one ulp above its Bayes axis, others inside", xs, 1.0)
        xs = list(mid)
        xs[j] = edges[j][0] - 3.0
        add(f"logit {j} below its Bayes axis, others inside", xs, 0.7)
    for os_ in (1.0, 0.37, 1e-6, 0.0):
        add(f"outside every Bayes axis, objectness {os_}",
            [e[-1] + 1.5 if j % 2 else e[0] - 1.5 for j, e in enumerate(edges)], os_)
    add("+inf in logit 1, others inside", [mid[0], np.inf, mid[2]], 1.0)
    add("+inf in logits 0 and 2", [np.inf, mid[1], np.inf], 0.6)
    add("+inf everywhere", [np.inf] * k, 1.0)
    add("-inf everywhere", [-np.inf] * k, 0.5)
    add("-inf in logit 0, others inside", [-np.inf] + mid[1:], 0.9)
    add("tied largest logits 0 and 1", [1.0, 1.0, -1.0], 1.0)
    add("tied largest logits 1 and 2", [-3.0, 0.5, 0.5], 0.8)
    add("all logits equal", [0.25] * k, 1.0)
    add("logits one ulp apart", [1.5, np.nextafter(f(1.5), f(2.0)), -2.0], 1.0)
    rng = np.random.default_rng(1708)
    for n in range(12):
        xs = [rng.uniform(e[0] - 1.0, e[-1] + 1.0) for e in edges]
        add(f"grid point {n}", xs, rng.choice([1.0, 0.8, 0.55]))
    return out


def quantization(data, table_crc):
    """(bits, scales, zero points) of the quantized section at the end of `data`
    (docs/FORMAT.md, "The quantized section"), after checking its CRC, magic, version and
    the table it names."""
    n, crc = struct.unpack("<II", data[-8:])
    sec = data[-n:]
    if zlib.crc32(sec[:-4]) & 0xFFFFFFFF != crc or sec[:4] != b"MLMQ" or sec[4] not in (1, 2):
        raise ValueError("not a valid quantized section")
    bits, flags = sec[5], sec[6]
    k, bins_ml = struct.unpack("<HH", sec[8:12])
    if struct.unpack("<I", sec[16:20])[0] != table_crc:
        raise ValueError("the section was computed from another table")
    pos, scales, zps = 32, [], []
    width = 1 if bins_ml <= 256 else 2
    for _ in range(k):
        scale, zp, _start, n_ml = struct.unpack("<fiiI", sec[pos:pos + 16])
        scales.append(np.float32(scale))
        zps.append(zp)
        pos += 16 + width * n_ml + 4 * bins_ml
        _start, n_map = struct.unpack("<iI", sec[pos:pos + 8])
        pos += 8 + 4 * n_map
    assert bits == 8 and flags == 1, "the firmware checks an int8 section with the Bayes head"
    return bits, scales, zps


def quantized_cases(table, scales, zps):
    """(label, codes) pairs: extremes, each class's mean, and the test rows' logits
    rounded to codes."""
    k = table["k"]
    cls = table["classes"]

    def code(x, c):
        return int(min(127, max(-128, round(float(x) / float(scales[c])) + zps[c])))

    out = [("every code -128", [-128] * k), ("every code 127", [127] * k),
           ("every code 0", [0] * k), ("codes -128, 127, ...", [127 if i % 2 else -128 for i in range(k)])]
    for i in range(k):
        xs = [-128] * k
        xs[i] = code(cls[i]["mean"], i)
        out.append((f"only class {i} near its mean", xs))
    with open(TEST_CSV) as fh:
        for row in list(csv.DictReader(fh))[:CSV_ROWS]:
            out.append((f"test.csv id {row['id']} as codes",
                        [code(row[c["name"]], i) for i, c in enumerate(cls)]))
    return out


def error_cases(k):
    """(label, logits, objectness, expected error) for inputs the layer must reject."""
    f = np.float32
    out = []
    for i in range(k):
        xs = [f(1.0)] * k
        xs[i] = f(np.nan)
        out.append((f"NaN logit in class {i}", xs, f(0.9), f"NanLogit {{ class: {i} }}"))
    out.append(("NaN logits everywhere", [f(np.nan)] * k, f(1.0), "NanLogit { class: 0 }"))
    out.append(("NaN logit and bad objectness", [f(np.nan)] * k, f(2.0),
                "NanLogit { class: 0 }"))
    for os_ in (1.5, -0.25, np.inf, np.nan):
        out.append((f"objectness {os_}", [f(0.0)] * k, f(os_), "Objectness"))
    out.append(("objectness just above 1", [f(0.0)] * k,
                np.nextafter(f(1.0), f(2.0)), "Objectness"))
    return out


def map_cases(k):
    """The rows of maps.csv for small_maps.mlmap: (case, logits, objectness, the four
    heads' scores (ML, MAP, Bayes, open), or the Rust error)."""
    with open(MAPS_CSV, newline="") as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    out = []
    for r in rows:
        if r["table"] != "small_maps":
            continue
        logits = [np.float32(r[f"x{i}"]) for i in range(k)]
        os_ = np.float32(r["objectness"])
        err = r["error"]
        if err.startswith("nan_logit:"):
            err = f"Some(InferError::NanLogit {{ class: {int(err[len('nan_logit:'):])} }})"
            scores = [[0.0] * k for _ in range(4)]
        elif err == "objectness":
            err = "Some(InferError::Objectness)"
            scores = [[0.0] * k for _ in range(4)]
        elif err == "":
            err = "None"
            scores = [[float(r[f"{h}{i}"]) for i in range(k)]
                      for h in ("ml", "map", "bayes", "open")]
        else:
            raise ValueError(f"{MAPS_CSV}: unknown error {err!r}")
        out.append((r["case"], logits, os_, scores, err))
    if len(out) < 40:
        raise ValueError(f"{MAPS_CSV}: only {len(out)} rows for small_maps")
    return out

# The monitor replay: (source, first row, rows) blocks of the stream, in order.
MONITOR_STREAM = (("test", 0, 50), ("ood", 0, 50), ("test", 50, 40), ("ood", 50, 10),
                  ("test", 90, 20))
# A metric closer than this (relative to 1 + |threshold|) to its threshold is refused.
MONITOR_MARGIN = 1e-4
# Below this gap between the two largest per-logit PSI, psi_logit is not checked.
PSI_LOGIT_MARGIN = 1e-4


def monitor_replay(table_crc):
    """(rows, windows, thresholds, window size): the stream's rows as (float32 logits,
    objectness) and each window's expected metrics and alarms."""
    with open(MONITOR_FILE, "rb") as fh:
        data = fh.read()
    table_bytes, sections = monitor_ref.split_sections(data)
    if struct.unpack("<I", table_bytes[-4:])[0] != table_crc:
        raise ValueError(f"{MONITOR_FILE}: not a section of the shipped table")
    t = mlmap_ref.decode(table_bytes)
    sec = monitor_ref.read_monitor_section(sections[b"MLMW"])
    if sec["table_crc"] != table_crc or not sec["has_q"]:
        raise ValueError(f"{MONITOR_FILE}: the section does not name the shipped table")
    ref = monitor_ref.reference(t)
    # The stored shares are the float32 of the reference's.
    assert np.abs(ref - sec["reference"]).max() < 1e-7
    w = sec["window"]
    data_ = {}
    for name, path in (("test", TEST_CSV), ("ood", OOD_CSV)):
        _, _, x, os_ = monitor_ref.logits_f32(path)
        data_[name] = (x, os_.astype(np.float32))
    xs, oss = [], []
    for name, start, n in MONITOR_STREAM:
        x, os_ = data_[name]
        xs.append(x[start:start + n])
        oss.append(os_[start:start + n])
    x, os_ = np.concatenate(xs), np.concatenate(oss)
    bins_ = monitor_ref.row_bins(t, x)
    outside = monitor_ref.row_outside(bins_, ref)
    q = monitor_ref.row_q(t, x)
    th = (float(sec["psi"]), float(sec["oos"]), float(sec["q"]))
    if MONITOR_MARGIN < 10 * firmware_tolerance(name="MONITOR_TOLERANCE"):
        raise ValueError("MONITOR_MARGIN must be well above the firmware's MONITOR_TOLERANCE")
    windows = []
    for i, start in enumerate(range(0, len(x), w)):
        idx = np.arange(start, min(start + w, len(x)))
        m = monitor_ref.window_metrics(bins_, outside, q, ref, idx)
        full = len(idx) == w
        for v, tv in ((m["psi_max"], th[0]), (m["oos_rate"], th[1]), (m["q_mean"], th[2])):
            if abs(v - tv) <= MONITOR_MARGIN * (1.0 + abs(tv)):
                raise ValueError(f"window {i}: a metric {v} is too close to its threshold {tv}")
        alarms = (full and m["psi_max"] > th[0], full and m["oos_rate"] > th[1],
                  full and m["q_mean"] < th[2])
        top = sorted(m["psi"], reverse=True)
        logit = m["psi_logit"] if top[0] - top[1] > PSI_LOGIT_MARGIN else None
        windows.append(dict(window=i, rows=len(idx), psi=[float(v) for v in m["psi"]],
                            psi_max=m["psi_max"], psi_logit=logit, oos_rate=m["oos_rate"],
                            q_mean=m["q_mean"], alarms=alarms))
    if not any(any(v["alarms"]) for v in windows) or all(
            any(v["alarms"]) for v in windows if v["rows"] == w):
        raise ValueError("the replay needs a window with an alarm and a full one without")
    if windows[-1]["rows"] == w:
        raise ValueError("the replay must end with a partial window")
    rows = [([np.float32(v) for v in r], np.float32(o)) for r, o in zip(x, os_)]
    return rows, windows, th, w


def conformal_cases(table_crc, k):
    """(alpha, thresholds, cases): the section's alpha and thresholds (read from its
    bytes, and checked against the CSV's), and per row of sets_open_0.1.csv the test row's
    logits, objectness, the expected mask and whether it is compared."""
    with open(CONFORMAL_FILE, "rb") as fh:
        data = fh.read()
    table_bytes, sections = monitor_ref.split_sections(data)
    if struct.unpack("<I", table_bytes[-4:])[0] != table_crc:
        raise ValueError(f"{CONFORMAL_FILE}: not a section of the shipped table")
    sec = sections[b"MLMS"]
    magic, version, head, _r, k_, _r2, crc, alpha = struct.unpack_from("<4sBBHHHIf", sec, 0)
    if (magic, version, head, k_, crc) != (b"MLMS", 1, 3, k, table_crc):
        raise ValueError(f"{CONFORMAL_FILE}: not an open-head section of the shipped table")
    stored = [struct.unpack_from("<If", sec, 20 + 8 * c) for c in range(k)]
    with open(SETS_CSV, newline="") as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    with open(TEST_CSV, newline="") as fh:
        test = list(csv.DictReader(fh))
    names = [f[2:] for f in rows[0] if f.startswith("t_")]
    thresholds = [float(rows[0][f"t_{n}"]) for n in names]
    for (_, t32), t64 in zip(stored, thresholds):
        assert abs(float(t32) - t64) <= 1e-7, (t32, t64)
    out = []
    for r in rows:
        i = int(r["row"])
        d = test[i]
        logits = [np.float32(d[n]) for n in names]
        out.append((f"test.csv id {d['id']}", logits, np.float32(d["objectness"]),
                    int(r["mask"]), float(r["margin"]) > 1e-5))
    if sum(c[4] for c in out) < 10:
        raise ValueError(f"{SETS_CSV}: fewer than 10 rows away from the thresholds")
    return np.float32(alpha), thresholds, out


def lit(v):
    """A Rust f32 expression for float32 `v`, exact."""
    v = np.float32(v)
    if np.isnan(v):
        return "f32::NAN"
    if np.isinf(v):
        return "f32::INFINITY" if v > 0 else "f32::NEG_INFINITY"
    s = str(v)
    if "e" not in s and "." not in s:
        s += ".0"
    assert np.float32(s) == v, (s, v)
    return s


def lit64(v):
    s = repr(float(v))
    return s if ("." in s or "e" in s) else s + ".0"


def case_lines(table, label, logits, os_, pad):
    """The lines of one `Case` (its float64 scores for every head), indented by `pad`."""
    k = table["k"]
    (ml, ml_uniform), (mp, map_uniform) = layer(table, logits, os_)
    bayes = bayes_scores(table, logits, os_)
    opened = open_scores(table, logits, os_)
    # No evidence in a head: every score is exactly OS / K in float32.
    share = np.float32(os_) / np.float32(k)
    if ml_uniform:
        assert all(abs(v - float(share)) < 1e-7 for v in ml)
    if map_uniform:
        assert all(abs(v - float(share)) < 1e-7 for v in mp)
    lines = [
        "Case {",
        f"    label: {json.dumps(label)},",
        f"    logits: [{', '.join(lit(x) for x in logits)}],",
        f"    objectness: {lit(os_)},",
    ]
    for head, scores, uniform in (("ml", ml, ml_uniform), ("map", mp, map_uniform),
                                  ("bayes", bayes, False)):
        lines += [
            f"    {head}: Expect {{",
            f"        scores: [{', '.join(lit64(v) for v in scores)}],",
            f"        uniform: {str(uniform).lower()},",
            f"        argmax: {rust_opt(argmax(scores))},",
            "    },",
        ]
    lines += [
        "    open: OpenExpect {",
        f"        scores: [{', '.join(lit64(v) for v in opened)}],",
        f"        decision: {decision(logits)},",
        "    },",
        "},",
    ]
    return [pad + line for line in lines]


def render(table, source, small, small_source):
    k = table["k"]
    if table["open"] is None or small["open"] is None:
        raise ValueError("the firmware checks the open head: both tables must be version 3")
    if small["k"] != k or [c["name"] for c in small["classes"]] != [
            c["name"] for c in table["classes"]]:
        raise ValueError("the small table must have the shipped table's classes")
    names = ", ".join(f'"{c["name"]}"' for c in table["classes"])
    sb = small["bayes"]
    lines = [
        f"//! Inputs and expected scores for the firmware example, computed in float64 by",
        f"//! `python3 tools/firmware_expected.py` from `{source}` and `{small_source}`.",
        "//! Generated: do not edit; `.ci/firmware.sh` checks that it is up to date.",
        "",
        "use crate::case::{Case, ErrorCase, Expect, MapCase, OpenExpect, QCase, SetCase, WindowCase};",
        "use mlmap::InferError;",
        "",
        "/// Number of classes of the table.",
        f"pub const K: usize = {k};",
        f"/// The classes, in order: {names}.",
        f"pub const CLASS_NAMES: [&str; K] = [{names}];",
        "/// CRC-32 of the table the values were computed from (its last four bytes).",
        f"pub const TABLE_CRC: u32 = 0x{table['crc']:08x};",
        "/// The open head's temperature and epsilon stored in that table.",
        f"pub const OPEN_PARAMS: (f32, f32) = ({lit(table['open'][0])}, {lit(table['open'][1])});",
        "",
        "/// Valid detections and their float64 ML, MAP, Bayes and open-head scores.",
        "pub static CASES: &[Case<K>] = &[",
    ]
    for label, logits, os_ in cases(table):
        lines += case_lines(table, label, logits, os_, "    ")
    lines += [
        "];",
        "",
        f"/// Shape of `{small_source}`: ML bins, MAP bins, Bayes bins, Bayes categories.",
        f"pub const SMALL_SHAPE: (usize, usize, usize, usize) = ({small['bins_ml']}, "
        f"{small['bins_map']}, {sb['bins']}, {len(sb['rows'])});",
        "/// CRC-32 of that table.",
        f"pub const SMALL_TABLE_CRC: u32 = 0x{small['crc']:08x};",
        "/// Its open head's temperature and epsilon (an unknown category of weight epsilon).",
        f"pub const SMALL_OPEN_PARAMS: (f32, f32) = ({lit(small['open'][0])}, "
        f"{lit(small['open'][1])});",
        "",
        "/// Valid detections on that table and their float64 scores.",
        "pub static SMALL_CASES: &[Case<K>] = &[",
    ]
    for label, logits, os_ in small_cases(small):
        lines += case_lines(small, label, logits, os_, "    ")
    with open(QUANTIZED, "rb") as fh:
        _, scales, zps = quantization(fh.read(), table["crc"])
    lines += [
        "];",
        "",
        f"/// Scales of the quantized section of `{os.path.relpath(QUANTIZED, ROOT)}`.",
        f"pub const Q_SCALES: [f32; K] = [{', '.join(lit(v) for v in scales)}];",
        "/// Zero points of that section.",
        f"pub const Q_ZERO_POINTS: [i32; K] = [{', '.join(str(z) for z in zps)}];",
        "",
        "/// int8 codes, their dequantized logits and the float64 scores of those.",
        "pub static QCASES: &[QCase<K>] = &[",
    ]
    for n, (label, codes) in enumerate(quantized_cases(table, scales, zps)):
        os_ = np.float32([1.0, 0.8, 0.55][n % 3])
        logits = [np.float32(np.float32(q - z) * s) for q, z, s in zip(codes, zps, scales)]
        lines += [
            "    QCase {",
            f"        codes: [{', '.join(str(q) for q in codes)}],",
        ]
        case = case_lines(table, label, logits, os_, "        ")
        case[0] = "        case: Case {"
        lines += case
        lines += ["    },"]
    lines += ["];", "", "/// Inputs the layer must reject, and the error it must give.",
              "pub static ERROR_CASES: &[ErrorCase<K>] = &["]
    for label, logits, os_, err in error_cases(k):
        lines += [
            "    ErrorCase {",
            f"        label: {json.dumps(label)},",
            f"        logits: [{', '.join(lit(x) for x in logits)}],",
            f"        objectness: {lit(os_)},",
            f"        error: InferError::{err},",
            "    },",
        ]
    with open(SMALL_MAPS, "rb") as fh:
        maps_crc = struct.unpack("<I", fh.read()[-4:])[0]
    lines += [
        "];",
        "",
        f"/// CRC of `{os.path.relpath(SMALL_MAPS, ROOT)}`, the small table with a recalibration",
        "/// map on every head.",
        f"pub const MAPS_TABLE_CRC: u32 = 0x{maps_crc:08x};",
        "",
        "/// Detections and every head's scores after its map (ML, MAP, Bayes, open), from",
        f"/// `{os.path.relpath(MAPS_CSV, ROOT)}` (the numpy reference), or the error.",
        "pub static MAP_CASES: &[MapCase<K>] = &[",
    ]
    for label, logits, os_, scores, err in map_cases(k):
        lines += [
            "    MapCase {",
            f"        label: {json.dumps(label)},",
            f"        logits: [{', '.join(lit(x) for x in logits)}],",
            f"        objectness: {lit(os_)},",
            "        scores: [",
        ]
        lines += [f"            [{', '.join(lit64(v) for v in h)}]," for h in scores]
        lines += ["        ],", f"        error: {err},", "    },"]
    rows, windows, th, w = monitor_replay(table["crc"])
    lines += [
        "];",
        "",
        f"/// The window of the monitor section of `{os.path.relpath(MONITOR_FILE, ROOT)}`.",
        f"pub const MONITOR_WINDOW: u32 = {w};",
        "/// Its thresholds of psi_max, oos_rate and q_mean, as stored.",
        f"pub const MONITOR_THRESHOLDS: (f32, f32, f32) = ({lit(th[0])}, {lit(th[1])}, {lit(th[2])});",
        "",
        "/// The replayed stream, in order: (logits, objectness) of rows of test.csv and ood.csv",
        f"/// ({', '.join(f'{name} {a}..{a + n}' for name, a, n in MONITOR_STREAM)}).",
        "pub static MONITOR_ROWS: &[([f32; K], f32)] = &[",
    ]
    lines += [f"    ([{', '.join(lit(v) for v in x)}], {lit(o)})," for x, o in rows]
    lines += [
        "];",
        "",
        "/// Each window's metrics (numpy reference, float64) and alarms; the last is partial.",
        "pub static MONITOR_WINDOWS: &[WindowCase<K>] = &[",
    ]
    for m in windows:
        lines += [
            "    WindowCase {",
            f"        window: {m['window']},",
            f"        rows: {m['rows']},",
            f"        psi: [{', '.join(lit64(v) for v in m['psi'])}],",
            f"        psi_max: {lit64(m['psi_max'])},",
            f"        psi_logit: {rust_opt(m['psi_logit'])},",
            f"        oos_rate: {lit64(m['oos_rate'])},",
            f"        q_mean: {lit64(m['q_mean'])},",
            f"        alarms: ({', '.join(str(bool(a)).lower() for a in m['alarms'])}),",
            "    },",
        ]
    alpha, thresholds, sets = conformal_cases(table["crc"], k)
    lines += [
        "];",
        "",
        f"/// The alpha of the conformal section of `{os.path.relpath(CONFORMAL_FILE, ROOT)}` (open",
        "/// head).",
        f"pub const CONFORMAL_ALPHA: f32 = {lit(alpha)};",
        "/// Its thresholds, from the numpy reference.",
        f"pub const CONFORMAL_THRESHOLDS: [f64; K] = [{', '.join(lit64(v) for v in thresholds)}];",
        "",
        f"/// Detections and their sets (`{os.path.relpath(SETS_CSV, ROOT)}`).",
        "pub static SET_CASES: &[SetCase<K>] = &[",
    ]
    for label, logits, os_, mask, compared in sets:
        lines += [
            "    SetCase {",
            f"        label: {json.dumps(label)},",
            f"        logits: [{', '.join(lit(x) for x in logits)}],",
            f"        objectness: {lit(os_)},",
            f"        mask: {mask},",
            f"        compared: {str(compared).lower()},",
            "    },",
        ]
    lines += ["];", ""]
    return "\n".join(lines)


def rust_opt(v):
    return "None" if v is None else f"Some({v})"


FIRMWARE_MAIN = os.path.join(ROOT, "firmware", "src", "main.rs")
FLOAT = re.compile(r"-?(?:\d+\.\d*(?:[eE][-+]?\d+)?|\d+[eE][-+]?\d+)")


def firmware_tolerance(path=FIRMWARE_MAIN, name="TOLERANCE"):
    """The firmware's bound on |score - expected| (`const TOLERANCE: f64 = ...;`), or
    another of its `f64` constants."""
    with open(path) as fh:
        found = re.findall(rf"const {name}: f64 = ([0-9.eE+-]+);", fh.read())
    if len(found) != 1:
        raise ValueError(f"{path}: expected one `const {name}: f64`, found {len(found)}")
    return float(found[0])


def differences(committed, fresh, tolerance):
    """Where two renderings differ beyond `tolerance` (floats) or at all (other text):
    a list of messages, empty when they agree."""
    a_text, b_text = FLOAT.split(committed), FLOAT.split(fresh)
    a_nums, b_nums = FLOAT.findall(committed), FLOAT.findall(fresh)
    if a_text != b_text or len(a_nums) != len(b_nums):
        for n, (x, y) in enumerate(zip(committed.splitlines(), fresh.splitlines()), 1):
            if FLOAT.sub("#", x) != FLOAT.sub("#", y):
                return [f"line {n} differs beyond its numbers: {x.strip()!r} vs {y.strip()!r}"]
        return ["the texts differ in length or in their numbers' places"]
    out = []
    for x, y in zip(a_nums, b_nums):
        if abs(float(x) - float(y)) > tolerance:
            out.append(f"{x} vs {y} (|difference| {abs(float(x) - float(y)):.3e} > {tolerance:.1e})")
    return out


def self_test():
    """The comparison itself: a last-ulp change passes, a real change or a text change fails."""
    base = "scores: [0.31833455845905556, 0.3314334775583502], argmax: Some(2), crc: 0x9756a697"
    ulp = base.replace("0.31833455845905556", repr(math.nextafter(0.31833455845905556, 1.0)))
    assert differences(base, ulp, 1e-9) == [], "a one-ulp change must pass"
    assert differences(base, base.replace("0.3314334775583502", "0.3314344775583502"), 1e-9)
    assert differences(base, base.replace("Some(2)", "Some(1)"), 1e-9)
    assert differences(base, base.replace("0x9756a697", "0x9756a698"), 1e-9)
    assert differences(base, base + ", 1.0", 1e-9)


def main(argv):
    check = "--check" in argv
    args = [a for a in argv if a != "--check"]
    table_path = args[0] if len(args) > 0 else DEFAULT_TABLE
    out_path = args[1] if len(args) > 1 else DEFAULT_OUT
    with open(table_path, "rb") as fh:
        table = decode(fh.read())
    with open(SMALL_OPEN, "rb") as fh:
        small = decode(fh.read())
    source = os.path.relpath(os.path.abspath(table_path), ROOT)
    text = render(table, source, small, os.path.relpath(SMALL_OPEN, ROOT))
    if check:
        self_test()
        tolerance = firmware_tolerance() / 1000
        with open(out_path) as fh:
            bad = differences(fh.read(), text, tolerance)
        if bad:
            for line in bad[:10]:
                print(f"  {line}", file=sys.stderr)
            print(f"{out_path} is out of date ({len(bad)} differences): run "
                  "python3 tools/firmware_expected.py", file=sys.stderr)
            return 1
        print(f"{out_path} is up to date (floats within {tolerance:.0e}, the firmware's "
              "tolerance / 1000)")
        return 0
    with open(out_path, "w") as fh:
        fh.write(text)
    print(f"wrote {out_path}: {text.count('    Case {')} cases (both tables, and the "
          f"quantized ones), {text.count('    ErrorCase {')} error cases")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
