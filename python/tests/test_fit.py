"""`mlmap.fit`, `mlmap.tune` and the mergeable statistics: the bytes of the independent
numpy fit (tools/mlmap_ref.py) with the default settings, and the same table bytes as
`mlmap fit` / `mlmap tune` on the shipped data, whatever the split of the rows."""

import json
import pickle
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mlmap
from conftest import CLASSES, DEFAULT_TABLE, ROOT

sys.path.insert(0, str(ROOT / "tools"))
import mlmap_ref  # noqa: E402  (the independent numpy implementation)

TRAIN = "examples/data/train.csv"


def cli_table(cli, tmp_path, *flags):
    out = tmp_path / "cli.mlmap"
    cli("fit", "--train", TRAIN, *flags, "--output", out)
    return out.read_bytes()


# (keywords of mlmap.fit, flags of mlmap fit)
SETTINGS = [
    ({}, []),
    (dict(bayes=None), ["--no-bayes"]),
    (dict(bayes=False), ["--no-bayes"]),
    (dict(edges="matlab"), ["--edges", "matlab"]),
    (dict(tail="clamp", bins_ml=9, lambda_ml=0.01, bins_map=30, lambda_map=1e-6),
     ["--upper-tail", "clamp", "--bins-ml", "9", "--lambda-ml", "0.01", "--bins-map", "30",
      "--lambda-map", "1e-6"]),
    (dict(bayes={"bins": 7, "lambda": 0.25}), ["--bins-bayes", "7", "--lambda-bayes", "0.25"]),
    (dict(edges="matlab", bayes={"bins": 40}), ["--edges", "matlab", "--bins-bayes", "40"]),
]


@pytest.mark.parametrize("kw, flags", SETTINGS)
def test_fit_gives_the_bytes_of_mlmap_fit(data, cli, tmp_path, kw, flags):
    train = data["train"]
    want = cli_table(cli, tmp_path, *flags)
    got = mlmap.fit(train.logits, train.labels, train.objectness, classes=CLASSES, **kw)
    assert got.to_bytes() == want


@pytest.mark.parametrize("bayes", [True, False])
def test_fit_gives_the_bytes_of_the_numpy_reference(data, bayes):
    """The fit with the default settings, with and without the Bayes head: the bytes of
    the independent numpy fit of tools/mlmap_ref.py (written from docs/DESIGN.md)."""
    train = data["train"]
    classes, lml, lmap, head = mlmap_ref.fit(str(ROOT / TRAIN), bayes=bayes)
    want = mlmap_ref.encode(classes, lml, lmap, bayes=head,
                            open_=mlmap_ref.UNTUNED_OPEN if bayes else None)
    kw = {} if bayes else dict(bayes=None)
    got = mlmap.fit(train.logits, train.labels, train.objectness, classes=CLASSES, **kw)
    assert got.to_bytes() == want


def test_fit_reads_every_layout(data):
    train = data["train"]
    want = DEFAULT_TABLE.read_bytes()
    wide = np.zeros((len(train), 6))
    wide[:, 1::2] = train.logits
    for x in (train.logits, np.asfortranarray(train.logits), wide[:, 1::2]):
        for y in (train.labels, train.labels.astype(np.int8), train.labels.astype(np.int32)[::1],
                  np.stack([train.labels, train.labels], axis=1)[:, 0]):
            got = mlmap.fit(x, y, classes=CLASSES)
            assert got.to_bytes() == want
    # float32 logits are other values (the CSV's decimals rounded): another table,
    # but the same one mlmap.fit gives on their float64 copy.
    x32 = train.logits.astype(np.float32)
    assert mlmap.fit(x32, train.labels, classes=CLASSES) == mlmap.fit(
        x32.astype(np.float64), train.labels, classes=CLASSES)


def test_default_class_names(data):
    train = data["train"]
    t = mlmap.fit(train.logits, train.labels)
    assert t.classes == ["class0", "class1", "class2"]


