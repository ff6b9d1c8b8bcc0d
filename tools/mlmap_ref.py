#!/usr/bin/env python3
"""An independent numpy implementation of mlmap's fit, table format and layer.

It shares no code with the Rust crate: it is written from DESIGN.md and docs/FORMAT.md,
so agreement between the two is evidence for both. Used to write golden values
(tests/golden/) and to cross-check tables written by `mlmap fit`.

    python3 tools/mlmap_ref.py fit examples/data/train.csv OUT.mlmap   # linspace, 22/17 bins
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


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "fit":
        classes, lml, lmap = fit(sys.argv[2])
        with open(sys.argv[3], "wb") as fh:
            fh.write(encode(classes, lml, lmap))
    else:
        print(__doc__)
        sys.exit(2)


if __name__ == "__main__":
    main()
