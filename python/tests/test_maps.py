"""Recalibration maps (docs/DESIGN.md section 1.9) from Python: every head of the tables
with maps within 1e-6 of the independent numpy reference (tests/golden/layer/maps.csv,
read here with the csv module), the maps' knots, the table without its maps, and
`tune`'s `maps=` keyword and report."""

import csv

import numpy as np
import pytest

import mlmap
from conftest import CLASSES, ROOT

GOLDEN = ROOT / "tests" / "golden" / "layer"
HEADS = ("ml", "map", "bayes", "open")
TOL = 1e-6  # the layer's golden tolerance (tests/support.rs)


def golden_rows():
    with open(GOLDEN / "maps.csv", newline="") as f:
        lines = [line for line in f if not line.startswith("#")]
    return list(csv.DictReader(lines))


@pytest.mark.parametrize("name", ["small_maps", "small_maps_nobayes"])
def test_mapped_heads_match_the_reference(name):
    table = mlmap.Table.load(GOLDEN / f"{name}.mlmap")
    raw = table.without_maps()
    rows = [r for r in golden_rows() if r["table"] == name]
    assert len(rows) >= 20
    compared = 0
    for head in HEADS:
        if head not in table.heads:
            assert name == "small_maps_nobayes" and head in ("bayes", "open")
            assert all(r[f"{head}0"] == "" for r in rows)
            with pytest.raises(ValueError):
                table.scores(head, np.zeros((1, 3)))
            continue
        for r in rows:
            x = np.array([[float(r[f"x{i}"]) for i in range(3)]])
            os_ = float(r["objectness"])
            if r["error"]:
                with pytest.raises(ValueError):
                    table.scores(head, x, os_)
                continue
            want = np.array([float(r[f"{head}{i}"]) for i in range(3)])
            got = table.scores(head, x, os_)[0].astype(np.float64)
            own = raw.scores(head, x, os_)[0]
            top = own.max()
            what = f"{name} {r['case']} {head}: x = {x[0]}, OS = {os_}"
            if top == 0.0:
                assert np.all(got == 0.0), what
            elif top < 1e-30:
                # The head's f32 scores have lost their ratios to underflow: only the
                # mapped top is compared (as tests/maps.rs does).
                assert abs(got[own == top].max() - want.max()) <= TOL, what
            else:
                assert np.all(np.abs(got - want) <= TOL), f"{what}: {got} vs {want}"
            # The map keeps the head's decision and the order of its scores.
            assert np.array_equal(
                mlmap.decide(got[None].astype(np.float32), x), mlmap.decide(own[None], x)
            ), what
            for i in range(3):
                for j in range(3):
                    if own[i] >= own[j]:
                        assert got[i] >= got[j], what
            compared += 1
    assert compared >= (200 if name == "small_maps" else 60)


def test_recal_map_gives_the_stored_knots():
    table = mlmap.Table.load(GOLDEN / "small_maps.mlmap")
    # The open head's map of tools/mlmap_ref.py (SMALL_MAPS), exact in f32.
    assert table.recal_map("open") == [(0.0, 0.03125), (0.5, 0.25), (1.0, 1.0)]
    for head in HEADS:
        knots = table.recal_map(head)
        assert knots is not None and 2 <= len(knots) <= 32
        assert knots[0][0] == 0.0 and knots[-1][0] == 1.0
    with pytest.raises(ValueError):
        table.recal_map("softmax")
    raw = table.without_maps()
    assert all(raw.recal_map(h) is None for h in HEADS)
    # Without maps the table is the version-3 table the maps were added to.
    assert raw.to_bytes() == (GOLDEN / "small_open.mlmap").read_bytes()
    assert table.to_bytes()[4] == 4 and raw.to_bytes()[4] == 3
    nobayes = mlmap.Table.load(GOLDEN / "small_maps_nobayes.mlmap")
    assert nobayes.recal_map("bayes") is None and nobayes.recal_map("open") is None
    assert nobayes.without_maps().to_bytes() == (GOLDEN / "small.mlmap").read_bytes()


def test_tune_maps_keyword(data):
    tr, val = data["train"], data["val"]
    args = (tr.logits, tr.labels, (val.logits, val.labels, val.objectness), tr.objectness)
    grid = dict(classes=CLASSES, bins_ml=[8], bins_map=[8], bins_bayes=[10],
                lambdas_per_decade=1)
    without, report_without = mlmap.tune(*args, maps=False, **grid)
    assert "maps" not in report_without
    assert all(without.recal_map(h) is None for h in without.heads)
    table, report = mlmap.tune(*args, **grid)
    assert set(report["maps"]) == set(table.heads)
    for head, v in report["maps"].items():
        assert set(v) == {"kept", "cv_ece_without", "cv_ece_with", "within_guards",
                          "adds_no_loss", "knots"}
        knots = [tuple(k) for k in v["knots"]]
        assert 2 <= len(knots) <= 32
        kept = v["kept"]
        if kept:
            assert v["adds_no_loss"] and v["cv_ece_with"] < v["cv_ece_without"]
            assert table.recal_map(head) == knots
        else:
            assert table.recal_map(head) is None
    # The maps change no head but by their maps: without them, the same table.
    assert table.without_maps() == without
