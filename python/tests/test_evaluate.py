"""`mlmap.evaluate`: the numbers of `mlmap eval --format json`, from arrays."""

import json

import numpy as np
import pytest

import mlmap
from conftest import CLASSES, DEFAULT_TABLE, ROOT


@pytest.fixture(scope="session")
def table():
    return mlmap.Table.load(DEFAULT_TABLE)


def eval_json(cli, *args):
    return json.loads(cli("eval", "--table", DEFAULT_TABLE, "--format", "json", *args))


@pytest.mark.parametrize(
    "binning, flag", [("design", "default"), ("default", "default"), ("netcal", "netcal"),
                      ("torchmetrics", "torchmetrics")])
def test_equals_mlmap_eval_with_val_and_ood(table, data, cli, binning, flag):
    want = eval_json(
        cli, "--test", "examples/data/test.csv", "--val", "examples/data/val.csv",
        "--ood", "examples/data/ood.csv", "--ece-bins", "15", "--ece-binning", flag,
    )
    test, val, ood = data["test"], data["val"], data["ood"]
    got = mlmap.evaluate(
        table, test.logits, test.labels, test.objectness,
        val=(val.logits, val.labels, val.objectness),
        ood=(ood.logits, None, ood.objectness),
        ece_bins=15, ece_binning=binning,
    )
    # Every value, exactly: the JSON holds the shortest repr of each f64.
    assert got == want
    assert list(got["methods"]) == [
        "sigmoid", "softmax", "temperature", "isotonic", "energy", "ml", "map", "bayes", "open"]
    assert got["methods"]["energy"]["ece"] is None
    assert 0.0 <= got["methods"]["isotonic"]["ood_fpr95"] <= 1.0


def test_equals_mlmap_eval_on_test_alone(table, data, cli):
    want = eval_json(cli, "--test", "examples/data/test.csv")
    test = data["test"]
    # Fortran-ordered logits, int8 labels: the same numbers.
    got = mlmap.evaluate(table, np.asfortranarray(test.logits), test.labels.astype(np.int8),
                         test.objectness, classes=CLASSES)
    assert got == want
    assert "temperature" not in got["methods"] and got["ood_rows"] is None


def test_group_by_equals_mlmap_eval_group_by(table, data, cli, tmp_path):
    # test.csv with a column `bucket` (id % 3) after the label: not a class.
    lines = (ROOT / "examples" / "data" / "test.csv").read_text().splitlines()
    out, buckets = [], []
    for i, line in enumerate(lines):
        ident, label, rest = line.split(",", 2)
        bucket = "bucket" if i == 0 else str(int(ident) % 3)
        out.append(f"{ident},{label},{bucket},{rest}")
        if i:
            buckets.append(int(bucket))
    path = tmp_path / "grouped.csv"
    path.write_text("\n".join(out) + "\n")
    want = eval_json(cli, "--test", str(path), "--ood", "examples/data/ood.csv",
                     "--group-by", "bucket")
    test, ood = data["test"], data["ood"]
    got = mlmap.evaluate(table, test.logits, test.labels, test.objectness,
                         ood=(ood.logits, None, ood.objectness), group_by=buckets)
    assert want.pop("group_by") == "bucket"
    assert got == want
    assert list(got["groups"]) == ["0", "1", "2"]
    assert sum(g["rows"] for g in got["groups"].values()) == got["rows"]
    with pytest.raises(ValueError, match="^group_by: has 2 values but the logits have"):
        mlmap.evaluate(table, test.logits, test.labels, group_by=[0, 1])


def test_undefined_metrics_are_none(table):
    # No row labelled pedestrian: its average precision is undefined.
    x = np.array([[5.0, -2.0, -1.0], [-1.0, 4.0, -2.0], [2.0, 1.0, 0.0]])
    got = mlmap.evaluate(table, x, np.array([0, 1, -1]))
    assert got["methods"]["ml"]["ap_pedestrian"] is None
    assert got["methods"]["ml"]["ap_car"] is not None


@pytest.mark.parametrize(
    "change, exc, message",
    [
        (dict(labels=np.array([0, 3, 1])), ValueError,
         r"^labels: row index 1: label 3 is not a class index \(0 to 2\) or -1 \(background\)$"),
        (dict(labels=np.array([0, -2, 1])), ValueError, r"label -2 is not a class index"),
        (dict(labels=np.array([0.0, 1.0, 1.0])), ValueError, r'^labels: dtype "float64" is not supported'),
        (dict(labels=np.array([0, 1])), ValueError, r"^labels: has 2 rows but the logits have 3$"),
        (dict(logits=np.array([[0.0, 1.0, 2.0], [0.0, np.inf, 1.0], [0.0, 0.0, 0.0]])), ValueError,
         r'^logits: row index 1: column "cyclist": "inf" is not a finite number$'),
        (dict(logits=np.array([[0.0, 1.0, 2.0], [0.0, 1.0, 1.0], [0.0, 0.0, np.nan]])), ValueError,
         r'^logits: row index 2: column "pedestrian": "NaN" is not a finite number$'),
        (dict(objectness=np.array([1.0, 1.0, 1.1])), ValueError,
         r'^objectness: row index 2: objectness "1.1" is not a number in \[0, 1\]$'),
        (dict(classes=["car", "pedestrian", "cyclist"]), ValueError,
         r"^test: its classes \[car, pedestrian, cyclist\] differ from the table's "
         r"\[car, cyclist, pedestrian\] \(same names, same order needed\)$"),
        (dict(ece_bins=0), ValueError, r"^ece_bins 0 is out of range: expected an integer from 1 to "),
        (dict(ece_binning="sklearn"), ValueError,
         r"^unknown binning `sklearn`: expected one of default, netcal, torchmetrics$"),
        (dict(val=(np.zeros((2, 3)), np.array([0, 5]))), ValueError, r"^val\.labels: row index 1: label 5"),
        (dict(ood=np.zeros((2, 4))), ValueError, r"^ood\.logits: has 4 columns but there are 3 classes"),
        (dict(logits=np.zeros((0, 3)), labels=np.zeros(0, dtype=int)), ValueError, r"^logits: holds no rows$"),
    ],
)
def test_bad_input_raises_with_the_cli_message(table, change, exc, message):
    args = dict(logits=np.array([[5.0, -2.0, -1.0], [-1.0, 4.0, -2.0], [2.0, 1.0, 0.0]]),
                labels=np.array([0, 1, -1]), objectness=None)
    args.update(change)
    kw = {k: args.pop(k) for k in ("val", "ood", "ece_bins", "ece_binning", "classes") if k in args}
    with pytest.raises(exc, match=message):
        mlmap.evaluate(table, args["logits"], args["labels"], args["objectness"], **kw)
