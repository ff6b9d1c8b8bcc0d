#!/usr/bin/env python3
"""The speed of the LiDAR maps (docs/DESIGN.md section 9), Rust against the vectorised
numpy reference, on the same synthetic KITTI-sized frame, in one run:

    cargo build --release --features std --example lidar_timing
    python3 tools/lidar_bench.py [--numpy-repeat 3] [--rust-repeat 21]

Generates the frame of examples/lidar_frame.py (seed 1) in a temporary directory, times
tools/lidar_ref.py (best of --numpy-repeat) and target/release/examples/lidar_timing
(median and best of --rust-repeat), both on one core, on the projection and the 13 x 13
upsampling of both maps (files read outside the timing), checks that the Rust maps equal
the reference within 1e-5 relative, and prints the times and the ratio.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--numpy-repeat", type=int, default=3)
    ap.add_argument("--rust-repeat", type=int, default=21)
    a = ap.parse_args()
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([sys.executable, os.path.join(ROOT, "examples", "lidar_frame.py"), d],
                       check=True, stdout=subprocess.DEVNULL)
        scan, calib = os.path.join(d, "velodyne.bin"), os.path.join(d, "calib.txt")
        ref = subprocess.run(
            [sys.executable, os.path.join(ROOT, "tools", "lidar_ref.py"), "--velodyne", scan,
             "--calib", calib, "--output", os.path.join(d, "ref"),
             "--repeat", str(a.numpy_repeat)],
            check=True, capture_output=True, text=True, env=env).stdout
        numpy_ms = float(re.search(r"best of \d+: ([\d.]+) ms", ref).group(1))
        rust = subprocess.run(
            ["taskset", "-c", "0",
             os.path.join(ROOT, "target", "release", "examples", "lidar_timing"), scan, calib,
             "1242", "375", "13", str(a.rust_repeat)],
            check=True, capture_output=True, text=True).stdout
        kv = dict(x.split("=") for x in rust.split())
        cli = os.path.join(ROOT, "target", "release", "mlmap")
        if os.path.exists(cli):
            subprocess.run([cli, "lidar-maps", "--velodyne", scan, "--calib", calib,
                            "--output", os.path.join(d, "rust")], check=True,
                           stdout=subprocess.DEVNULL)
            for m in ("rav", "rev"):
                got = np.load(os.path.join(d, "rust", f"{m}.npy"))
                want = np.load(os.path.join(d, "ref", f"{m}.npy"))
                err = np.max(np.abs(got - want) / np.maximum(np.abs(want), 1e-30))
                print(f"{m}: max relative difference {err:.2e}")
                if err > 1e-5:
                    sys.exit(f"{m}: Rust and numpy differ by {err:.2e} > 1e-5")
        print(f"frame: {kv['points']} points, {kv['pixels']} pixels with a point, "
              f"1242 x 375, mask 13")
        print(f"numpy (vectorised, best of {a.numpy_repeat}): {numpy_ms:.1f} ms")
        print(f"Rust (one core, median / best of {kv['reps']}): {kv['median_ms']} / "
              f"{kv['best_ms']} ms")
        print(f"ratio numpy / Rust (best): {numpy_ms / float(kv['best_ms']):.0f}x")


if __name__ == "__main__":
    main()