def test_large_fit_splits_rows_and_gives_the_bytes_of_one_pass(data):
    # Above the size of one parallel range (262144 rows): ranges on both cores, merged.
    train = data["train"]
    reps = 40  # 800 000 rows
    x, y = np.tile(train.logits, (reps, 1)), np.tile(train.labels, reps)
    whole = mlmap.fit(x, y, classes=CLASSES)
    parts = [slice(0, 123_457), slice(123_457, 500_000), slice(500_000, None)]
    stats = sum(mlmap.FitStats(x[p], y[p], classes=CLASSES) for p in parts)
    edges = stats.edges()
    counts = sum(mlmap.FitCounts(edges, x[p], y[p]) for p in parts)
    assert mlmap.finish(stats, counts) == whole
    assert whole.training_rows == [reps * n for n in mlmap.fit(
        train.logits, train.labels).training_rows]


@pytest.mark.parametrize(
    "change, exc, message",
    [
        (dict(bins_ml=0), ValueError, r"^bins_ml 0 is out of range: expected "),
        (dict(lambda_map=-1.0), ValueError, r"^lambda_map -1 is out of range: expected "),
        (dict(bayes={"bins": 22, "lambda": 2.0}), ValueError, r"is out of range"),
        (dict(bayes={"bin": 3}), ValueError, r'^bayes: unknown key "bin"'),
        (dict(bayes=3), TypeError, r"^bayes: expected True, False, None or a dict"),
        (dict(edges="log"), ValueError, r"^unknown edge mode `log`: expected one of linspace, matlab$"),
        (dict(tail="one"), ValueError, r"^unknown upper tail `one`: expected one of zero, clamp$"),
        (dict(classes=["a", "b"]), ValueError, r"^classes: 2 names given but the logits have 3 columns$"),
        (dict(classes=["a", "background", "c"]), ValueError,
         r'^classes: column "background": a class cannot be named "background"'),
        (dict(classes=["a", "b", "a"]), ValueError, r'^classes: column "a": the name appears more than once$'),
        (dict(classes=["a", "b", "x" * 32]), ValueError, r"the class name is 32 bytes long"),
        (dict(classes=["a", "b\x1b[2J", "c"]), ValueError,
         r'^classes: column "b\\+u\{1b\}\[2J": not a valid class name: the name holds a control character, U\+001B, at byte 1$'),
        (dict(classes=["a", "b\n", "c"]), ValueError, r"control character, U\+000A"),
        (dict(classes=["a", "b\u202e", "c"]), ValueError, r"bidirectional formatting character, U\+202E"),
        (dict(classes=["a", "b\u2028", "c"]), ValueError, r"separator other than the space, U\+2028"),
        (dict(classes=["a", " b", "c"]), ValueError, r"the name starts or ends with a space"),
        (dict(logits=np.zeros((4, 1))), ValueError, r"^classes: found 1 class column\(s\); between 2 and 4096"),
        (dict(logits=np.array([[0.0, 1.0, 2.0]] * 3 + [[0.0, np.nan, 0.0]])), ValueError,
         r'^logits: row index 3: column "class1": "NaN" is not a finite number$'),
        (dict(logits=np.array([[0.0, 1.0, 2.0]] * 3 + [[-np.inf, 0.0, 0.0]])), ValueError,
         r'^logits: row index 3: column "class0": "-inf" is not a finite number$'),
        (dict(labels=np.array([0, 1, 2, 3])), ValueError,
         r"^labels: row index 3: label 3 is not a class index \(0 to 2\) or -1 \(background\)$"),
        (dict(labels=np.array([0, 1, 2])), ValueError, r"^labels: has 3 rows but the logits have 4$"),
        (dict(labels=np.array([0.0, 1.0, 2.0, 2.0])), ValueError, r'^labels: dtype "float64" is not supported'),
        (dict(objectness=np.array([1.0, 1.0, 1.0, -1.0])), ValueError,
         r'^objectness: row index 3: objectness "-1" is not a number in \[0, 1\]$'),
        (dict(labels=np.array([0, 0, 2, -1])), ValueError, r"class1"),  # a class without rows
    ],
)
def test_bad_input_raises_value_error(change, exc, message):
    args = dict(logits=np.array([[2.0, -1.0, 0.5], [0.0, 3.0, -1.0], [1.0, 0.0, 2.5], [0.0, 0.0, 0.0]]),
                labels=np.array([0, 1, 2, -1]), objectness=None)
    args.update(change)
    with pytest.raises(exc, match=message):
        mlmap.fit(args.pop("logits"), args.pop("labels"), args.pop("objectness"), **args)


