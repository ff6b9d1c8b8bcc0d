"""The objectness feature (DESIGN §1.6): `fit(..., bayes={"objectness": True})` gives the
bytes of the independent numpy fit (tools/mlmap_ref.py), the statistics path refuses it,
and `tune(..., objectness_feature=True)` writes a table with it."""

import numpy as np
import pytest

import mlmap

from conftest import CLASSES, ROOT

GOLDEN = ROOT / "tests" / "golden" / "train_osf.mlmap"


def test_fit_with_the_objectness_feature_is_the_numpy_fit(data):
    t = data["train"]
    table = mlmap.fit(t.logits, t.labels, t.objectness, classes=CLASSES,
                      bayes={"objectness": True})
    assert table.to_bytes() == GOLDEN.read_bytes()
    # Without it, the table is the plain fit (and smaller).
    plain = mlmap.fit(t.logits, t.labels, t.objectness, classes=CLASSES)
    assert len(plain.to_bytes()) < len(GOLDEN.read_bytes())


def test_the_statistics_path_refuses_the_feature(data):
    t = data["train"]
    stats = mlmap.FitStats(t.logits, t.labels, t.objectness, classes=CLASSES)
    with pytest.raises(ValueError, match="objectness"):
        stats.edges(bayes={"objectness": True})
    with pytest.raises(TypeError, match="objectness"):
        mlmap.fit(t.logits, t.labels, t.objectness, classes=CLASSES,
                  bayes={"objectness": 1.0})


def test_objectness_zero_or_one_everywhere_is_refused(data):
    t = data["train"]
    ones = np.ones(len(t))
    with pytest.raises(ValueError, match="objectness"):
        mlmap.fit(t.logits, t.labels, ones, classes=CLASSES, bayes={"objectness": True})


def test_tune_with_the_feature(data):
    t, v = data["train"], data["val"]
    val = (v.logits, v.labels, v.objectness)
    table, report = mlmap.tune(t.logits, t.labels, val, t.objectness, classes=CLASSES,
                               bins_ml=[22], bins_map=[17], bins_bayes=[22],
                               lambdas_per_decade=1, objectness_feature=True, maps=False)
    # Version 4 (byte 4 of the file): the feature needs it.
    assert table.to_bytes()[4] == 4
    assert "open" in report
