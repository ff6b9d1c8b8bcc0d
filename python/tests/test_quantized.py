"""`Table.quantized_scores`: int8 / int16 codes through the table's quantized section,
within 1e-6 of the numpy reference (tools/mlmap_ref.py, tests/golden/layer/quantized.csv)
and bit for bit equal to `mlmap apply --quantized`."""

import csv

import numpy as np
import pytest

import mlmap
from conftest import CLASSES, DEFAULT_TABLE, ROOT

GOLDEN = ROOT / "tests" / "golden" / "layer" / "quantized.csv"


def golden_cases():
    """Per parameter set of the shipped table: (bits, scales, zero points, codes,
    objectness, {head: expected (N, K)})."""
    with open(GOLDEN, newline="") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    cases = {}
    for r in rows:
        if r["table"] != "default":
            continue
        key = (int(r["bits"]), tuple(r[f"scale{i}"] for i in range(3)),
               tuple(int(r[f"zp{i}"]) for i in range(3)))
        c = cases.setdefault(key, {"codes": [], "os": [], "want": {h: [] for h in mlmap.HEADS}})
        c["codes"].append([int(r[f"q{i}"]) for i in range(3)])
        c["os"].append(float(r["objectness"]))
        for h in mlmap.HEADS:
            c["want"][h].append([float(r[f"{h}{i}"]) for i in range(3)])
    return cases


@pytest.fixture(scope="module")
def quantized_tables(cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("quantized")
    out = {}
    for bits, scales, zps in golden_cases():
        path = d / f"q{bits}_{'_'.join(scales)}_{'_'.join(map(str, zps))}.mlmap"
        cli("quantize", "--table", DEFAULT_TABLE, "--bits", bits, "--scale=" + ",".join(scales),
            "--zero-point=" + ",".join(map(str, zps)), "--output", path)
        out[(bits, scales, zps)] = path
    return out


def test_scores_equal_the_numpy_reference(quantized_tables):
    for key, case in golden_cases().items():
        table = mlmap.Table.load(quantized_tables[key])
        assert table.quantized["bits"] == key[0]
        dtype = np.int8 if key[0] == 8 else np.int16
        codes = np.array(case["codes"], dtype=dtype)
        os_ = np.array(case["os"])
        for head in mlmap.HEADS:
            got = table.quantized_scores(head, codes, os_)
            assert got.dtype == np.float32 and got.shape == codes.shape
            want = np.array(case["want"][head])
            assert np.abs(got - want).max() <= 1e-6, (key, head)
        # Any integer dtype holding the codes, any layout: the same scores.
        wide = np.asfortranarray(codes.astype(np.int64))
        assert np.array_equal(table.quantized_scores("ml", wide, os_),
                              table.quantized_scores("ml", codes, os_))


def test_scores_equal_mlmap_apply_quantized(cli, quantized_tables, tmp_path):
    key = next(k for k in quantized_tables if k[0] == 8)
    path = quantized_tables[key]
    rng = np.random.default_rng(3)
    codes = rng.integers(-128, 128, size=(300, 3)).astype(np.int8)
    os_ = rng.uniform(0, 1, 300).astype(np.float32)
    src = tmp_path / "codes.csv"
    with open(src, "w") as f:
        f.write("id,objectness," + ",".join(CLASSES) + "\n")
        for i, (q, o) in enumerate(zip(codes, os_)):
            f.write(f"{i},{float(o)!r}," + ",".join(str(int(v)) for v in q) + "\n")
    out = tmp_path / "scores.csv"
    cli("apply", "--table", path, "--input", src, "--quantized", "--output", out)
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    table = mlmap.Table.load(path)
    for head in mlmap.HEADS:
        want = np.array([[np.float32(r[f"{head}_{c}"]) for c in CLASSES] for r in rows],
                        dtype=np.float32)
        got = table.quantized_scores(head, codes, os_)
        assert np.array_equal(got, want), head


def test_bad_codes_and_tables_raise(quantized_tables):
    key = next(k for k in quantized_tables if k[0] == 8)
    table = mlmap.Table.load(quantized_tables[key])
    with pytest.raises(ValueError, match="codes: row index 1"):
        table.quantized_scores("ml", np.array([[0, 0, 0], [0, 300, 0]]))
    with pytest.raises(TypeError, match="not an integer dtype"):
        table.quantized_scores("ml", np.zeros((2, 3), dtype=np.float32))
    with pytest.raises(ValueError, match="4 columns"):
        table.quantized_scores("ml", np.zeros((2, 4), dtype=np.int8))
    with pytest.raises(ValueError, match="2-D"):
        table.quantized_scores("ml", np.zeros(3, dtype=np.int8))
    with pytest.raises(ValueError, match="objectness"):
        table.quantized_scores("ml", np.zeros((2, 3), dtype=np.int8), 2.0)
    with pytest.raises(ValueError, match="no valid quantized section"):
        mlmap.Table.load(DEFAULT_TABLE).quantized_scores("ml", np.zeros((1, 3), dtype=np.int8))
