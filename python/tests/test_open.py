"""The open head (docs/DESIGN.md section 1.8) from Python: `Table.open` bit for bit
`mlmap apply`'s `open_*` columns and, within 1e-6, the independent numpy reference
(tools/mlmap_ref.py); tables without the head refuse it; `background=` rows give the
bytes of `mlmap fit --background FILE`, in one call, in shards, and in `tune`."""

import csv
import json
import sys

import numpy as np
import pytest

import mlmap
from conftest import CLASSES, DEFAULT_TABLE, ROOT

sys.path.insert(0, str(ROOT / "tools"))
import mlmap_ref  # noqa: E402  (the independent numpy implementation)

GOLDEN = ROOT / "tests" / "golden" / "layer"
TRAIN = "examples/data/train.csv"
# Tables with the open head: the shipped one (untuned: T = 1, epsilon = 0, with a
# background category), and two hand-made ones (T = 1.75, epsilon = 0.05 with
# background; T = 0.8, epsilon = 0 without).
OPEN_TABLES = {
    "default": DEFAULT_TABLE,
    "small_open": GOLDEN / "small_open.mlmap",
    "small_open_nobg": GOLDEN / "small_open_nobg.mlmap",
}
# Version 2 (Bayes head, no open head) and version 1 (neither).
V2_TABLE = GOLDEN / "small_bayes.mlmap"
V1_TABLE = GOLDEN / "small.mlmap"


def cases(n, seed):
    """(N, 3) logits over and beyond the small tables' ranges, with infinities, and
    objectness in [0, 1] with its ends."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-6.0, 6.0, size=(n, 3))
    x[::7] *= 4.0
    x[3] = [np.inf, 0.5, -1.0]
    x[4] = [-np.inf, -np.inf, 2.0]
    x[5] = [np.inf, np.inf, -np.inf]
    x[6] = [30.0, -30.0, 0.0]
    os_ = rng.uniform(0.0, 1.0, size=n)
    os_[:3] = [0.0, 1.0, 0.5]
    return x, os_


def write_csv(path, logits, objectness, labels=None):
    """A data file of DESIGN section 2; floats as `repr`, which reads back exactly."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["id", "label", "objectness"] + CLASSES)
        for i, (x, o) in enumerate(zip(logits, objectness)):
            label = "" if labels is None else labels[i]
            w.writerow([i, label, repr(float(o))] + [repr(float(v)) for v in x])


def apply(cli, tmp_path, table, logits, objectness):
    """`mlmap apply`: the open head's (N, K) float32 scores and its decisions."""
    src, out = tmp_path / "in.csv", tmp_path / "scores.csv"
    write_csv(src, logits, objectness)
    cli("apply", "--table", table, "--input", src, "--output", out)
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    scores = np.array([[np.float32(r[f"open_{c}"]) for c in CLASSES] for r in rows],
                      dtype=np.float32)
    pred = np.array([CLASSES.index(r["open_pred"]) for r in rows])
    return scores, pred


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


# --- scores ------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(OPEN_TABLES))
def test_open_scores_equal_mlmap_apply_bit_for_bit(cli, tmp_path, data, name):
    path = OPEN_TABLES[name]
    t = mlmap.Table.load(path)
    assert t.heads == ("ml", "map", "bayes", "open")
    if name == "default":
        x, os_ = data["test"].logits, data["test"].objectness
    else:
        x, os_ = cases(3000, 11)
        x = x[np.isfinite(x).all(axis=1)]  # the CSV holds finite values
        os_ = os_[: len(x)]
    want, want_pred = apply(cli, tmp_path, path, x, os_)
    for got in (t.open(x, os_), t.scores("open", x, os_),
                t.open(x.astype(np.float32), os_.astype(np.float32))):
        assert got.dtype == np.float32 and got.shape == x.shape
        assert np.array_equal(bits(got), bits(want))
    assert np.array_equal(mlmap.decide(t.open(x, os_), x), want_pred)
    # The head's decision is the detector's: the largest logit (ties: DESIGN 1.7).
    assert np.array_equal(want_pred, mlmap.decide(x, x))


