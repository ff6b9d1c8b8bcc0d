"""`mlmap.Evaluator`: `evaluate`'s metrics shard by shard (equal to the one-shot
`evaluate`, which equals `mlmap eval`), merged in any order, through pickling and Dask;
`report_frame`."""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import mlmap
from conftest import DEFAULT_TABLE

# The sums are compensated but added in another order: equal within this.
SUM_TOL = 1e-12
# auroc and ap_<class> count scores within 1 / rank_levels of each other as tied.
RANK_KEYS = ("auroc",)


@pytest.fixture(scope="session")
def table():
    return mlmap.Table.load(DEFAULT_TABLE)


def assert_close(got, want, rank_tol):
    assert got["rows"] == want["rows"] and got["classes"] == want["classes"]
    assert got["ece_bins"] == want["ece_bins"] and got["ece_binning"] == want["ece_binning"]
    for method, values in got["methods"].items():
        for key, v in values.items():
            w = want["methods"][method][key]
            if v is None or w is None:
                assert v == w, (method, key)
                continue
            tol = rank_tol if key in RANK_KEYS or key.startswith("ap_") else SUM_TOL
            assert abs(v - w) <= tol, (method, key, v, w)


def test_shards_equal_the_one_shot_evaluate(table, data):
    t = data["test"]
    want = mlmap.evaluate(table, t.logits, t.labels, t.objectness, ece_bins=15)
    shards = np.array_split(np.arange(len(t)), 7)
    evs = []
    for idx in shards:
        ev = mlmap.Evaluator(table, ece_bins=15)
        ev.update(t.logits[idx], t.labels[idx], t.objectness[idx])
        evs.append(ev)
    got = sum(evs).report()
    assert list(got["methods"]) == ["sigmoid", "softmax", "ml", "map", "bayes", "open"]
    assert got["rank_levels"] == 65536
    assert_close(got, want, rank_tol=1e-4)
    # Finer levels: closer ranks.
    fine = mlmap.Evaluator(table, ece_bins=15, rank_levels=1 << 20)
    fine.update(t.logits, t.labels, t.objectness)
    assert_close(fine.report(), want, rank_tol=1e-5)


def test_scores_on_the_levels_give_exact_ranks(table):
    # Logits of three values: the sigmoid and ML scores repeat exactly and lie far
    # apart, so the levels rank them as evaluate does (softmax, MAP and Bayes values of
    # permuted logits differ in their last bits, which evaluate ranks apart and the
    # levels tie).
    rng = np.random.default_rng(1)
    x = rng.choice([-2.0, 0.0, 2.0], size=(500, 3))
    y = rng.integers(-1, 3, 500)
    want = mlmap.evaluate(table, x, y)
    ev = mlmap.Evaluator(table, rank_levels=1 << 20)
    ev.update(x, y)
    got = ev.report()
    for m in ("sigmoid", "ml"):
        for key in ("auroc", "ap_car", "ap_cyclist", "ap_pedestrian"):
            assert abs(got["methods"][m][key] - want["methods"][m][key]) <= 1e-6


def test_temperature_and_binning(table, data):
    t = data["test"]
    want = mlmap.evaluate(table, t.logits, t.labels, t.objectness, ece_binning="netcal")
    ev = mlmap.Evaluator(table, ece_binning="netcal", temperature=1.0)
    ev.update(t.logits, t.labels, t.objectness)
    got = ev.report()
    assert got["ece_binning"] == "netcal"
    for m in ("sigmoid", "softmax", "ml", "map", "bayes", "open"):
        for key in ("ece", "mce", "nll", "brier", "accuracy"):
            assert abs(got["methods"][m][key] - want["methods"][m][key]) <= SUM_TOL
    # T = 1 is the softmax itself.
    assert got["methods"]["temperature"]["ece"] == pytest.approx(
        got["methods"]["softmax"]["ece"], abs=SUM_TOL)


