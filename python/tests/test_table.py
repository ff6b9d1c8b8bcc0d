"""`mlmap.Table`: bytes, files, pickling, properties, scores within 1e-6 of the independent
numpy reference (tools/mlmap_ref.py) and bit for bit equal to `mlmap apply` (the device's
f32 code), in every array layout."""

import csv
import pickle
import sys

import numpy as np
import pytest

import mlmap
from conftest import CLASSES, DEFAULT_TABLE, ROOT

sys.path.insert(0, str(ROOT / "tools"))
import mlmap_ref  # noqa: E402  (the independent numpy implementation)


@pytest.fixture(scope="session")
def table():
    return mlmap.Table.load(DEFAULT_TABLE)


@pytest.fixture(scope="session")
def applied(cli, tmp_path_factory):
    """`mlmap apply` of the shipped table on the test split: per head, the (N, K)
    float32 scores and the predicted class names."""
    out = tmp_path_factory.mktemp("apply") / "scores.csv"
    cli("apply", "--table", DEFAULT_TABLE, "--input", "examples/data/test.csv", "--output", out)
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    got = {}
    for head in mlmap.HEADS:
        # Each score is written as the shortest decimal that reads back as its f32.
        got[head] = np.array(
            [[np.float32(r[f"{head}_{c}"]) for c in CLASSES] for r in rows], dtype=np.float32
        )
        got[head + "_pred"] = np.array([CLASSES.index(r[f"{head}_pred"]) for r in rows])
    return got


def layouts(x):
    """The same matrix as float64 and float32, C order, Fortran order, and a strided
    view of a larger array."""
    wide = np.zeros((x.shape[0], 2 * x.shape[1]))
    wide[:, ::2] = x
    return {
        "f64-C": np.ascontiguousarray(x, dtype=np.float64),
        "f32-C": np.ascontiguousarray(x, dtype=np.float32),
        "f64-F": np.asfortranarray(x, dtype=np.float64),
        "f32-F": np.asfortranarray(x, dtype=np.float32),
        "f64-strided": wide[:, ::2],
        "f32-strided": wide.astype(np.float32)[:, ::2],
        "f16": x.astype(np.float16).astype(np.float64),  # the reference for the next
    }


REFERENCE = {"ml": mlmap_ref.ml, "map": mlmap_ref.map_, "bayes": mlmap_ref.bayes,
             "open": mlmap_ref.open_}


@pytest.mark.parametrize("head", mlmap.HEADS)
def test_scores_equal_the_numpy_reference(table, data, head):
    """Each head within 1e-6 of the float64 reference of tools/mlmap_ref.py, written from
    docs/DESIGN.md without the crate's code, on 2000 rows of the test split."""
    ref = mlmap_ref.decode(DEFAULT_TABLE.read_bytes())
    # The layer scores float32 logits and objectness: give the reference the same values.
    x = data["test"].logits[:2000].astype(np.float32).astype(np.float64)
    os32 = data["test"].objectness[:2000].astype(np.float32)
    got = table.scores(head, x, os32)
    want = np.array([REFERENCE[head](ref, row, float(o)) for row, o in zip(x, os32)])
    assert np.abs(got - want).max() <= 1e-6


@pytest.mark.parametrize("head", mlmap.HEADS)
def test_scores_equal_mlmap_apply_bit_for_bit(table, data, applied, head):
    test = data["test"]
    for name, x in layouts(test.logits).items():
        if name == "f16":
            continue
        for os in (test.objectness, test.objectness.astype(np.float32), np.asfortranarray(
                np.stack([test.objectness, test.objectness], axis=1))[:, 0]):
            got = table.scores(head, x, os)
            assert got.dtype == np.float32 and got.shape == (len(test), 3)
            # Bit-for-bit: compare the integer views, so -0.0 / 0.0 would differ too.
            assert np.array_equal(got.view(np.uint32), applied[head].view(np.uint32)), name
    assert np.array_equal(getattr(table, head)(test.logits, test.objectness), applied[head])


def test_other_float_dtypes_are_read_as_float64(table, data):
    x = data["test"].logits[:100]
    h = x.astype(np.float16)
    assert np.array_equal(table.ml(h), table.ml(h.astype(np.float64)))
    assert np.array_equal(table.map(x.tolist()), table.map(x))


@pytest.mark.parametrize("head", mlmap.HEADS)
def test_decisions_equal_mlmap_apply(table, data, applied, head):
    test = data["test"]
    scores = table.scores(head, test.logits.astype(np.float32), test.objectness)
    got = mlmap.decide(scores, test.logits.astype(np.float32))
    assert got.dtype == np.int64
    assert np.array_equal(got, applied[head + "_pred"])