@pytest.mark.parametrize("name", list(OPEN_TABLES))
def test_open_scores_equal_the_numpy_reference(data, name):
    path = OPEN_TABLES[name]
    ref = mlmap_ref.decode(path.read_bytes())
    t = mlmap.Table.load(path)
    assert t.open_params == {"temperature": ref["open"][0], "epsilon": ref["open"][1]}
    if name == "default":
        x, os_ = data["test"].logits[:2000], data["test"].objectness[:2000]
        # The layer scores float32 logits: give the reference the same values.
        x = x.astype(np.float32).astype(np.float64)
    else:
        x, os_ = cases(2000, 5)
    os32 = os_.astype(np.float32)
    got = t.open(x, os32)
    want = np.array([mlmap_ref.open_(ref, row, float(o)) for row, o in zip(x, os32)])
    assert np.abs(got - want).max() <= 1e-6
    # Invariants of DESIGN 1.8: in [0, OS], summing to at most OS.
    assert (got >= 0).all() and (got <= os32[:, None]).all()
    assert (got.sum(axis=1) <= os32 * (1 + 1e-5)).all()


def test_open_without_background_or_unknown_is_the_temperature_softmax():
    # T = 0.8, epsilon = 0, no background category: q = 1, the scores are
    # OS * softmax(z / T) (DESIGN 1.8).
    t = mlmap.Table.load(OPEN_TABLES["small_open_nobg"])
    x, os_ = cases(500, 2)
    x = x[np.isfinite(x).all(axis=1)]
    os_ = os_[: len(x)]
    z = x.astype(np.float32).astype(np.float64) / 0.800000011920929  # f32(0.8)
    e = np.exp(z - z.max(axis=1, keepdims=True))
    want = np.float32(os_)[:, None] * e / e.sum(axis=1, keepdims=True)
    assert np.abs(t.open(x, os_) - want).max() <= 1e-6


def test_a_table_without_the_open_head_refuses_it(data):
    x = data["test"].logits[:5]
    for path, heads in ((V2_TABLE, ("ml", "map", "bayes")), (V1_TABLE, ("ml", "map"))):
        t = mlmap.Table.load(path)
        assert t.heads == heads and t.open_params is None
        assert "open=" not in repr(t)
        for call in (lambda: t.open(x), lambda: t.scores("open", x, 0.5)):
            with pytest.raises(ValueError, match="^the table has no open head$"):
                call()
        # The other heads still score.
        assert t.scores(heads[-1], x).shape == (5, 3)


def test_open_head_properties_and_repr(inspect):
    for name, path in OPEN_TABLES.items():
        t = mlmap.Table.load(path)
        info = inspect(path)
        assert info["format_version"] == 3
        assert t.open_params == {"temperature": info["open"]["temperature"],
                                 "epsilon": info["open"]["epsilon"]}
    t = mlmap.Table.load(OPEN_TABLES["small_open"])
    assert t.open_params == {"temperature": 1.75, "epsilon": float(np.float32(0.05))}
    assert ", open=(temperature=1.75, epsilon=0.05), " in repr(t)
    assert mlmap.Table.load(DEFAULT_TABLE).open_params == {"temperature": 1.0, "epsilon": 0.0}
    with pytest.raises(ValueError, match=r"^the open head has no histogram of its own"):
        t.histogram("open", 0)
    with pytest.raises(ValueError, match="^unknown head `softmax`: expected one of ml, map, bayes, open$"):
        t.scores("softmax", np.zeros((1, 3)))


def test_open_refuses_bad_input_as_the_other_heads():
    t = mlmap.Table.load(OPEN_TABLES["small_open"])
    with pytest.raises(ValueError, match=r"^logits: row index 1: logit of class 2 is NaN$"):
        t.open(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, np.nan]]))
    with pytest.raises(ValueError, match=r'^objectness: row index 0: objectness "1\.5"'):
        t.open(np.zeros((2, 3)), np.array([1.5, 0.5]))
    with pytest.raises(ValueError, match=r"^logits: has 2 columns; the table has 3 classes"):
        t.open(np.zeros((2, 2)))


