#!/usr/bin/env python3
"""A seeded synthetic KITTI-like LiDAR frame, for `mlmap lidar-maps` (docs/LIDAR.md).

    python3 examples/lidar_frame.py DIR [--seed 1]
    python3 examples/lidar_frame.py --pictures MAPS_DIR OUT_PREFIX

The first form writes DIR/velodyne.bin (x, y, z, reflectance as little-endian float32),
DIR/calib.txt (KITTI's keys, with values close to KITTI's left colour camera) and
DIR/label.txt (the car and the pedestrian, KITTI label format). The scene is ray-cast
from a 64-beam spinning LiDAR 1.73 m above a flat road (elevations +2 to -24.8 degrees,
1920 azimuth steps, returns up to 120 m, 1.5 cm range noise): the road, two building
facades with a side street, a parked car and a pedestrian. About 120 000 points.

The second form reads MAPS_DIR/rav.npy and rev.npy (written by `mlmap lidar-maps`) and
writes OUT_PREFIX_rav.png and OUT_PREFIX_rev.png: 8-bit pictures with the scaling of
DESIGN section 9.4 (range up to 80 m, brighter is nearer; reflectance 0 to 1).
"""
import argparse
import os
import struct
import sys
import zlib

import numpy as np

HEIGHT = 1.73  # sensor above the road (m)
CALIB = """P0: 7.215e+02 0 6.096e+02 0 0 7.215e+02 1.729e+02 0 0 0 1 0
P1: 7.215e+02 0 6.096e+02 -3.875e+02 0 7.215e+02 1.729e+02 0 0 0 1 0
P2: 7.215e+02 0 6.096e+02 4.486e+01 0 7.215e+02 1.729e+02 2.164e-01 0 0 1 2.746e-03
P3: 7.215e+02 0 6.096e+02 -3.395e+02 0 7.215e+02 1.729e+02 2.199e+00 0 0 1 2.730e-03
R0_rect: 9.9992e-01 9.8378e-03 -7.4451e-03 -9.8698e-03 9.9994e-01 -4.2785e-03 7.4028e-03 4.3516e-03 9.9996e-01
Tr_velo_to_cam: 7.5337e-03 -9.9997e-01 -6.1660e-04 -4.0698e-03 1.4802e-02 7.2807e-04 -9.9989e-01 -7.6316e-02 9.9986e-01 7.5238e-03 1.4808e-02 -2.7178e-01
Tr_imu_to_velo: 1 0 0 -8.086e-01 0 1 0 3.196e-01 0 0 1 -7.997e-01
"""

# Axis-aligned boxes in the LiDAR frame: (name, min corner, max corner, reflectance).
CAR = ("Car", (9.0, -3.9, -HEIGHT), (13.2, -2.1, -0.25), 0.55)
PEDESTRIAN = ("Pedestrian", (6.6, 1.9, -HEIGHT), (7.1, 2.5, 0.02), 0.3)


def ray_box(d, lo, hi):
    """Distance along unit rays d (n x 3) from the origin to a box, inf on a miss."""
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = np.array(lo)[None, :] / d
        t2 = np.array(hi)[None, :] / d
    tmin = np.nanmax(np.minimum(t1, t2), axis=1)
    tmax = np.nanmin(np.maximum(t1, t2), axis=1)
    return np.where((tmax >= tmin) & (tmin > 0), tmin, np.inf)


