#!/usr/bin/env python3
"""Writes the golden files of the LiDAR maps (docs/DESIGN.md section 9) into
tests/golden/lidar/, with the independent numpy reference tools/lidar_ref.py:

    python3 tools/lidar_goldens.py          # write
    python3 tools/lidar_goldens.py --check  # fail if a committed file differs

small.bin, small_calib.txt: a seeded 96 x 32 frame (a few hundred points in front of
the camera, some behind it, outside the image, at the origin, and points sharing a
pixel, with equal ranges too). For each case `<name>` (mask, r0 option):
<name>_rav.npy, <name>_rev.npy, and small_rav_sparse.npy, small_rev_sparse.npy.
firmware/src/lidar_expected.rs: a 24 x 12 frame and its expected maps for the
Cortex-M4F run (rounded to 9 significant digits).
"""
import io
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import lidar_ref  # noqa: E402

OUT = os.path.join(ROOT, "tests", "golden", "lidar")
CASES = [("m13", 13, "gs-mean"), ("m5", 5, "gs-mean"), ("m13_nearest", 13, "nearest"),
         ("m1", 1, "gs-mean"), ("m63", 63, "gs-mean")]

# A camera looking along the LiDAR's x axis (KITTI's axes: x forward, y left, z up),
# a little rotated and offset, focal length 40 px on a 96 x 32 image.
CALIB = """P0: 1 0 0 0 0 1 0 0 0 0 1 0
P2: 40.0 0.0 48.2 1.5 0.0 40.0 16.3 0.02 0.0 0.0 1.0 0.003
R0_rect: 0.9999 0.0098 -0.0074 -0.0099 0.9999 -0.0043 0.0074 0.0044 1.0
Tr_velo_to_cam: 0.0075 -0.9999 -0.0006 -0.004 0.0148 0.0007 -0.9999 -0.076 0.9999 0.0075 0.0148 -0.27
Tr_imu_to_velo: 1 0 0 0 0 1 0 0 0 0 1 0
"""


def small_scan(seed=7, n=500):
    rng = np.random.default_rng(seed)
    x = rng.uniform(2.0, 40.0, n)
    y = x * rng.uniform(-1.1, 1.1, n)
    z = x * rng.uniform(-0.45, 0.4, n)
    f = rng.uniform(0.0, 1.0, n)
    pts = np.stack([x, y, z, f], axis=1).astype(np.float32)
    extra = [
        [-5.0, 0.0, 0.0, 0.3],     # behind the camera
        [10.0, 50.0, 0.0, 0.3],    # outside the image
        [0.0, 0.0, 0.0, 0.9],      # at the origin: no measurement
        [20.0, 1.0, 0.5, 0.11],    # three on one pixel: the nearest wins ...
        [20.0, 1.0, 0.5, 0.22],    # ... an equal range: the first stays
        [25.0, 1.25, 0.625, 0.33],  # farther, same ray
        [30.0, -3.0, 1.0, 0.44],   # farther first, then nearer on the same ray
        [15.0, -1.5, 0.5, 0.55],
    ]
    return np.concatenate([pts, np.array(extra, dtype=np.float32)])


def outputs(scan_path, calib_path, width, height, cases):
    pts = lidar_ref.read_scan(scan_path)
    p2, r, t = lidar_ref.read_calib(calib_path)
    sr, sf, _ = lidar_ref.project(pts, p2, r, t, width, height)
    files = {"small_rav_sparse.npy": sr, "small_rev_sparse.npy": sf}
    for name, mask, r0 in cases:
        dr, df = lidar_ref.upsample(sr, sf, mask, r0)
        files[f"{name}_rav.npy"] = dr.astype(np.float32)
        files[f"{name}_rev.npy"] = df.astype(np.float32)
    return files


def npy_bytes(a):
    buf = io.BytesIO()
    np.save(buf, a)
    return buf.getvalue()


