"""examples/dask_fit.py: 8 shards fitted on a LocalCluster of 2 worker processes give
the bytes of one process's `mlmap.fit` and of `mlmap fit`."""

import importlib.util

import numpy as np
import pytest

import mlmap
from conftest import CLASSES, DEFAULT_TABLE, ROOT

distributed = pytest.importorskip("dask.distributed")


@pytest.fixture(scope="module")
def dask_fit():
    spec = importlib.util.spec_from_file_location("dask_fit", ROOT / "examples" / "dask_fit.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, env={"RAYON_NUM_THREADS": "1"}) as c, \
            distributed.Client(c) as client:
        yield client


@pytest.mark.parametrize("settings, flags", [
    ({}, []),
    (dict(bayes=None, edges="matlab"), ["--no-bayes", "--edges", "matlab"]),
])
def test_dask_fit_equals_one_process_and_the_cli(dask_fit, client, data, cli, tmp_path,
                                                 settings, flags):
    shards = dask_fit.write_shards(tmp_path / "shards", parts=8)
    assert len(shards) == 8
    assert len(client.scheduler_info()["workers"]) == 2
    table = dask_fit.fit_shards(client, shards, **settings)
    train = data["train"]
    assert table == mlmap.fit(train.logits, train.labels, classes=CLASSES, **settings)
    out = tmp_path / "cli.mlmap"
    cli("fit", "--train", "examples/data/train.csv", *flags, "--output", out)
    assert table.to_bytes() == out.read_bytes()
    if not settings:
        assert table.to_bytes() == DEFAULT_TABLE.read_bytes()


def test_dask_fit_of_uneven_shards(dask_fit, client, data, tmp_path):
    # Shards of very different sizes (one of a single row), in a scrambled order.
    train = data["train"]
    cuts = [0, 1, 7, 5000, 5001, 12000, len(train)]
    shards = []
    for i, (a, b) in enumerate(zip(cuts, cuts[1:])):
        p = tmp_path / f"s{i}"
        p.mkdir()
        np.save(p / "logits.npy", train.logits[a:b])
        np.save(p / "labels.npy", train.labels[a:b].astype(np.int16))
        (p / "classes.txt").write_text("\n".join(CLASSES) + "\n")
        shards.append(p)
    shards = [shards[i] for i in (3, 0, 5, 1, 4, 2)]
    assert dask_fit.fit_shards(client, shards).to_bytes() == DEFAULT_TABLE.read_bytes()