def scan(seed):
    rng = np.random.default_rng(seed)
    elev = np.radians(np.linspace(2.0, -24.8, 64))
    azim = np.radians(np.arange(1920) * 360.0 / 1920)
    el, az = np.meshgrid(elev, azim, indexing="ij")
    d = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], -1).reshape(-1, 3)
    t = np.full(len(d), np.inf)
    refl = np.zeros(len(d))
    with np.errstate(divide="ignore", invalid="ignore"):
        ground = np.where(d[:, 2] < 0, -HEIGHT / d[:, 2], np.inf)
        # Facades at y = +9 m (a side street from x = 25 to 35 m) and y = -11 m, 8 m high.
        left = np.where(d[:, 1] > 0, 9.0 / d[:, 1], np.inf)
        right = np.where(d[:, 1] < 0, -11.0 / d[:, 1], np.inf)
    for tt, gap in ((left, True), (right, False)):
        finite = np.isfinite(tt)
        hit = d * np.where(finite, tt, 0.0)[:, None]
        ok = finite & (hit[:, 2] <= 8.0 - HEIGHT) & (hit[:, 2] >= -HEIGHT)
        if gap:
            ok &= ~((hit[:, 0] > 25.0) & (hit[:, 0] < 35.0))
        tt[~ok] = np.inf
    surfaces = [
        (ground, lambda n: 0.12 + 0.05 * rng.random(n)),
        (left, lambda n: 0.35 + 0.1 * rng.random(n)),
        (right, lambda n: 0.28 + 0.1 * rng.random(n)),
        (ray_box(d, CAR[1], CAR[2]), lambda n: CAR[3] + 0.2 * rng.random(n)),
        (ray_box(d, PEDESTRIAN[1], PEDESTRIAN[2]), lambda n: PEDESTRIAN[3] + 0.1 * rng.random(n)),
    ]
    for ts, r in surfaces:
        closer = ts < t
        t[closer] = ts[closer]
        refl[closer] = r(int(closer.sum()))
    keep = t < 120.0
    t = t[keep] + rng.normal(0.0, 0.015, int(keep.sum()))
    pts = d[keep] * t[:, None]
    return np.column_stack([pts, np.clip(refl[keep], 0, 1)]).astype("<f4")


def label_lines():
    """KITTI label lines of the two boxes, their 2-D boxes from the projected corners."""
    vals = {k: np.array(v.split(), dtype=float)
            for k, v in (ln.split(":", 1) for ln in CALIB.strip().splitlines())}
    p2 = vals["P2"].reshape(3, 4)
    r = np.eye(4)
    r[:3, :3] = vals["R0_rect"].reshape(3, 3)
    tr = np.eye(4)
    tr[:3, :] = vals["Tr_velo_to_cam"].reshape(3, 4)
    lines = []
    for name, lo, hi, _ in (CAR, PEDESTRIAN):
        corners = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                            for z in (lo[2], hi[2])])
        cam = (r @ tr @ corners.T)
        uvw = p2 @ cam
        u, v = uvw[0] / uvw[2], uvw[1] / uvw[2]
        box = [max(u.min(), 0), max(v.min(), 0), min(u.max(), 1241), min(v.max(), 374)]
        size = np.array(hi) - np.array(lo)
        bottom = cam[:3, :].mean(axis=1)
        lines.append(
            f"{name} 0.00 0 0.00 {box[0]:.2f} {box[1]:.2f} {box[2]:.2f} {box[3]:.2f} "
            f"{size[2]:.2f} {size[1]:.2f} {size[0]:.2f} {bottom[0]:.2f} {bottom[1]:.2f} "
            f"{bottom[2]:.2f} -1.57")
    return "\n".join(lines) + "\n"


def png8(path, img):
    """An 8-bit grayscale PNG (no dependency beyond zlib)."""
    h, w = img.shape
    raw = b"".join(b"\x00" + img[y].astype(np.uint8).tobytes() for y in range(h))

    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def pictures(maps_dir, prefix):
    rav = np.load(os.path.join(maps_dir, "rav.npy")).astype(np.float64)
    rev = np.load(os.path.join(maps_dir, "rev.npy")).astype(np.float64)
    # DESIGN 9.4's 8-bit range scaling, inverted for the picture (near is bright; no data black).
    r8 = np.floor(255 * np.minimum(rav, 80.0) / 80.0 + 0.5)
    png8(prefix + "_rav.png", np.where(rav > 0, 255 - r8, 0))
    png8(prefix + "_rev.png", np.floor(255 * np.clip(rev, 0, 1) + 0.5))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", nargs="?")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--pictures", nargs=2, metavar=("MAPS_DIR", "OUT_PREFIX"))
    a = ap.parse_args()
    if a.pictures:
        pictures(*a.pictures)
        return
    if not a.dir:
        sys.exit("give an output directory")
    os.makedirs(a.dir, exist_ok=True)
    pts = scan(a.seed)
    open(os.path.join(a.dir, "velodyne.bin"), "wb").write(pts.tobytes())
    open(os.path.join(a.dir, "calib.txt"), "w").write(CALIB)
    open(os.path.join(a.dir, "label.txt"), "w").write(label_lines())
    print(f"wrote {a.dir}/velodyne.bin ({len(pts)} points), calib.txt, label.txt")


if __name__ == "__main__":
    main()
