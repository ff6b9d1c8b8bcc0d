"""mlmap.conformal_fit and Table.conformal_sets (docs/DESIGN.md section 8): the bytes of
`mlmap conformal`, the thresholds and sets of the numpy reference (tools/conformal_ref.py)."""
import json
import math
import pathlib

import numpy as np
import pytest

import mlmap

ROOT = pathlib.Path(__file__).resolve().parents[2]
NAMES = ("car", "cyclist", "pedestrian")


def read(name):
    import csv

    with open(ROOT / "examples" / "data" / f"{name}.csv") as fh:
        rows = list(csv.DictReader(fh))
    x = np.array([[float(r[c]) for c in NAMES] for r in rows])
    os_ = np.array([float(r["objectness"]) for r in rows])
    y = np.array([NAMES.index(r["label"]) if r["label"] in NAMES else -1 for r in rows])
    return x, os_, y


def reference(head, alpha):
    ref = json.loads((ROOT / "tests" / "golden" / "conformal" / "reference.json").read_text())
    return next(c for c in ref["cases"] if c["head"] == head and c["alpha"] == alpha)


def test_fit_gives_the_cli_bytes_and_numpy_sets():
    table = mlmap.Table.load(ROOT / "tables" / "default.mlmap")
    x, os_, y = read("val")
    data = mlmap.conformal_fit(table, x, y, os_, alpha=0.1, head="open")
    assert data == (ROOT / "tests" / "golden" / "conformal_small.mlmap").read_bytes()
    t = mlmap.Table.from_bytes(data)
    want = reference("open", 0.1)
    info = t.conformal
    assert info["head"] == "open" and info["calibration_rows"] == want["rows"]
    for got, w in zip(info["thresholds"], want["thresholds"]):
        assert abs(got - w) < 1e-5
    xt, ot, _ = read("test")
    n = len(want["test_sets"])
    sets = t.conformal_sets(xt[:n], ot[:n])
    assert sets.shape == (n, 3) and sets.dtype == np.bool_
    compared = 0
    for row, w, m in zip(sets, want["test_sets"], want["test_margin"]):
        if m > 1e-5:
            compared += 1
            assert list(row.astype(int)) == w
    assert compared > 0.9 * n
    # Round trip keeps the section.
    assert mlmap.Table.from_bytes(t.to_bytes()).conformal == info


def test_refusals():
    table = mlmap.Table.load(ROOT / "tables" / "default.mlmap")
    x, os_, y = read("val")
    assert table.conformal is None
    with pytest.raises(ValueError, match="no conformal section"):
        table.conformal_sets(x[:2], os_[:2])
    for alpha in (0.0, 1.0, math.nan):
        with pytest.raises(ValueError, match="alpha"):
            mlmap.conformal_fit(table, x, y, os_, alpha=alpha)
    with pytest.raises(ValueError, match="head"):
        mlmap.conformal_fit(table, x, y, os_, alpha=0.1, head="best")
    with pytest.raises(ValueError, match="labels"):
        mlmap.conformal_fit(table, x, y[:-1], os_, alpha=0.1)
    t = mlmap.Table.from_bytes(mlmap.conformal_fit(table, x, y, os_, alpha=0.1))
    with pytest.raises(ValueError):
        t.conformal_sets(np.array([[0.0, math.nan, 0.0]]))