def test_large_inputs_score_the_open_head_in_parallel_as_in_small_batches():
    t = mlmap.Table.load(OPEN_TABLES["small_open"])
    rng = np.random.default_rng(1)
    n = 150_001
    x = rng.normal(0.0, 3.0, size=(n, 3)).astype(np.float32)
    os_ = rng.uniform(0.0, 1.0, size=n)
    whole = t.open(x, os_)
    parts = np.concatenate([t.open(x[i : i + 7000], os_[i : i + 7000]) for i in range(0, n, 7000)])
    assert np.array_equal(whole, parts)
    x[140_000, 0] = np.nan
    x[90_000, 1] = np.nan
    with pytest.raises(ValueError, match=r"^logits: row index 90000: logit of class 1 is NaN$"):
        t.open(x)


# --- background rows ---------------------------------------------------------------


@pytest.fixture(scope="session")
def background(data, tmp_path_factory):
    """Rows taken as background: the never-seen objects of the shipped data, written to
    two CSV files (with labels of classes, which `--background` ignores); the arrays."""
    ood = data["ood"]
    d = tmp_path_factory.mktemp("background")
    half = len(ood) // 2
    labels = [CLASSES[i % 3] for i in range(len(ood))]
    write_csv(d / "a.csv", ood.logits[:half], ood.objectness[:half], labels[:half])
    write_csv(d / "b.csv", ood.logits[half:], ood.objectness[half:], labels[half:])
    return {"files": (d / "a.csv", d / "b.csv"), "logits": ood.logits, "half": half}


def test_fit_with_background_gives_the_bytes_of_mlmap_fit_background(data, cli, tmp_path,
                                                                     background):
    train = data["train"]
    a, b = background["files"]
    out = tmp_path / "bg.mlmap"
    cli("fit", "--train", TRAIN, "--background", a, "--background", b, "--output", out)
    got = mlmap.fit(train.logits, train.labels, train.objectness, classes=CLASSES,
                    background=background["logits"])
    assert got.to_bytes() == out.read_bytes()
    # The background rows changed the table: only its Bayes head (and so the open head).
    plain = mlmap.fit(train.logits, train.labels, classes=CLASSES)
    assert got != plain
    assert got.training_rows == plain.training_rows
    for head in ("ml", "map"):
        assert np.array_equal(got.scores(head, data["test"].logits),
                              plain.scores(head, data["test"].logits))
    assert got.open_params == {"temperature": 1.0, "epsilon": 0.0}
    # The never-seen objects now look less like known objects.
    ood = background["logits"]
    assert got.open(ood).sum(axis=1).mean() < plain.open(ood).sum(axis=1).mean()
    # One file: the first half.
    out1 = tmp_path / "bg1.mlmap"
    cli("fit", "--train", TRAIN, "--background", a, "--output", out1)
    one = mlmap.fit(train.logits, train.labels, classes=CLASSES,
                    background=background["logits"][: background["half"]])
    assert one.to_bytes() == out1.read_bytes()
    # No rows given as background: the plain fit.
    assert mlmap.fit(train.logits, train.labels, classes=CLASSES,
                     background=np.zeros((0, 3))) == plain
    assert mlmap.fit(train.logits, train.labels, classes=CLASSES, background=None) == plain


def test_background_rows_are_rows_labelled_background(data, background):
    train = data["train"]
    bg = background["logits"]
    as_labels = mlmap.fit(np.concatenate([train.logits, bg]),
                          np.concatenate([train.labels, np.full(len(bg), -1)]),
                          classes=CLASSES)
    assert mlmap.fit(train.logits, train.labels, classes=CLASSES, background=bg) == as_labels


