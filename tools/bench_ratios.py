#!/usr/bin/env python3
"""Ratios of the layer benchmarks (benches/layer.rs) to the Sigmoid layer, from one run.

    python3 tools/bench_ratios.py --run     # runs `cargo bench --bench layer --features micromath` first
    python3 tools/bench_ratios.py           # reads the last run under target/criterion/

Uses criterion's median estimate of every benchmark. Ratios, not absolute times, are
the figures to compare between machines: they come from one run on one machine, so a
slow or busy machine slows every layer alike (to the extent it slows them evenly).
Exits 1 when a goal is missed, so a script can tell.
"""
import json
import os
import subprocess
import sys

LAYERS = ["sigmoid", "softmax", "ml", "map", "map_fast", "map_micromath"]
GOALS = {"ml": 0.5, "map": 1.25, "map_fast": 0.75}  # at most this many times the Sigmoid layer
GROUPS = {"detection": 1, "batch4096": 4096}


def target_dir():
    out = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--no-deps"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return json.loads(out)["target_directory"]


def median_ns(root, group, name):
    path = os.path.join(root, "criterion", group, name, "new", "estimates.json")
    try:
        with open(path) as f:
            return json.load(f)["median"]["point_estimate"]
    except FileNotFoundError:
        return None


def main():
    if "--run" in sys.argv[1:]:
        subprocess.run(["cargo", "bench", "--bench", "layer", "--features", "micromath"], check=True)
    root = target_dir()
    missed = []
    for group, per in GROUPS.items():
        base = median_ns(root, group, "sigmoid")
        if base is None:
            sys.exit(f"no results for {group}/sigmoid under {root}/criterion; run with --run")
        print(f"{group} ({per} detection{'s' if per > 1 else ''} per iteration)")
        print(f"  {'layer':10} {'ns/detection':>13} {'/ sigmoid':>10} {'goal':>8}")
        for name in LAYERS:
            t = median_ns(root, group, name)
            if t is None:
                print(f"  {name:10} {'(not run)':>13}")
                continue
            ratio = t / base
            goal = GOALS.get(name)
            mark = ""
            if goal is not None:
                ok = ratio <= goal
                mark = f"<= {goal:<4} {'met' if ok else 'MISSED'}"
                if not ok:
                    missed.append(f"{group}/{name}")
            print(f"  {name:10} {t / per:13.2f} {ratio:10.3f}   {mark}")
        print()
    dec = median_ns(root, "decode", "from_bytes")
    if dec is not None:
        print(f"decode: Table::<3, 22, 17>::from_bytes of the shipped table: {dec / 1000:.2f} us")
    if missed:
        print(f"goals missed: {', '.join(missed)}")
        sys.exit(1)


if __name__ == "__main__":
    main()