def firmware_source():
    """A 24 x 12 frame, mask 5, for firmware/src/lidar_expected.rs."""
    rng = np.random.default_rng(11)
    n = 40
    x = rng.uniform(3.0, 30.0, n)
    y = x * rng.uniform(-0.5, 0.5, n)
    z = x * rng.uniform(-0.3, 0.2, n)
    f = rng.uniform(0.0, 1.0, n)
    pts = np.stack([x, y, z, f], axis=1).astype(np.float32)
    p2 = np.array([[10.0, 0, 12.0, 0], [0, 10.0, 6.0, 0], [0, 0, 1.0, 0]])
    r = np.eye(4)
    t = np.zeros((4, 4))
    t[:3, :] = [[0, -1, 0, 0], [0, 0, -1, 0], [1, 0, 0, 0]]
    t[3, 3] = 1.0
    sr, sf, _ = lidar_ref.project(pts, p2, r, t, 24, 12)
    dr, df = lidar_ref.upsample(sr, sf, 5, "gs-mean")

    def arr(name, a, ty, per_line):
        vals = [f"{v:.9e}" for v in np.asarray(a, dtype=np.float64).ravel()]
        lines = [", ".join(vals[i:i + per_line]) for i in range(0, len(vals), per_line)]
        body = "".join(f"    {ln},\n" for ln in lines)
        return f"pub static {name}: [{ty}; {len(vals)}] = [\n{body}];\n"

    pts_lines = "".join(
        "    [" + ", ".join(f"{v:.9e}" for v in p.astype(np.float64)) + "],\n" for p in pts)
    return (
        "//! Written by tools/lidar_goldens.py (the numpy reference of DESIGN §9): a\n"
        "//! 24 x 12 frame, its projection matrix and its dense maps with a 5 x 5 mask.\n"
        "//! Do not edit.\n\n"
        "/// Image width and height, and the mask.\n"
        "pub const WIDTH: usize = 24;\npub const HEIGHT: usize = 12;\npub const MASK: usize = 5;\n\n"
        "/// The composed projection matrix, row by row.\n"
        "pub static PROJECTION: [[f64; 4]; 3] = [\n"
        + "".join("    [" + ", ".join(f"{v:.1f}" for v in row) + "],\n"
                  for row in lidar_ref.product(lidar_ref.product(p2, r), t)[:3])
        + "];\n\n/// The scan: x, y, z, reflectance.\n"
        + f"pub static POINTS: [[f32; 4]; {n}] = [\n{pts_lines}];\n\n"
        + "/// The dense range map.\n" + arr("RANGE", dr, "f32", 6)
        + "\n/// The dense reflectance map.\n" + arr("REFLECTANCE", df, "f32", 6)
    )


def main():
    check = "--check" in sys.argv[1:]
    os.makedirs(OUT, exist_ok=True)
    scan = small_scan()
    files = {"small.bin": scan.astype("<f4").tobytes(), "small_calib.txt": CALIB.encode()}
    scan_path = os.path.join(OUT, "small.bin")
    calib_path = os.path.join(OUT, "small_calib.txt")
    if not check:
        for name in ("small.bin", "small_calib.txt"):
            open(os.path.join(OUT, name), "wb").write(files[name])
    arrays = outputs(scan_path, calib_path, 96, 32, CASES)
    files.update({k: npy_bytes(v) for k, v in arrays.items()})
    paths = {os.path.join(OUT, k): v for k, v in files.items()}
    paths[os.path.join(ROOT, "firmware", "src", "lidar_expected.rs")] = firmware_source().encode()
    bad = []
    for p, data in paths.items():
        if check:
            if not os.path.exists(p) or open(p, "rb").read() != data:
                bad.append(p)
        else:
            open(p, "wb").write(data)
    if bad:
        sys.exit("lidar_goldens: out of date: " + ", ".join(bad))
    print(f"{'checked' if check else 'wrote'} {len(paths)} files")


if __name__ == "__main__":
    main()