def test_decide_breaks_exact_ties_by_the_logits():
    scores = np.array([[0.25, 0.25, 0.25], [0.2, 0.7, 0.1], [0.5, 0.5, 0.0]])
    logits = np.array([[-1.0, 3.0, 2.0], [0.0, -9.0, 0.0], [1.0, 1.0, 5.0]])
    assert mlmap.decide(scores, logits).tolist() == [1, 1, 0]
    with pytest.raises(ValueError, match="shape"):
        mlmap.decide(scores, logits[:2])


def test_large_inputs_score_in_parallel_as_in_small_batches(table):
    # Above the parallel threshold (65536 rows), in chunks: the same bits as scoring
    # small batches on one thread, and the error of the lowest bad row.
    rng = np.random.default_rng(7)
    n = 200_003
    x = rng.normal(0.0, 4.0, size=(n, 3)).astype(np.float32)
    os = rng.uniform(0.0, 1.0, size=n)
    for head in mlmap.HEADS:
        whole = table.scores(head, x, os)
        parts = np.concatenate(
            [table.scores(head, x[i : i + 5000], os[i : i + 5000]) for i in range(0, n, 5000)]
        )
        assert np.array_equal(whole, parts)
    x[150_001, 2] = np.nan
    x[70_000, 1] = np.nan
    with pytest.raises(ValueError, match=r"^logits: row index 70000: logit of class 1 is NaN$"):
        table.ml(x)


def test_empty_input_gives_empty_scores(table):
    assert table.ml(np.zeros((0, 3))).shape == (0, 3)


def test_infinite_logits_are_valid_and_unseen_logits_get_os_over_k(table):
    # DESIGN §1.2/§1.3: +-inf is a valid input; outside every histogram ML and MAP
    # answer exactly OS / K.
    x = np.array([[np.inf, -np.inf, 1e30], [-50.0, -50.0, -50.0]])
    for os in (1.0, 0.6):
        for head in ("ml", "map"):
            got = table.scores(head, x, os)
            assert np.array_equal(got, np.full((2, 3), np.float32(os) / np.float32(3)))


def test_bytes_round_trip(table):
    raw = DEFAULT_TABLE.read_bytes()
    assert table.to_bytes() == raw
    again = mlmap.Table.from_bytes(raw)
    assert again == table and hash(again) == hash(table)
    assert mlmap.Table.from_bytes(bytearray(raw)) == table
    assert table.size == len(raw)


def test_save_and_load(table, tmp_path):
    path = tmp_path / "t.mlmap"
    table.save(path)
    assert path.read_bytes() == DEFAULT_TABLE.read_bytes()
    assert mlmap.Table.load(str(path)) == table
    assert [p.name for p in tmp_path.iterdir()] == ["t.mlmap"]  # no temporary file left


def test_pickle(table):
    for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
        again = pickle.loads(pickle.dumps(table, protocol=protocol))
        assert isinstance(again, mlmap.Table)
        assert again.to_bytes() == table.to_bytes()
    assert table != table.to_bytes() and table != object()


def test_properties_equal_mlmap_inspect(table, inspect):
    info = inspect(DEFAULT_TABLE)
    assert table.classes == [c["name"] for c in info["classes"]] == CLASSES
    assert table.k == 3
    assert table.heads == ("ml", "map", "bayes", "open")
    assert table.open_params == {"temperature": info["open"]["temperature"],
                                 "epsilon": info["open"]["epsilon"]}
    assert (table.bins_ml, table.bins_map, table.bins_bayes) == (
        info["bins_ml"], info["bins_map"], info["bayes"]["bins"])
    assert table.lambda_ml == info["lambda_ml"] and table.lambda_map == info["lambda_map"]
    assert table.lambda_bayes == info["bayes"]["lambda"]
    assert table.edges == info["edge_mode"] and table.upper_tail == info["upper_tail"]
    assert table.training_rows == [c["rows"] for c in info["classes"]]
    assert table.categories == CLASSES + ["background"]
    for i, c in enumerate(info["classes"]):
        assert table.priors[i] == (c["prior"]["mean"], c["prior"]["variance"])
        for head in ("ml", "map"):
            edges, freqs = table.histogram(head, i)
            assert edges.tolist() == c[head]["edges"]
            assert freqs.tolist() == c[head]["frequencies"]
            by_name = table.histogram(head, c["name"])
            assert np.array_equal(by_name[0], edges)
    assert repr(table).startswith("Table(classes=['car', 'cyclist', 'pedestrian'], bins=(ml=22")
    assert "open=(temperature=1.0, epsilon=0.0)" in repr(table)