def test_a_class_without_rows_names_it(cli, tmp_path):
    x = np.array([[2.0, -1.0, 0.5], [0.0, 3.0, -1.0], [1.0, 0.0, 2.5]])
    with pytest.raises(ValueError) as e:
        mlmap.fit(x, np.array([0, 0, 2]), classes=["a", "b", "c"])
    assert "b" in str(e.value)


# --- the mergeable statistics --------------------------------------------------------


def test_stats_pickle_and_bytes_round_trip(data):
    train = data["train"]
    s = mlmap.FitStats(train.logits, train.labels, classes=CLASSES)
    assert s.rows == len(train) and s.classes == CLASSES
    assert s.class_rows == mlmap.Table.load(DEFAULT_TABLE).training_rows
    for obj in (s, s.edges(), mlmap.FitCounts(s.edges(), train.logits, train.labels)):
        again = pickle.loads(pickle.dumps(obj))
        assert again == obj and type(again) is type(obj)
        assert type(obj).from_bytes(obj.to_bytes()).to_bytes() == obj.to_bytes()
    assert repr(s).startswith("FitStats(classes=")


def test_stats_refuse_corrupt_bytes_and_other_classes(data):
    train = data["train"]
    s = mlmap.FitStats(train.logits[:100], train.labels[:100], classes=CLASSES)
    raw = s.to_bytes()
    for bad in (b"", raw[:-1], raw[:8] + b"\xff\xff" + raw[10:], b"x" + raw[1:]):
        with pytest.raises(ValueError):
            mlmap.FitStats.from_bytes(bad)
    with pytest.raises(ValueError):
        mlmap.FitCounts.from_bytes(raw)  # statistics are not counts
    other = mlmap.FitStats(train.logits[:100], train.labels[:100], classes=["a", "b", "c"])
    with pytest.raises(ValueError):
        s + other
    with pytest.raises(TypeError):
        s + 1
    assert sum([s]) == s and s + 0 == s
    empty = mlmap.FitStats.empty(CLASSES)
    assert empty + s == s and empty.rows == 0


def test_counts_of_rows_outside_the_edges_are_refused(data):
    train = data["train"]
    small = mlmap.FitStats(train.logits[:50], train.labels[:50], classes=CLASSES)
    with pytest.raises(ValueError, match="outside the edges"):
        mlmap.FitCounts(small.edges(), train.logits, train.labels)
    # Counts of other rows than the statistics': refused at the end.
    s = mlmap.FitStats(train.logits, train.labels, classes=CLASSES)
    c = mlmap.FitCounts(s.edges(), train.logits[:1000], train.labels[:1000])
    with pytest.raises(ValueError):
        mlmap.finish(s, c)
    # The settings travel with the edges: counts over other settings' edges give that
    # fit's table.
    c = mlmap.FitCounts(s.edges(bins_ml=5), train.logits, train.labels)
    assert mlmap.finish(s, c) == mlmap.fit(train.logits, train.labels, classes=CLASSES, bins_ml=5)
    # Counts over the edges of other statistics are refused.
    other = mlmap.FitStats(train.logits[:15000], train.labels[:15000], classes=CLASSES)
    with pytest.raises(ValueError):
        mlmap.finish(s, mlmap.FitCounts.empty(other.edges()))
    assert s.finish(mlmap.FitCounts(s.edges(), train.logits, train.labels)).to_bytes() == \
        DEFAULT_TABLE.read_bytes()


def merge_tree(items, order, splits):
    """Merges `items` in the order `order`, grouped as a random binary tree."""
    items = [items[i] for i in order]
    while len(items) > 1:
        i = splits.draw(st.integers(0, len(items) - 2))
        items[i : i + 2] = [items[i] + items[i + 1]]
    return items[0]


SUBSET = None


def subset(data):
    global SUBSET
    if SUBSET is None:
        t = data["train"]
        pick = np.random.default_rng(3).choice(len(t), 3000, replace=False)
        SUBSET = (t.logits[pick], t.labels[pick])
    return SUBSET


@settings(max_examples=40, deadline=None)
@given(split=st.data(), edges=st.sampled_from(["linspace", "matlab"]),
       bayes=st.sampled_from([True, None]), via_bytes=st.booleans())
