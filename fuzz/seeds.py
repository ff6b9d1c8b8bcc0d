#!/usr/bin/env python3
"""Writes the committed seed corpora under fuzz/corpus/seed_<target>/.

    python3 fuzz/seeds.py

decode:    the shipped table (format version 3: a Bayes head and the open head's
           temperature and epsilon), truncations of it, the same as version 2 and with
           the clamp policy, the small golden Bayes tables (versions 2 and 3), version-3
           tables with the open head's parameters at and beyond their bounds, and small
           version-1 tables of the other shapes the target decodes (written with the
           independent encoder in tools/mlmap_ref.py).
roundtrip: the shipped table's statistics, small tables, and small tables with a Bayes
           head and an open head, in the `arbitrary` layout of the target's `Input`.
quantized: mode 0 (a section): the int8 section of tables/default_q8.mlmap, the whole
           file, and the section truncated; mode 1 (build one): int8 and int16
           quantizations of the shipped table with a few codes.
lidar:     a velodyne scan (first byte even) and calibration files (odd): the golden
           small frame's, truncated, one without Tr_velo_to_cam.
csv:       the example of DESIGN §2, the head of examples/data/test.csv, malformed files.
infer:     detections on the shipped table (rows of examples/data/test.csv, NaN, ±inf,
           subnormals, bin edges, objectness at and beyond its bounds), on the shipped
           table with other open-head parameters, on a small structured table, and on
           structured tables with a Bayes head and an open head, in the `arbitrary`
           layout of the target.

Files named `regression_*` are inputs the fuzzers once failed on; they are kept by hand,
not written here.

The `arbitrary` layout (arbitrary 1.x): integers little-endian; a derived enum reads a
u32 `v` and picks variant `(v * count) >> 32`; `bool` is one byte's low bit; fixed
arrays and struct fields follow in order.
"""
import csv
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "tools"))
import mlmap_ref  # noqa: E402


def write(target, name, data):
    d = os.path.join(HERE, "corpus", f"seed_{target}")
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


# --- the table format ------------------------------------------------------------------


def read_varint(b, i):
    n, shift = 0, 0
    while True:
        byte = b[i]
        i += 1
        n |= (byte & 0x7F) << shift
        shift += 7
        if byte & 0x80 == 0:
            return n, i


def parse_table(b):
    """The fields of a table file of format version 1, 2 or 3, as floats and ints (no
    validation beyond the layout): a dict with the arguments of `mlmap_ref.encode`
    (classes, lambda_ml, lambda_map, edge_mode, upper_tail, bayes, open_)."""
    assert b[:4] == b"MLMP"
    i = 4
    version, i = read_varint(b, i)
    assert version in (1, 2, 3), version
    k, i = read_varint(b, i)
    bml, i = read_varint(b, i)
    bmap, i = read_varint(b, i)
    if version >= 2:  # the Bayes head's bins and categories
        bayes_bins, i = read_varint(b, i)
        bayes_categories, i = read_varint(b, i)
    edge_mode, upper_tail = b[i], b[i + 1]
    lambda_ml, lambda_map = struct.unpack_from("<ff", b, i + 2)
    i += 10
    n, i = read_varint(b, i)
    assert n == k
    f = lambda j: struct.unpack_from("<f", b, j)[0]  # noqa: E731
    classes = []
    for _ in range(k):
        ln, i = read_varint(b, i)
        name = b[i : i + ln].decode()
        i += ln
        rows, i = read_varint(b, i)
        c = {"name": name, "rows": rows, "mean": f(i), "var": f(i + 4)}
        c["ml_lo"], c["ml_hi"] = f(i + 8), f(i + 12)
        i += 16
        nb, i = read_varint(b, i)
        c["ml_freqs"] = [f(i + 4 * j) for j in range(nb)]
        i += 4 * nb
        c["map_lo"], c["map_hi"] = f(i), f(i + 4)
        i += 8
        nb, i = read_varint(b, i)
        c["map_freqs"] = [f(i + 4 * j) for j in range(nb)]
        i += 4 * nb
        classes.append(c)
    bayes, open_ = None, None
    if version >= 2:
        # The Bayes head: lambda, rows per category, a range per logit, the log-terms
        # (stored logit-major (j, b, c); held category-major (c, j, b) as
        # mlmap_ref.encode takes them).
        lam = f(i)
        i += 4
        n, i = read_varint(b, i)
        rows = []
        for _ in range(n):
            r, i = read_varint(b, i)
            rows.append(r)
        n, i = read_varint(b, i)
        ranges = [(f(i + 8 * j), f(i + 8 * j + 4)) for j in range(n)]
        i += 8 * n
        n, i = read_varint(b, i)
        stored = [f(i + 4 * j) for j in range(n)]
        i += 4 * n
        assert len(rows) == bayes_categories and len(ranges) == k
        assert n == bayes_categories * k * bayes_bins
        terms = [stored[(j * bayes_bins + bb) * bayes_categories + c]
                 for c in range(bayes_categories) for j in range(k) for bb in range(bayes_bins)]
        bayes = {"lambda": lam, "rows": rows, "ranges": ranges, "terms": terms}
    if version == 3:  # the open head: temperature, epsilon
        open_ = (f(i), f(i + 4))
        i += 8
    assert i + 4 == len(b), "trailing bytes"
    t = dict(classes=classes, lambda_ml=lambda_ml, lambda_map=lambda_map,
             edge_mode=edge_mode, upper_tail=upper_tail, bayes=bayes, open_=open_)
    # The independent encoder writes the very same bytes back.
    assert mlmap_ref.encode(**t) == b, "re-encoding gives other bytes"
    return t


