"""mlmap.Monitor and mlmap.monitor_fit (docs/DESIGN.md section 7): the bytes of
`mlmap monitor fit`, the windows of the numpy reference (tools/monitor_ref.py)."""
import json
import math
import pathlib

import numpy as np
import pytest

import mlmap

ROOT = pathlib.Path(__file__).resolve().parents[2]


def read(name):
    import csv

    with open(ROOT / "examples" / "data" / f"{name}.csv") as fh:
        rows = list(csv.DictReader(fh))
    x = np.array([[float(r[c]) for c in ("car", "cyclist", "pedestrian")] for r in rows])
    os_ = np.array([float(r["objectness"]) for r in rows])
    return x, os_


def test_fit_gives_the_cli_bytes():
    table = mlmap.Table.load(ROOT / "tables" / "default.mlmap")
    x, os_ = read("val")
    data = mlmap.monitor_fit(table, x, os_, window=50, false_alarm=0.05)
    assert data == (ROOT / "tests" / "golden" / "monitor_small.mlmap").read_bytes()


def test_windows_match_the_reference():
    mon = mlmap.Monitor.load(ROOT / "tests" / "golden" / "monitor_small.mlmap")
    assert mon.window == 50 and mon.fitted
    assert mon.alpha == pytest.approx(0.05)
    golden = json.loads((ROOT / "tests" / "golden" / "monitor" / "windows_ood.json").read_text())
    x, os_ = read("ood")
    got = mon.push(x, os_)
    assert mon.finish() is None
    assert len(got) == len(golden["windows"]) == 40
    for g, w in zip(got, golden["windows"]):
        assert g["window"] == w["window"] and g["rows"] == 50
        assert g["alarm"] is True
        assert g["psi_max"] == pytest.approx(w["psi_max"], rel=1e-5, abs=1e-6)
        assert g["oos_rate"] == pytest.approx(w["oos_rate"], abs=1e-6)
        assert g["q_mean"] == pytest.approx(w["q_mean"], abs=1e-5)
        assert set(g["psi"]) == {"car", "cyclist", "pedestrian"}


def test_one_row_at_a_time_is_the_same():
    mon_a = mlmap.Monitor.load(ROOT / "tests" / "golden" / "monitor_small.mlmap")
    mon_b = mlmap.Monitor.load(ROOT / "tests" / "golden" / "monitor_small.mlmap")
    x, os_ = read("test")
    x, os_ = x[:120], os_[:120]
    whole = mon_a.push(x, os_)
    single = [w for i in range(len(x)) for w in mon_b.push(x[i], float(os_[i]))]
    assert whole == single and len(whole) == 2
    last = mon_a.finish()
    assert last["rows"] == 20 and last["alarm"] is False


def test_refusals():
    plain = (ROOT / "tables" / "default.mlmap").read_bytes()
    with pytest.raises(ValueError, match="window="):
        mlmap.Monitor.from_bytes(plain)
    mon = mlmap.Monitor.from_bytes(plain, window=10)
    assert not mon.fitted and math.isinf(mon.thresholds["psi"])
    with pytest.raises(ValueError, match="row index 1"):
        mon.push(np.array([[0.0, 0.0, 0.0], [0.0, np.nan, 0.0]]))
    with pytest.raises(ValueError, match="windows of 50"):
        mlmap.Monitor.load(ROOT / "tests" / "golden" / "monitor_small.mlmap", window=60)
    table = mlmap.Table.load(ROOT / "tables" / "default.mlmap")
    with pytest.raises(ValueError, match="false_alarm"):
        mlmap.monitor_fit(table, np.zeros((5, 3)), window=5, false_alarm=0.0)