def test_histogram_refuses_bad_arguments(table):
    with pytest.raises(ValueError, match="not a class"):
        table.histogram("ml", "truck")
    with pytest.raises(ValueError, match=r"class index 3 is not in 0\.\.3"):
        table.histogram("ml", 3)
    with pytest.raises(ValueError, match="Bayes head"):
        table.histogram("bayes", 0)


# --- bad input -------------------------------------------------------------------


@pytest.mark.parametrize(
    "logits, message",
    [
        (np.zeros(3), r"^logits: shape \(3,\) is not \(N, K\)"),
        (np.zeros((2, 3, 1)), r"^logits: shape \(2, 3, 1\) is not \(N, K\)"),
        (np.zeros((2, 4)), r"^logits: has 4 columns; the table has 3 classes \(car, cyclist, pedestrian\)$"),
        (np.zeros((2, 3), dtype=np.int64), r'^logits: dtype "int64" is not supported; expected float32 or float64$'),
        (np.zeros((2, 3), dtype=bool), r'dtype "bool" is not supported'),
        (np.zeros((2, 3), dtype=np.complex64), r'dtype "complex64" is not supported'),
        (np.array([["a", "b", "c"]]), r'dtype "<U1" is not supported'),
        (np.array([[0.0, np.nan, 1.0]]), r"^logits: row index 0: logit of class 1 is NaN$"),
    ],
)
def test_bad_logits_raise_value_error(table, logits, message):
    for head in mlmap.HEADS:
        with pytest.raises(ValueError, match=message):
            table.scores(head, logits)


@pytest.mark.parametrize(
    "objectness, message",
    [
        (1.5, r'^objectness: objectness "1\.5" is not a number in \[0, 1\]$'),
        (-0.0001, r'objectness "-0\.0001" is not a number'),
        (np.array([0.5, np.nan]), r'^objectness: row index 1: objectness "NaN" is not a number in \[0, 1\]$'),
        (np.array([0.5, 2.0], dtype=np.float32), r"^objectness: row index 1: objectness \"2\""),
        (np.array([0.5]), r"^objectness: has 1 rows but the logits have 2$"),
        (np.ones((2, 1)), r"^objectness: shape \(2, 1\) is not \(N,\)"),
        (np.ones(2, dtype=np.int32), r'^objectness: dtype "int32" is not supported'),
    ],
)
def test_bad_objectness_raises_value_error(table, objectness, message):
    with pytest.raises(ValueError, match=message):
        table.ml(np.zeros((2, 3)), objectness)


def test_bayes_of_a_table_without_that_head(cli, tmp_path):
    path = tmp_path / "nob.mlmap"
    cli("fit", "--train", "examples/data/train.csv", "--no-bayes", "--output", path)
    t = mlmap.Table.load(path)
    assert t.heads == ("ml", "map") and t.bins_bayes is None and t.categories is None
    assert t.open_params is None
    with pytest.raises(ValueError, match="^the table has no Bayes head$"):
        t.bayes(np.zeros((1, 3)))
    with pytest.raises(ValueError, match="^the table has no open head$"):
        t.open(np.zeros((1, 3)))
    with pytest.raises(ValueError, match="^unknown head `softmax`: expected one of ml, map, bayes, open$"):
        t.scores("softmax", np.zeros((1, 3)))


def test_corrupt_tables_raise_table_error(tmp_path):
    raw = DEFAULT_TABLE.read_bytes()
    assert issubclass(mlmap.TableError, ValueError)
    cases = {
        b"": "input is too short to be an mlmap table",
        b"JUNK" + raw[4:]: "input does not start with the mlmap magic `MLMP`",
        raw[:-1]: None,
        raw + b"\0": None,
    }
    for bad, message in cases.items():
        with pytest.raises(mlmap.TableError) as e:
            mlmap.Table.from_bytes(bad)
        if message:
            assert str(e.value) == message
    # Every single-byte change is refused (the CRC covers every byte).
    for i in range(len(raw)):
        bad = bytearray(raw)
        bad[i] ^= 0x5A
        with pytest.raises(mlmap.TableError):
            mlmap.Table.from_bytes(bytes(bad))
    path = tmp_path / "bad.mlmap"
    path.write_bytes(raw[:100])
    with pytest.raises(mlmap.TableError, match=r"bad\.mlmap: table checksum does not match"):
        mlmap.Table.load(path)
    with pytest.raises(FileNotFoundError, match=r"missing\.mlmap: No such file"):
        mlmap.Table.load(tmp_path / "missing.mlmap")
    with pytest.raises(TypeError):
        mlmap.Table.from_bytes("not bytes")