def small_class(name, mean, bml, bmap):
    return {
        "name": name,
        "rows": 100,
        "mean": mean,
        "var": 1.5,
        "ml_lo": mean - 2.0,
        "ml_hi": mean + 2.0,
        "ml_freqs": [1.0 / bml] * bml,
        "map_lo": mean - 3.0,
        "map_hi": mean + 1.0,
        "map_freqs": [1.0] + [0.0] * (bmap - 1),
    }


# --- the arbitrary layout -----------------------------------------------------------------


def u8(v):
    return struct.pack("<B", v)


def i8(v):
    return struct.pack("<b", v)


def u16(v):
    return struct.pack("<H", v)


def i16(v):
    return struct.pack("<h", v)


def u32(v):
    return struct.pack("<I", v)


def u64(v):
    return struct.pack("<Q", v)


def bits(x):
    return struct.unpack("<I", struct.pack("<f", x))[0]


def tag(i, count):
    """The u32 a derived enum with `count` variants reads as variant `i`."""
    v = -(-(i << 32) // count)
    assert (v * count) >> 32 == i
    return u32(v)


def real_bits(x):
    return tag(2, 3) + u32(bits(x))


def real_small(v):
    return tag(0, 3) + i16(v)


def arb_hist(lo, hi, freqs):
    span = struct.unpack("<f", struct.pack("<f", hi - lo))[0]
    return real_bits(lo) + real_bits(span) + tag(2, 3) + b"".join(u32(bits(v)) for v in freqs)


def arb_class(c, known_index):
    return (
        tag(0, 2)
        + u8(known_index)
        + u64(c["rows"])
        + real_bits(c["mean"])
        + real_bits(c["var"])
        + arb_hist(c["ml_lo"], c["ml_hi"], c["ml_freqs"])
        + arb_hist(c["map_lo"], c["map_hi"], c["map_freqs"])
    )


def arb_table(classes, lambda_ml, lambda_map, matlab=0, clamp=0):
    out = real_bits(lambda_ml) + real_bits(lambda_map) + u8(matlab) + u8(clamp)
    for i, c in enumerate(classes):
        out += arb_class(c, i)  # names "car", "cyclist", "pedestrian", "truck", ...
    return out


def logit_bits(x):
    return tag(0, 4) + u32(bits(x))


def logit_raw(b):
    return tag(0, 4) + u32(b)


def logit_edge(map_head, k, ulps):
    return tag(2, 4) + u8(map_head) + u16(k) + i8(ulps)


def logit_bayes_edge(k, ulps):
    return tag(3, 4) + u16(k) + i8(ulps)


def os_bits(x):
    return tag(0, 4) + u32(bits(x))


def os_raw(b):
    return tag(0, 4) + u32(b)


def os_special(i):
    return tag(3, 4) + u8(i)


def arb_bayes(lam, ranges, rows, freqs):
    """An `ArbBayes<K, BB, C>`: lambda as bits, each range as (lo, span) bits, rows (the
    target adds 1), per category and logit integer weights proportional to `freqs`
    (freqs[c][j][b]), no hostile term."""
    out = tag(1, 2) + u32(bits(lam))
    for lo, hi in ranges:
        out += real_bits(lo) + real_bits(hi - lo)
    out += b"".join(u32(n - 1) for n in rows)
    for per_logit in freqs:
        for hist in per_logit:
            out += b"".join(u16(round(1000 * h)) for h in hist)
    return out + u8(0)


def arb_open(temperature, epsilon, raise_=256):
    """An `ArbOpen`: temperature and epsilon as bits, and the raise of the second
    epsilon (`epsilon * 2^(raise / 256)`)."""
    return tag(3, 4) + u32(bits(temperature)) + tag(3, 4) + u32(bits(epsilon)) + u16(raise_)


NAN, NEG_NAN, INF, NEG_INF = 0x7FC00000, 0xFFC00001, 0x7F800000, 0xFF800000
SUB_MIN, SUB_MAX, NEG_SUB = 0x00000001, 0x007FFFFF, 0x80000001


def main():
    shipped = open(os.path.join(ROOT, "tables", "default.mlmap"), "rb").read()
    table = parse_table(shipped)
    assert table["open_"] is not None, "the shipped table is format version 3"
    classes, lml, lmap = table["classes"], table["lambda_ml"], table["lambda_map"]
    golden = os.path.join(ROOT, "tests", "golden", "layer")

    # decode
    write("decode", "shipped.mlmap", shipped)
    for n in (4, 8, 24, len(shipped) // 2, len(shipped) - 9, len(shipped) - 5,
              len(shipped) - 1):
        write("decode", f"shipped_first_{n}.bin", shipped[:n])
    v2 = dict(table, open_=None)
    write("decode", "shipped_v2.mlmap", mlmap_ref.encode(**v2))
    write("decode", "shipped_clamp.mlmap", mlmap_ref.encode(**dict(table, upper_tail=1)))
    for name in ("small_bayes", "small_bayes_nobg", "small_open", "small_open_nobg"):
        with open(os.path.join(golden, name + ".mlmap"), "rb") as fh:
            data = fh.read()
        parse_table(data)
        write("decode", name + ".mlmap", data)
    # The open head's parameters at their bounds, and just beyond them (refused).
    sub = struct.unpack("<f", u32(0x00400000))[0]
    for name, params in (
        ("t_min_eps_0", (1e-6, 0.0)),
        ("t_max_eps_max", (1e6, 1e30)),
        ("t_1_eps_min_normal", (1.0, 2.0 ** -126)),
        ("t_0", (0.0, 0.0)),
        ("t_above_max", (struct.unpack("<f", u32(bits(1e6) + 1))[0], 0.0)),
        ("eps_negative_zero", (1.0, -0.0)),
        ("eps_subnormal", (1.0, sub)),
        ("eps_above_max", (1.0, struct.unpack("<f", u32(bits(1e30) + 1))[0])),
        ("eps_inf", (1.0, float("inf"))),
        ("t_nan", (float("nan"), 0.05)),
    ):
        data = mlmap_ref.encode(mlmap_ref.SMALL, mlmap_ref.SMALL_LAMBDA_ML,
                                mlmap_ref.SMALL_LAMBDA_MAP, bayes=mlmap_ref.SMALL_BAYES,
                                open_=params)
        write("decode", f"small_open_{name}.mlmap", data)
    small = [small_class("car", 1.0, 4, 3), small_class("cyclist", -1.0, 4, 3)]
    write("decode", "k2_b4_b3.mlmap", mlmap_ref.encode(small, 0.0055, 0.00012))
    write("decode", "k2_b4_b3_clamp_matlab.mlmap", mlmap_ref.encode(small, 0.5, 1e-8, 1, 1))
    one = [small_class("car", 1.0, 1, 1), small_class("x", 0.0, 1, 1)]
    write("decode", "k2_b1_b1.mlmap", mlmap_ref.encode(one, 0.01, 0.01))
    five = [small_class(f"class{i}", float(i), 9, 2) for i in range(5)]
    write("decode", "k5_b9_b2.mlmap", mlmap_ref.encode(five, 1e-3, 1e-3))

    # roundtrip: Input::Shipped, Small, OneBin (variants 0, 1, 2 of 6), then Open and
    # OpenNoBackground (4 and 5): a Bayes head and an open head.
    write("roundtrip", "shipped.bin", tag(0, 6) + arb_table(classes, lml, lmap))
    write("roundtrip", "small.bin", tag(1, 6) + arb_table(small, 0.0055, 0.00012, 1, 1))
    write("roundtrip", "one_bin.bin", tag(2, 6) + arb_table(one, 0.01, 0.01))
    freqs = mlmap_ref.SMALL_BAYES_FREQS
    small_bayes = arb_bayes(0.01, mlmap_ref.SMALL_BAYES_RANGES, [40, 20, 20, 20],
                            [freqs[c] for c in freqs])
    small3 = arb_table(mlmap_ref.SMALL, mlmap_ref.SMALL_LAMBDA_ML, mlmap_ref.SMALL_LAMBDA_MAP)
    write("roundtrip", "small_open.bin", tag(4, 6) + small3 + small_bayes + arb_open(1.75, 0.05))
    write("roundtrip", "small_open_eps_0.bin",
          tag(4, 6) + small3 + small_bayes + arb_open(0.8, 0.0))
    two = [small_class("car", 1.0, 3, 1), small_class("x", 0.0, 3, 1)]
    two_bayes = arb_bayes(0.001, [(-1.0, 3.0), (-2.0, 2.0)], [30, 10],
                          [[[0.25, 0.75], [0.5, 0.5]], [[1.0, 0.0], [0.1, 0.9]]])
    write("roundtrip", "open_no_background.bin",
          tag(5, 6) + arb_table(two, 0.01, 0.01) + two_bayes + arb_open(2.5, 1e-3))

    # infer: choice 0 is the shipped table; then [3 x Logit, Objectness] per detection
    rows = list(csv.DictReader(open(os.path.join(ROOT, "examples", "data", "test.csv"))))
    names = [c["name"] for c in classes]
    # (the target reads at most MAX_DETECTIONS = 8 detections per input)
    for j in range(0, 40, 8):
        det = b""
        for r in rows[j : j + 8]:
            det += b"".join(logit_bits(float(r[n])) for n in names)
            det += os_bits(float(r["objectness"]))
        write("infer", f"test_rows_{j}.bin", u8(0) + det)
    specials = [NAN, NEG_NAN, INF, NEG_INF, SUB_MIN, SUB_MAX, NEG_SUB, 0, 0x80000000, 0x7F7FFFFF]
    for j, s in enumerate(specials):
        det = logit_raw(s) + logit_bits(0.5) + logit_bits(-0.5) + os_bits(0.9)
        det += logit_bits(3.0) + logit_raw(s) + logit_raw(s) + os_special(j)
        det += logit_bits(-1.0) + logit_bits(-4.0) + logit_raw(s) + os_raw(s)
        write("infer", f"special_logit_{s:08x}.bin", u8(0) + det)
    det = b""
    for o in (NAN, INF, 0x3F800001, 0xBF800000, SUB_MIN, 0, 0x80000000):
        det += logit_bits(4.0) + logit_bits(-2.0) + logit_bits(-1.0) + os_raw(o)
    write("infer", "special_objectness.bin", u8(0) + det)
    for k in range(0, 23, 2):
        det = b""
        for kk in (k, k + 1):
            for ulps in (-1, 0, 1):
                det += logit_edge(0, kk, ulps) + logit_edge(1, kk, ulps)
                det += logit_edge(0, kk, -ulps) + os_special(2)
        write("infer", f"edges_{k}.bin", u8(0) + det)
    far = [(100.0, 100.0, 100.0), (-100.0, -100.0, -100.0), (1e30, -1e30, 50.0)]
    det = b"".join(b"".join(logit_bits(x) for x in xs) + os_bits(0.75) for xs in far)
    write("infer", "out_of_support.bin", u8(0) + det)
    # choice 2: a structured Table<2, 4, 3>, then [2 x Logit, Objectness] per detection
    det = b""
    for xs in ((1.0, -1.0), (-0.5, 0.25), (50.0, -50.0), (3.0, 3.0)):
        det += b"".join(logit_bits(x) for x in xs) + os_bits(0.5)
    write("infer", "small_table.bin", u8(2) + arb_table(small, 0.0055, 0.00012) + det)
    # choice 7: the shipped table with another open head, then detections (test rows,
    # Bayes edges, far outside, where the unknown category weighs most)
    for name, params in (("t_1_75_eps_0_05", (1.75, 0.05)), ("t_0_5_eps_1e3", (0.5, 1e3)),
                         ("t_1e6_eps_max", (1e6, 1e30)), ("t_1e-6_eps_min", (1e-6, 2.0 ** -126))):
        det = b""
        for r in rows[:4]:
            det += b"".join(logit_bits(float(r[n])) for n in names)
            det += os_bits(float(r["objectness"]))
        det += b"".join(logit_bayes_edge(kk, 0) for kk in (0, 11, 22)) + os_special(2)
        det += b"".join(logit_bits(x) for x in (1e3, -1e3, 50.0)) + os_bits(0.75)
        det += b"".join(logit_raw(v) for v in (INF, INF, NEG_INF)) + os_bits(1.0)
        write("infer", f"shipped_open_{name}.bin", u8(7) + arb_open(*params) + det)
    # choice 6: a structured Table<2, 4, 3> with a Bayes head of 1 bin and 3 categories
    # (background) and an open head, then [2 x Logit, Objectness] per detection
    one_bin = arb_bayes(0.05, [(-2.0, 2.0), (-2.0, 2.0)], [50, 30, 20],
                        [[[1.0], [1.0]], [[1.0], [1.0]], [[1.0], [1.0]]])
    det = b""
    for xs in ((1.0, -1.0), (-0.5, 0.25), (50.0, -50.0), (3.0, 3.0)):
        det += b"".join(logit_bits(x) for x in xs) + os_bits(0.5)
    write("infer", "small_open_table.bin",
          u8(6) + arb_table(small, 0.0055, 0.00012) + one_bin + arb_open(1.3, 0.2) + det)

    # quantized
    with open(os.path.join(ROOT, "tables", "default_q8.mlmap"), "rb") as f:
        q8 = f.read()
    n = struct.unpack("<I", q8[-8:-4])[0]
    write("quantized", "section_q8.bin", u8(0) + q8[-n:])
    write("quantized", "file_q8.bin", u8(0) + q8)
    write("quantized", "section_q8_head.bin", u8(0) + q8[-n:][:200] + q8[-8:])
    codes = b"".join(struct.pack("<hhhB", a, b, c, o)
                     for a, b, c, o in ((50, -20, 10, 255), (-128, 127, 0, 128), (300, -300, 5, 7)))
    for name, width, scale, zp in (("build_q8.bin", 0, 0.08, 0), ("build_q16.bin", 1, 0.001, -300)):
        params = u8(width) + struct.pack("<fff", scale, scale * 0.7, scale * 1.3) + struct.pack("<hhh", zp, 3, -7)
        write("quantized", name, u8(1) + params + codes)

    # monitor: the shipped example's section, then detections (3 f32 logits, objectness byte)
    with open(os.path.join(ROOT, "tests", "golden", "monitor_small.mlmap"), "rb") as f:
        mon = f.read()
    m = struct.unpack("<I", mon[-8:-4])[0]
    dets = b"".join(struct.pack("<fffB", a, b, c, o) for a, b, c, o in
                    ((1.0, -2.0, 0.5, 200), (1e6, -1e6, 0.0, 255), (float("inf"), 0.0, -3.0, 0),
                     (0.25, 0.25, 0.25, 128)) * 30)
    write("monitor", "section_and_detections.bin", struct.pack("<H", m) + mon[-m:] + dets)
    write("monitor", "section_header.bin", struct.pack("<H", 60) + mon[-m:][:52] + mon[-8:] + dets[:39])
    # the same target reads a conformal section (the open head's, alpha 0.1)
    with open(os.path.join(ROOT, "tests", "golden", "conformal_small.mlmap"), "rb") as f:
        conf = f.read()
    c = struct.unpack("<I", conf[-8:-4])[0]
    write("monitor", "conformal_and_detections.bin", struct.pack("<H", c) + conf[-c:] + dets)

    # csv (the target is built once the reader lands; see fuzz_targets/csv.rs)
    with open(os.path.join(ROOT, "examples", "data", "test.csv"), "rb") as f:
        write("csv", "test_head.csv", b"".join(f.readlines()[:20]))
    write(
        "csv",
        "design_example.csv",
        b"id,label,objectness,car,cyclist,pedestrian\n"
        b"17,car,0.93,4.1,-2.3,-1.7\n18,background,0.55,1.2,0.3,-0.4\n",
    )
    write("csv", "malformed.csv", b"label,car,cyclist\ncar,1e3,-inf\n,NaN,0\ncyclist,1.5\n")
    write("csv", "bad_values.csv", b"label,objectness,car,cyclist\ncar,1.5,1,2\ntruck,0.5,1,2\n")

    # lidar: byte 0 even, a velodyne scan (the golden frame's first 64 points, and a
    # truncated one); odd, a calibration file (the golden one, and one missing a matrix)
    golden = os.path.join(ROOT, "tests", "golden", "lidar")
    with open(os.path.join(golden, "small.bin"), "rb") as f:
        scan = f.read()
    with open(os.path.join(golden, "small_calib.txt"), "rb") as f:
        calib = f.read()
    write("lidar", "scan_small", b"\x00" + scan[: 16 * 64])
    write("lidar", "scan_truncated", b"\x00" + scan[: 16 * 3 + 7])
    write("lidar", "calib_small", b"\x01" + calib)
    write("lidar", "calib_missing",
          b"\x01P2: 1 0 0 0 0 1 0 0 0 0 1 0\nR0_rect: 1 0 0 0 1 0 0 0 1\n")


if __name__ == "__main__":
    main()
