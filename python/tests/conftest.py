"""Shared fixtures: the repository, the shipped data as numpy arrays, and the `mlmap`
command-line tool, whose outputs are the golden values of the binding tests (the
correctness of the scores and the fit is checked against the numpy reference
tools/mlmap_ref.py)."""

import csv
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA = ROOT / "examples" / "data"
DEFAULT_TABLE = ROOT / "tables" / "default.mlmap"
CLASSES = ["car", "cyclist", "pedestrian"]


class Data:
    """One CSV file of DESIGN §2 as arrays: float64 logits as written, labels as
    class indices (-1 background), objectness."""

    def __init__(self, path):
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        self.path = path
        self.logits = np.array([[float(r[c]) for c in CLASSES] for r in rows])
        self.labels = np.array(
            [CLASSES.index(r["label"]) if r["label"] in CLASSES else -1 for r in rows],
            dtype=np.int64,
        )
        self.objectness = np.array([float(r["objectness"]) for r in rows])
        self.ids = [r["id"] for r in rows]

    def __len__(self):
        return len(self.labels)


@pytest.fixture(scope="session")
def data():
    """The shipped data sets, by name: train, val, test, ood."""
    return {name: Data(DATA / f"{name}.csv") for name in ("train", "val", "test", "ood")}


@pytest.fixture(scope="session")
def cli():
    """A function running the `mlmap` tool (`$MLMAP_CLI`, or built here) and returning
    its standard output."""
    exe = os.environ.get("MLMAP_CLI")
    if not exe:
        subprocess.run(
            ["cargo", "build", "--release", "--features", "cli", "--bin", "mlmap", "--quiet"],
            cwd=ROOT,
            check=True,
        )
        exe = str(ROOT / "target" / "release" / "mlmap")

    def run(*args):
        done = subprocess.run(
            [exe, *map(str, args)], cwd=ROOT, capture_output=True, text=True
        )
        if done.returncode != 0:
            raise AssertionError(f"mlmap {' '.join(map(str, args))}: {done.stderr}")
        return done.stdout

    return run


@pytest.fixture(scope="session")
def inspect(cli):
    """`mlmap inspect --format json` of a table file, parsed."""
    return lambda path: json.loads(cli("inspect", path, "--format", "json"))