def test_any_split_and_merge_order_gives_the_bytes_of_one_fit(data, split, edges, bayes, via_bytes):
    x, y = subset(data)
    n = len(y)
    cuts = sorted(split.draw(st.lists(st.integers(1, n - 1), min_size=0, max_size=7, unique=True)))
    shards = [slice(a, b) for a, b in zip([0] + cuts, cuts + [n])]
    ship = (lambda o: pickle.loads(pickle.dumps(o))) if via_bytes else (lambda o: o)
    stats = [ship(mlmap.FitStats(x[s], y[s], classes=CLASSES)) for s in shards]
    order = split.draw(st.permutations(range(len(shards))))
    merged = merge_tree(stats, order, split)
    e = ship(merged.edges(edges=edges, bayes=bayes))
    counts = [ship(mlmap.FitCounts(e, x[s], y[s])) for s in shards]
    order = split.draw(st.permutations(range(len(shards))))
    table = mlmap.finish(merged, merge_tree(counts, order, split))
    want = mlmap.fit(x, y, classes=CLASSES, edges=edges, bayes=bayes)
    assert table.to_bytes() == want.to_bytes()


# --- tune ----------------------------------------------------------------------------


def test_tune_gives_the_table_and_report_of_mlmap_tune(data, cli, tmp_path):
    out = tmp_path / "tuned.mlmap"
    report = json.loads(cli(
        "tune", "--train", TRAIN, "--val", "examples/data/val.csv", "--ood",
        "examples/data/ood.csv", "--bins-ml", "8,16,22", "--bins-map", "8,17",
        "--bins-bayes", "10,22", "--lambdas-per-decade", "1", "--format", "json",
        "--output", out))
    tr, val, ood = data["train"], data["val"], data["ood"]
    table, got = mlmap.tune(
        tr.logits, tr.labels, (val.logits, val.labels, val.objectness), tr.objectness,
        ood=(ood.logits, None, ood.objectness), classes=CLASSES,
        bins_ml=[8, 16, 22], bins_map=[8, 17], bins_bayes=[10, 22], lambdas_per_decade=1)
    assert table.to_bytes() == out.read_bytes()
    del report["table"]
    assert got == report


def test_tune_refuses_bad_settings(data):
    tr, val = data["train"], data["val"]
    args = (tr.logits, tr.labels, (val.logits, val.labels))
    with pytest.raises(ValueError, match="^lambda_min/lambda_max: "):
        mlmap.tune(*args, classes=CLASSES, lambda_min=1.0, lambda_max=0.1)
    with pytest.raises(ValueError, match="^bins_ml: bin counts must be in"):
        mlmap.tune(*args, classes=CLASSES, bins_ml=[0])
    with pytest.raises(ValueError, match="^unknown objective `auc`"):
        mlmap.tune(*args, classes=CLASSES, objective="auc")
    with pytest.raises(ValueError, match="^max_accuracy_loss must be a number >= 0"):
        mlmap.tune(*args, classes=CLASSES, max_accuracy_loss=-1.0)
    with pytest.raises(ValueError, match=r"^val\.labels: row index 0: label 5 is not a class index"):
        mlmap.tune(tr.logits, tr.labels, (val.logits, np.full(len(val), 5)))
    with pytest.raises(ValueError, match=r"^val\.logits: has 2 columns but there are 3 classes"):
        mlmap.tune(tr.logits, tr.labels, (val.logits[:, :2], val.labels))


def test_float32_arrays_give_the_bytes_of_mlmap_fit_on_an_npy_directory(data, cli, tmp_path):
    # The CLI reads a float32 logits.npy as the same f64 values the package reads.
    train = data["train"]
    d = tmp_path / "npy"
    d.mkdir()
    x32 = train.logits.astype(np.float32)
    np.save(d / "logits.npy", x32)
    np.save(d / "labels.npy", train.labels.astype(np.int32))
    np.save(d / "objectness.npy", train.objectness.astype(np.float32))
    (d / "classes.txt").write_text("\n".join(CLASSES) + "\n")
    out = tmp_path / "npy.mlmap"
    cli("fit", "--train", d, "--edges", "matlab", "--output", out)
    got = mlmap.fit(x32, train.labels.astype(np.int32), train.objectness.astype(np.float32),
                    classes=CLASSES, edges="matlab")
    assert got.to_bytes() == out.read_bytes()
