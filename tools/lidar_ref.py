#!/usr/bin/env python3
"""An independent numpy implementation of docs/DESIGN.md section 9: the LiDAR range-view
(RaV) and reflectance-view (ReV) maps, from a KITTI velodyne scan and calibration file.

    python3 tools/lidar_ref.py --velodyne F.bin --calib F.txt [--width 1242 --height 375]
        [--mask 13] [--r0 gs-mean|nearest] --output DIR [--repeat N]

writes DIR/rav.npy, DIR/rev.npy (the dense maps, float32, height x width) and
DIR/rav_sparse.npy, DIR/rev_sparse.npy (the projection). Everything is computed in
float64 and vectorised over the image: the upsampling loops over the c x c offsets of
the mask, never over pixels. `--repeat N` times the whole computation N times and prints
the best time of the projection and upsampling (files read once, outside the
timing), for the speed comparison of docs/LIDAR.md.

Written from the text of the design, not from the Rust code; the tests compare the two.
"""
import argparse
import os
import sys
import time

import numpy as np


def read_scan(path):
    raw = open(path, "rb").read()
    if len(raw) % 16:
        raise ValueError(f"{path}: {len(raw)} bytes is not a whole number of 16-byte points")
    pts = np.frombuffer(raw, dtype="<f4").reshape(-1, 4)
    bad = ~np.all(np.isfinite(pts) & (np.abs(pts) <= 1e18), axis=1)
    if bad.any():
        raise ValueError(f"{path}: point {int(np.argmax(bad))} is not finite")
    return pts


def read_calib(path):
    want = {"P2": 12, "R0_rect": 9, "Tr_velo_to_cam": 12}
    got = {}
    for line in open(path, encoding="utf-8"):
        if ":" not in line:
            continue
        key, vals = line.split(":", 1)
        key = key.strip()
        if key in want:
            v = [float(t) for t in vals.split()]
            if len(v) != want[key] or key in got:
                raise ValueError(f"{path}: bad {key}")
            got[key] = v
    missing = [k for k in want if k not in got]
    if missing:
        raise ValueError(f"{path}: missing {missing}")
    p2 = np.array(got["P2"]).reshape(3, 4)
    r = np.zeros((4, 4))
    r[:3, :3] = np.array(got["R0_rect"]).reshape(3, 3)
    r[3, 3] = 1.0
    t = np.zeros((4, 4))
    t[:3, :] = np.array(got["Tr_velo_to_cam"]).reshape(3, 4)
    t[3, 3] = 1.0
    return p2, r, t


def product(a, b):
    """a @ b with each entry summed over the inner index in increasing order."""
    out = np.zeros((a.shape[0], b.shape[1]))
    for i in range(a.shape[0]):
        for j in range(b.shape[1]):
            s = 0.0
            for k in range(a.shape[1]):
                s += a[i, k] * b[k, j]
            out[i, j] = s
    return out


def project(pts, p2, r, t, width, height):
    """The sparse maps of section 9.2 (float32, 0 where no point falls)."""
    m = product(product(p2, r), t)
    x, y, z = (pts[:, i].astype(np.float64) for i in range(3))
    c = [0.0 + m[i, 0] * x + m[i, 1] * y + m[i, 2] * z + m[i, 3] for i in range(3)]
    a, b, w = c
    front = w > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        col = np.floor(a / w + 0.5)
        row = np.floor(b / w + 0.5)
    rho = np.sqrt(x * x + y * y + z * z).astype(np.float32)
    keep = front & (col >= 0) & (col < width) & (row >= 0) & (row < height) & (rho > 0)
    idx = np.nonzero(keep)[0]
    pix = (row[idx] * width + col[idx]).astype(np.int64)
    # Nearest first, then file order: the first entry of each pixel wins.
    order = np.lexsort((idx, rho[idx], pix))
    pix, idx = pix[order], idx[order]
    first = np.ones(len(pix), dtype=bool)
    first[1:] = pix[1:] != pix[:-1]
    rav = np.zeros(width * height, dtype=np.float32)
    rev = np.zeros(width * height, dtype=np.float32)
    rav[pix[first]] = rho[idx[first]]
    rev[pix[first]] = pts[idx[first], 3]
    return rav.reshape(height, width), rev.reshape(height, width), int(keep.sum())