@settings(max_examples=15, deadline=None)
@given(st.data())
def test_any_split_and_merge_order_gives_the_same_report(table, data, hyp):
    t = data["test"]
    n = 600
    cuts = sorted(hyp.draw(st.lists(st.integers(0, n), max_size=5)))
    bounds = [0, *cuts, n]
    evs = []
    for a, b in zip(bounds, bounds[1:]):
        ev = mlmap.Evaluator(table)
        ev.update(t.logits[a:b], t.labels[a:b], t.objectness[a:b])
        evs.append(pickle.loads(pickle.dumps(ev)) if hyp.draw(st.booleans()) else ev)
    order = hyp.draw(st.permutations(range(len(evs))))
    merged = sum(evs[i] for i in order)
    one = mlmap.Evaluator(table)
    one.update(t.logits[:n], t.labels[:n], t.objectness[:n])
    got, want = merged.report(), one.report()
    assert merged.rows == n
    # Counts merge exactly: every rank metric and count-based metric is equal.
    for m, values in want["methods"].items():
        for key, w in values.items():
            g = got["methods"][m][key]
            assert (g is None) == (w is None)
            if w is not None:
                assert abs(g - w) <= SUM_TOL, (m, key)


def test_large_update_is_split_and_checked(table):
    rng = np.random.default_rng(2)
    n = 200_000
    x = rng.normal(size=(n, 3)).astype(np.float32)
    y = rng.integers(-1, 3, n)
    ev = mlmap.Evaluator(table)
    ev.update(x, y)
    small = mlmap.Evaluator(table)
    for a in range(0, n, 50_000):
        small.update(x[a:a + 50_000], y[a:a + 50_000])
    assert_close(ev.report(), small.report(), rank_tol=0.0)
    bad = y.copy()
    bad[150_000] = 7
    with pytest.raises(ValueError, match="rows 131072 .. 196608"):
        mlmap.Evaluator(table).update(x, bad)
    with pytest.raises(ValueError, match="labels: has 3 rows"):
        mlmap.Evaluator(table).update(x, y[:3])


def test_empty_shards_bad_settings_and_mismatched_merges(table, data):
    t = data["test"]
    ev = mlmap.Evaluator(table)
    ev.update(np.zeros((0, 3)), np.zeros(0, dtype=np.int64))
    assert ev.rows == 0
    with pytest.raises(ValueError, match="no rows"):
        ev.report()
    with pytest.raises(ValueError, match="3 classes"):
        ev.update(np.zeros((2, 2)), np.zeros(2, dtype=np.int64))
    with pytest.raises(ValueError, match="rank_levels"):
        mlmap.Evaluator(table, rank_levels=0)
    with pytest.raises(ValueError, match="ece_bins"):
        mlmap.Evaluator(table, ece_bins=0)
    with pytest.raises(ValueError, match="temperature"):
        mlmap.Evaluator(table, temperature=-1.0)
    with pytest.raises(ValueError, match="bins"):
        mlmap.Evaluator(table) + mlmap.Evaluator(table, ece_bins=12)
    with pytest.raises(TypeError):
        mlmap.Evaluator(table) + 1
    with pytest.raises(ValueError, match="not the bytes of an mlmap.Evaluator"):
        mlmap.Evaluator.from_bytes(mlmap.Evaluator(table).to_bytes()[:-3])
    ev.update(t.logits[:10], t.labels[:10])
    data_bytes = bytearray(ev.to_bytes())
    data_bytes[-2] ^= 1
    with pytest.raises(ValueError, match="not the bytes"):
        mlmap.Evaluator.from_bytes(bytes(data_bytes))


def test_on_dask_like_the_fit(table, data):
    dask = pytest.importorskip("dask")
    import dask.array as da  # noqa: F401

    t = data["test"]
    shards = np.array_split(np.arange(len(t)), 4)

    def shard(idx):
        ev = mlmap.Evaluator(table)
        ev.update(t.logits[idx], t.labels[idx], t.objectness[idx])
        return ev

    parts = [dask.delayed(shard)(idx) for idx in shards]
    total = dask.delayed(sum)(parts).compute(scheduler="processes", num_workers=2)
    one = mlmap.Evaluator(table)
    one.update(t.logits, t.labels, t.objectness)
    assert_close(total.report(), one.report(), rank_tol=0.0)


def test_report_frame(table, data):
    pd = pytest.importorskip("pandas")
    t = data["test"]
    report = mlmap.evaluate(table, t.logits, t.labels, t.objectness)
    df = mlmap.report_frame(report)
    assert isinstance(df, pd.DataFrame)
    assert list(df.index) == list(report["methods"])
    assert df.loc["ml", "ece"] == report["methods"]["ml"]["ece"]
    assert np.isnan(df.loc["energy", "ece"])
    ev = mlmap.Evaluator(table)
    ev.update(t.logits, t.labels, t.objectness)
    assert list(mlmap.report_frame(ev.report()).index) == [
        "sigmoid", "softmax", "ml", "map", "bayes", "open"]
