"""pandas DataFrames and class-name labels in `fit`, `tune` and `evaluate` (the golden
values: `mlmap fit`, `tune` and `eval` on the same CSV files, whose labels are class
names), the table size warning, and `Table.from_bytes` on every kind of buffer."""

import json
import mmap
import subprocess
import sys
import warnings

import numpy as np
import pytest

import mlmap
from conftest import DEFAULT_TABLE, ROOT

pd = pytest.importorskip("pandas")

DATA = ROOT / "examples" / "data"


def frame(name):
    """A data file as pandas reads it: logits as a DataFrame (columns = class names),
    labels as strings, objectness as a Series."""
    df = pd.read_csv(DATA / f"{name}.csv")
    return df[["car", "cyclist", "pedestrian"]], df["label"], df["objectness"]


def test_fit_on_a_dataframe_with_string_labels_gives_the_bytes_of_mlmap_fit(cli, tmp_path):
    out = tmp_path / "t.mlmap"
    cli("fit", "--train", DATA / "train.csv", "--output", out)
    x, y, o = frame("train")
    table = mlmap.fit(x, y, o)
    assert table.classes == ["car", "cyclist", "pedestrian"]
    assert table.to_bytes() == out.read_bytes()
    # A pandas Categorical and a numpy array of str: the same labels.
    assert mlmap.fit(x, y.astype("category"), o).to_bytes() == out.read_bytes()
    assert mlmap.fit(x, y.to_numpy(dtype=str)).to_bytes() == out.read_bytes()


def test_columns_name_the_classes_in_their_order(cli, tmp_path):
    x, y, o = frame("train")
    # Reordered columns: other class indices, same class names.
    table = mlmap.fit(x[["pedestrian", "car", "cyclist"]], y)
    assert table.classes == ["pedestrian", "car", "cyclist"]
    want = mlmap.fit(x.to_numpy()[:, [2, 0, 1]],
                     y.map({"pedestrian": 0, "car": 1, "cyclist": 2}).fillna(-1).astype(int),
                     classes=["pedestrian", "car", "cyclist"])
    assert table.to_bytes() == want.to_bytes()


def test_integer_labels_keep_working_with_a_dataframe():
    x, y, _ = frame("train")
    idx = y.map({"car": 0, "cyclist": 1, "pedestrian": 2}).fillna(-1).astype(np.int64)
    assert mlmap.fit(x, idx).to_bytes() == mlmap.fit(x, y).to_bytes()


def test_unknown_labels_and_disagreeing_classes_are_clear_errors():
    x, y, _ = frame("train")
    bad = y.copy()
    bad.iloc[5] = "truck"
    with pytest.raises(ValueError, match=r"row index 5: label 'truck' is not a class name "
                                         r"\(car, cyclist, pedestrian\) or 'background'"):
        mlmap.fit(x, bad)
    with pytest.raises(ValueError, match="differ from the DataFrame's columns"):
        mlmap.fit(x, y, classes=["a", "b", "c"])
    # Array logits name their classes by `classes=` (or class0 ..).
    with pytest.raises(ValueError, match=r"label 'car' is not a class name \(class0"):
        mlmap.fit(x.to_numpy(), y)
    assert mlmap.fit(x.to_numpy(), y, classes=["car", "cyclist", "pedestrian"]) == mlmap.fit(x, y)
    with pytest.raises(ValueError, match="labels: has 3 rows"):
        mlmap.fit(x, y[:3])


def test_background_dataframe_must_have_the_same_columns():
    x, y, _ = frame("train")
    bg, _, _ = frame("ood")
    table = mlmap.fit(x, y, background=bg)
    assert table == mlmap.fit(x.to_numpy(), y, classes=list(x.columns), background=bg.to_numpy())
    with pytest.raises(ValueError, match="background: the DataFrame's columns"):
        mlmap.fit(x, y, background=bg[["cyclist", "car", "pedestrian"]])


def test_evaluate_on_dataframes_equals_mlmap_eval(cli):
    want = json.loads(cli("eval", "--table", DEFAULT_TABLE, "--format", "json",
                          "--test", "examples/data/test.csv", "--val", "examples/data/val.csv",
                          "--ood", "examples/data/ood.csv"))
    table = mlmap.Table.load(DEFAULT_TABLE)
    x, y, o = frame("test")
    vx, vy, vo = frame("val")
    ox, _, oo = frame("ood")
    got = mlmap.evaluate(table, x, y, o, val=(vx, vy, vo), ood=(ox, None, oo))
    assert got == want
    with pytest.raises(ValueError, match="classes"):
        mlmap.evaluate(table, x[["cyclist", "car", "pedestrian"]], y, o)