def upsample(sparse_r, sparse_f, mask, r0_mode="gs-mean"):
    """The dense maps of section 9.3, in float64, vectorised over the image."""
    hgt, wid = sparse_r.shape
    h = mask // 2
    occ = sparse_r > 0
    pad = lambda a: np.pad(a, h)  # noqa: E731  (zeros outside: never occupied)
    occ_p = pad(occ)
    vals = [pad(sparse_r.astype(np.float64)), pad(sparse_f.astype(np.float64))]
    offsets = [(dy, dx) for dy in range(-h, h + 1) for dx in range(-h, h + 1)]

    def shifted(a, dy, dx):
        return a[h + dy : h + dy + hgt, h + dx : h + dx + wid]

    count = np.zeros((hgt, wid), dtype=np.int64)
    sg = np.zeros((hgt, wid))
    sgv = [np.zeros((hgt, wid)), np.zeros((hgt, wid))]
    best_d2 = np.full((hgt, wid), np.iinfo(np.int64).max)
    nearest = [np.zeros((hgt, wid)), np.zeros((hgt, wid))]
    for dy, dx in offsets:
        o = shifted(occ_p, dy, dx)
        g = 1.0 / (1.0 + np.sqrt(dx * dx + dy * dy))
        count += o
        sg += g * o
        d2 = dx * dx + dy * dy
        closer = o & (d2 < best_d2)
        best_d2 = np.where(closer, d2, best_d2)
        for m in range(2):
            v = shifted(vals[m], dy, dx)
            sgv[m] += g * v * o
            nearest[m] = np.where(closer, v, nearest[m])
    out = []
    for m in range(2):
        with np.errstate(divide="ignore", invalid="ignore"):
            r0 = sgv[m] / sg if r0_mode == "gs-mean" else nearest[m]
        sw = np.zeros((hgt, wid))
        swv = np.zeros((hgt, wid))
        for dy, dx in offsets:
            o = shifted(occ_p, dy, dx)
            v = shifted(vals[m], dy, dx)
            wgt = o * (1.0 / (1.0 + np.sqrt(dx * dx + dy * dy))) / (1.0 + np.abs(r0 - v))
            sw += wgt
            swv += wgt * v
        with np.errstate(divide="ignore", invalid="ignore"):
            dense = np.where(count > 0, swv / sw, 0.0)
        sparse = sparse_r if m == 0 else sparse_f
        dense = np.where(occ, sparse.astype(np.float64), dense)
        out.append(dense)
    return out


def maps(pts, calib, width, height, mask, r0_mode):
    sr, sf, kept = project(pts, *calib, width, height)
    dr, df = upsample(sr, sf, mask, r0_mode)
    return sr, sf, dr, df, len(pts), kept


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--velodyne", required=True)
    ap.add_argument("--calib", required=True)
    ap.add_argument("--width", type=int, default=1242)
    ap.add_argument("--height", type=int, default=375)
    ap.add_argument("--mask", type=int, default=13)
    ap.add_argument("--r0", choices=["gs-mean", "nearest"], default="gs-mean")
    ap.add_argument("--output", required=True)
    ap.add_argument("--repeat", type=int, default=1)
    a = ap.parse_args()
    if a.mask % 2 == 0 or not 1 <= a.mask <= 63:
        sys.exit("--mask must be odd, from 1 to 63")
    pts = read_scan(a.velodyne)
    calib = read_calib(a.calib)
    best = float("inf")
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        sr, sf, dr, df, n, kept = maps(pts, calib, a.width, a.height, a.mask, a.r0)
        best = min(best, time.perf_counter() - t0)
    os.makedirs(a.output, exist_ok=True)
    np.save(os.path.join(a.output, "rav.npy"), dr.astype(np.float32))
    np.save(os.path.join(a.output, "rev.npy"), df.astype(np.float32))
    np.save(os.path.join(a.output, "rav_sparse.npy"), sr)
    np.save(os.path.join(a.output, "rev_sparse.npy"), sf)
    print(f"{n} points, {kept} kept, {int((sr > 0).sum())} pixels; best of {a.repeat}: "
          f"{best * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