def test_sharded_fit_with_background_gives_the_bytes_of_one_fit(data, background):
    train, bg, half = data["train"], background["logits"], background["half"]
    want = mlmap.fit(train.logits, train.labels, classes=CLASSES, background=bg)
    x, y = train.logits, train.labels
    # Shards: training rows with some background rows, training rows alone, and
    # background rows alone.
    shards = [
        dict(logits=x[:7000], labels=y[:7000], background=bg[:half]),
        dict(logits=x[7000:], labels=y[7000:]),
        dict(logits=np.zeros((0, 3)), labels=np.zeros(0, dtype=np.int64), background=bg[half:]),
    ]
    stats = sum(mlmap.FitStats(classes=CLASSES, **s) for s in shards)
    assert stats.rows == len(train) + len(bg)
    edges = stats.edges()
    counts = sum(mlmap.FitCounts(edges, **s) for s in shards)
    assert counts.rows == len(train) + len(bg)
    assert mlmap.finish(stats, counts).to_bytes() == want.to_bytes()
    # Counts of background rows the statistics did not see are refused, naming them.
    far = np.full((1, 3), 1e6)
    with pytest.raises(ValueError, match=r"^background: row index 0: a training value lies "
                                         r"outside the edges"):
        mlmap.FitCounts(edges, x[:10], y[:10], background=far)


def test_tune_with_background_gives_the_table_and_report_of_mlmap_tune(data, cli, tmp_path,
                                                                       background):
    a, b = background["files"]
    out = tmp_path / "tuned.mlmap"
    grid = ["--bins-ml", "8,22", "--bins-map", "8,17", "--bins-bayes", "10,22",
            "--lambdas-per-decade", "1"]
    report = json.loads(cli(
        "tune", "--train", TRAIN, "--val", "examples/data/val.csv", "--background", a,
        "--background", b, *grid, "--format", "json", "--output", out))
    tr, val = data["train"], data["val"]
    table, got = mlmap.tune(
        tr.logits, tr.labels, (val.logits, val.labels, val.objectness), tr.objectness,
        background=background["logits"], classes=CLASSES, bins_ml=[8, 22], bins_map=[8, 17],
        bins_bayes=[10, 22], lambdas_per_decade=1)
    assert table.to_bytes() == out.read_bytes()
    del report["table"]
    assert got == report
    # The open head is searched (epsilon 0 among the candidates) and reported; the
    # table holds the best candidate's parameters.
    assert got["candidates"]["open"] >= 2 and got["open"]
    best = got["open"][0]
    chosen = got["validation"]["methods"]["open"]
    params = {"temperature": best["temperature"], "epsilon": best["epsilon"]}
    assert table.open_params == params
    assert {k: chosen[k] for k in params} == params


@pytest.mark.parametrize(
    "bg, message",
    [
        (np.zeros((2, 2)), r"^background: has 2 columns but the logits have 3$"),
        (np.zeros(3), r"^background: shape \(3,\) is not \(N, K\)"),
        (np.zeros((2, 3), dtype=np.int64), r'^background: dtype "int64" is not supported'),
        (np.array([[0.0, 1.0, 2.0], [0.0, np.nan, 0.0]]),
         r'^background: row index 1: column "cyclist": "NaN" is not a finite number$'),
        (np.array([[0.0, 1.0, np.inf]]),
         r'^background: row index 0: column "pedestrian": "inf" is not a finite number$'),
    ],
)
def test_bad_background_raises_value_error(data, bg, message):
    train = data["train"]
    x, y = train.logits[:3000], train.labels[:3000]
    with pytest.raises(ValueError, match=message):
        mlmap.fit(x, y, classes=CLASSES, background=bg)
    with pytest.raises(ValueError, match=message):
        mlmap.FitStats(x, y, classes=CLASSES, background=bg)
    with pytest.raises(ValueError, match=message):
        mlmap.FitCounts(mlmap.FitStats(x, y, classes=CLASSES).edges(), x, y, background=bg)