def test_tune_on_dataframes_equals_tune_on_arrays():
    x, y, o = frame("train")
    vx, vy, vo = frame("val")
    kw = dict(bins_ml=[8, 22], bins_map=[17], bins_bayes=[22], lambdas_per_decade=1)
    table, report = mlmap.tune(x, y, (vx, vy, vo), o, **kw)
    idx = {"car": 0, "cyclist": 1, "pedestrian": 2}
    ya = y.map(idx).fillna(-1).astype(int).to_numpy()
    vya = vy.map(idx).fillna(-1).astype(int).to_numpy()
    t2, r2 = mlmap.tune(x.to_numpy(), ya, (vx.to_numpy(), vya, vo.to_numpy()), o.to_numpy(),
                        classes=list(idx), **kw)
    assert table == t2 and report == r2
    assert table.classes == list(idx)


def test_calibrator_uses_the_same_label_mapping():
    x, y, _ = frame("train")
    cal = mlmap.Calibrator(head="ml").fit(x, y)
    assert list(cal.classes_) == ["car", "cyclist", "pedestrian"]
    assert cal.table_ == mlmap.fit(x, y)


def test_mlmap_works_without_pandas():
    # pandas made unimportable: arrays, string labels and the Calibrator still work.
    code = ("import sys; sys.modules['pandas'] = None; import mlmap, numpy as np; "
            "x = np.random.default_rng(0).normal(size=(200, 2)); "
            "y = np.array(['a', 'b'])[np.arange(200) % 2]; "
            "t = mlmap.fit(x, y, classes=['a', 'b']); assert t.classes == ['a', 'b']; "
            "mlmap.Calibrator(head='ml').fit(x, np.arange(200) % 2)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT / "target")
    assert done.returncode == 0, done.stderr


# --- the size warning -----------------------------------------------------------------


def many_classes(k, n_per=12, seed=0):
    rng = np.random.default_rng(seed)
    y = np.repeat(np.arange(k), n_per)
    x = rng.normal(size=(len(y), k)).astype(np.float32)
    x[np.arange(len(y)), y] += 3.0
    return x, y


def test_a_large_table_warns_and_says_how_to_shrink_it():
    x, y = many_classes(200)
    with pytest.warns(mlmap.TableSizeWarning, match=r"above 1 MiB; to shrink it, fit with "
                                                    r"bayes=False") as rec:
        table = mlmap.fit(x, y)
    assert table.size > mlmap.TABLE_SIZE_WARNING
    assert issubclass(mlmap.TableSizeWarning, UserWarning)
    # Attributed to the caller's line, not to mlmap's wrapper.
    assert rec[0].filename == __file__
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        small = mlmap.fit(x, y, bayes=False)
    assert small.size < mlmap.TABLE_SIZE_WARNING


def test_a_small_table_does_not_warn():
    x, y, _ = frame("train")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mlmap.fit(x, y)


# --- from_bytes on buffers ------------------------------------------------------------


def test_from_bytes_reads_every_contiguous_buffer(tmp_path):
    data = DEFAULT_TABLE.read_bytes()
    want = mlmap.Table.from_bytes(data)
    arr = np.frombuffer(data, dtype=np.uint8).copy()
    for buf in (bytearray(data), memoryview(data), arr, memoryview(arr), arr.reshape(1, -1)):
        assert mlmap.Table.from_bytes(buf) == want
    with open(DEFAULT_TABLE, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
        assert mlmap.Table.from_bytes(m) == want
    # The same for the fit statistics' bytes.
    x, y, _ = frame("train")
    stats = mlmap.FitStats(x.to_numpy(), y.map({"car": 0, "cyclist": 1, "pedestrian": 2})
                           .fillna(-1).astype(int).to_numpy(), classes=list(x.columns))
    assert mlmap.FitStats.from_bytes(bytearray(stats.to_bytes())) == stats


def test_from_bytes_refuses_non_contiguous_and_wide_buffers():
    data = DEFAULT_TABLE.read_bytes()
    doubled = np.frombuffer(data, dtype=np.uint8).repeat(2)
    with pytest.raises(TypeError, match="not contiguous"):
        mlmap.Table.from_bytes(doubled[::2])
    with pytest.raises(TypeError, match="not contiguous"):
        mlmap.Table.from_bytes(memoryview(doubled)[::2])
    with pytest.raises(TypeError, match="2-byte items"):
        mlmap.Table.from_bytes(np.zeros(8, dtype=np.uint16))
    with pytest.raises(TypeError, match="not str"):
        mlmap.Table.from_bytes("abc")
