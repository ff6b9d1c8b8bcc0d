"""Arrays in every layout numpy can hand over, integer settings out of range, NaN in
`decide`, buffers, and table files with a quantized section.

Every function that takes arrays gives, for an array that is unaligned, strided by a
byte count that is not a whole number of elements (a field of a packed structured
array), reversed, Fortran-ordered, byte-swapped or read-only, exactly what it gives
for a clean C-contiguous copy of the same values; bad values in such arrays are
refused with the message of the clean copy."""

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mlmap
from conftest import CLASSES, DEFAULT_TABLE, ROOT

Q8_TABLE = ROOT / "tables" / "default_q8.mlmap"


def unaligned(a):
    """`a`'s values in a buffer one byte past an aligned address."""
    a = np.ascontiguousarray(a)
    buf = bytearray(a.nbytes + 1)
    buf[1:] = a.tobytes()
    return np.frombuffer(buf, dtype=a.dtype, offset=1).reshape(a.shape)


def field(a, pad):
    """`a`'s values as the field after `pad` bytes of a packed structured array: the
    byte stride is the item size plus `pad` (9, 13, 17 ... for float64)."""
    rec = np.zeros(a.shape, dtype=np.dtype([("pad", f"V{pad}"), ("v", a.dtype)]))
    rec["v"] = a
    return rec["v"]


def every_second(a, offset=0):
    """`a`'s values as every second row of a larger array, `offset` bytes into its
    buffer."""
    shape = (2 * a.shape[0],) + a.shape[1:]
    buf = bytearray(2 * a.nbytes + offset)
    big = np.frombuffer(buf, dtype=a.dtype, offset=offset).reshape(shape)
    big[::2] = a
    return big[::2]


def variants(a):
    """The values of `a` in every layout, by name: each equal to `a`, none of them a
    C-contiguous, aligned, native array (except "readonly", which is read-only)."""
    a = np.ascontiguousarray(a)
    out = {
        "unaligned": unaligned(a),
        "field+1": field(a, 1),
        "field+5": field(a, 5),
        "field+9": field(a, 9),
        "every-second": every_second(a),
        "every-second-unaligned": every_second(a, 3),
        "reversed": a[::-1].copy()[::-1],
        "byteswapped": a.astype(a.dtype.newbyteorder()),
    }
    if a.ndim == 2:
        out["columns-reversed"] = a[:, ::-1].copy()[:, ::-1]
        out["fortran"] = np.asfortranarray(a)
        out["fortran-unaligned"] = np.asfortranarray(unaligned(a.T.copy()).T)
    else:
        # The same names for a 1-D array (the arguments of a call share a layout).
        out["columns-reversed"] = field(a, 3)
        out["fortran"] = every_second(a, 1)
        out["fortran-unaligned"] = unaligned(a)
    ro = a.copy()
    ro.flags.writeable = False
    out["readonly"] = ro
    for name, v in out.items():
        assert np.array_equal(v, a, equal_nan=True), name
        if a.dtype.itemsize > 1 and a.size > 1 and "unaligned" in name:
            assert not v.flags.aligned, name
        if name.startswith("field") and a.dtype.itemsize > 1:
            assert v.strides[-1] % a.dtype.itemsize != 0, name
    return out


VARIANTS = list(variants(np.zeros((3, 2))))


@pytest.fixture(scope="session")
def table():
    return mlmap.Table.load(DEFAULT_TABLE)


@pytest.fixture(scope="session")
def small(data):
    """Small slices of the shipped splits: (logits, labels, objectness) each."""
    def part(name, n):
        d = data[name]
        return (np.ascontiguousarray(d.logits[:n]), np.ascontiguousarray(d.labels[:n]),
                np.ascontiguousarray(d.objectness[:n]))
    return {"train": part("train", 3000), "val": part("val", 1000), "test": part("test", 1000),
            "ood": part("ood", 300)}


def bits(a):
    return np.ascontiguousarray(a).view(np.uint32)


# --- Scoring -----------------------------------------------------------------------


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("layout", VARIANTS)
def test_scores_in_every_layout_equal_the_contiguous_copy(table, small, dtype, layout):
    x, _, os = small["test"]
    x, os = x.astype(dtype), os.astype(dtype)
    want = {h: table.scores(h, x, os) for h in mlmap.HEADS}
    # The logits of an unaligned float64 array were once read as all zero: the
    # scores must differ from those (OS / K) for real data.
    assert not np.allclose(want["ml"], os[:, None] / 3)
    vx, vos = variants(x)[layout], variants(os)[layout]
    for head in mlmap.HEADS:
        for args in ((vx, os), (x, vos), (vx, vos)):
            got = table.scores(head, *args)
            assert got.shape == want[head].shape, (head, layout)
            assert np.array_equal(bits(got), bits(want[head])), (head, layout)
        assert np.array_equal(bits(getattr(table, head)(vx, vos)), bits(want[head]))


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
@pytest.mark.parametrize("layout", VARIANTS)
def test_decide_in_every_layout_equals_the_contiguous_copy(table, small, dtype, layout):
    x = small["test"][0].astype(dtype)
    s = table.ml(x).astype(dtype)
    # Rows the histograms call "I don't know" (OS / K) make ties that the logits break.
    s[::7] = np.float32(1 / 3)
    want = mlmap.decide(s, x)
    assert want.shape == (len(x),)
    vs, vx = variants(s)[layout], variants(x)[layout]
    for args in ((vs, x), (s, vx), (vs, vx)):
        got = mlmap.decide(*args)
        assert got.dtype == np.int64 and np.array_equal(got, want), layout


@settings(max_examples=60, deadline=None)
@given(
    rows=st.integers(1, 40),
    offset=st.integers(0, 7),
    pad=st.integers(0, 11),
    step=st.integers(1, 3),
    reverse=st.booleans(),
    f32=st.booleans(),
    seed=st.integers(0, 2**32 - 1),
)
def test_any_offset_stride_and_direction_scores_as_the_copy(rows, offset, pad, step, reverse,
                                                             f32, seed):
    table = mlmap.Table.load(DEFAULT_TABLE)
    rng = np.random.default_rng(seed)
    dtype = np.float32 if f32 else np.float64
    x = (rng.normal(size=(rows, 3)) * 4).astype(dtype)
    os = rng.uniform(size=rows).astype(dtype)
    # A buffer `offset` bytes in; each row `pad` bytes after the previous; every
    # `step`-th row; optionally backwards.
    item = np.dtype(dtype).itemsize
    rec_t = np.dtype([("pad", f"V{pad}"), ("x", dtype, (3,)), ("os", dtype)]) if pad else \
        np.dtype([("x", dtype, (3,)), ("os", dtype)])
    buf = bytearray(rows * step * rec_t.itemsize + offset)
    rec = np.frombuffer(buf, dtype=rec_t, offset=offset)[::step]
    if reverse:
        rec = rec[::-1]
    rec["x"], rec["os"] = x, os
    vx, vos = rec["x"], rec["os"]
    assert np.array_equal(vx, x) and vx.strides[0] == (-1 if reverse else 1) * step * \
        rec_t.itemsize and vx.strides[1] == item
    for head in mlmap.HEADS:
        want = table.scores(head, x, os)
        assert np.array_equal(bits(table.scores(head, vx, vos)), bits(want))
        assert np.array_equal(mlmap.decide(vx, vx), mlmap.decide(x, x))


# --- Evaluation and fitting --------------------------------------------------------


def label_variants(labels):
    """The labels as int64, int32 and int8, each in every layout."""
    out = {}
    for dt in (np.int64, np.int32, np.int8):
        for name, v in variants(labels.astype(dt)).items():
            out[f"{np.dtype(dt).name}-{name}"] = v
    return out


@pytest.mark.parametrize("layout", VARIANTS)
def test_evaluate_in_every_layout_equals_the_contiguous_copy(table, small, layout):
    (x, y, os), (vx_, vy_, vos_), (ox, _, oos) = small["test"], small["val"], small["ood"]
    want = mlmap.evaluate(table, x, y, os, val=(vx_, vy_, vos_), ood=(ox, None, oos))
    v = lambda a: variants(a)[layout]  # noqa: E731
    got = mlmap.evaluate(table, v(x), v(y), v(os), val=(v(vx_), v(vy_), v(vos_)),
                         ood=(v(ox), None, v(oos)))
    assert got == want
    for dt in (np.int32, np.int8):
        assert mlmap.evaluate(table, x, v(y.astype(dt)), os) == mlmap.evaluate(table, x, y, os)
    assert mlmap.evaluate(table, v(x.astype(np.float32)), y, v(os.astype(np.float32))) == \
        mlmap.evaluate(table, x.astype(np.float32), y, os.astype(np.float32))


@pytest.mark.parametrize("layout", VARIANTS)
def test_fit_stats_and_counts_in_every_layout_equal_the_contiguous_copy(small, layout):
    x, y, os = small["train"]
    want = mlmap.fit(x, y, os, classes=CLASSES).to_bytes()
    stats = mlmap.FitStats(x, y, os, classes=CLASSES)
    edges = stats.edges()
    counts = mlmap.FitCounts(edges, x, y, os)
    v = lambda a: variants(a)[layout]  # noqa: E731
    for dt in (np.float64, np.float32):
        xd = x.astype(dt)
        want_dt = mlmap.fit(xd, y, os, classes=CLASSES).to_bytes()
        for args in ((v(xd), y, os), (xd, v(y), os), (xd, y, v(os)), (v(xd), v(y), v(os))):
            assert mlmap.fit(*args, classes=CLASSES).to_bytes() == want_dt, layout
        if dt is np.float64:
            assert want_dt == want
    for ldt in (np.int64, np.int32, np.int8):
        vy = v(y.astype(ldt))
        assert mlmap.fit(v(x), vy, v(os), classes=CLASSES).to_bytes() == want, ldt
        assert mlmap.FitStats(v(x), vy, v(os), classes=CLASSES) == stats
        assert mlmap.FitCounts(edges, v(x), vy, v(os)) == counts
    assert mlmap.finish(mlmap.FitStats(v(x), v(y), v(os), classes=CLASSES),
                        mlmap.FitCounts(edges, v(x), v(y), v(os))).to_bytes() == want


@pytest.mark.parametrize("layout", VARIANTS)
def test_background_in_every_layout_equals_the_contiguous_copy(small, layout):
    x, y, os = small["train"]
    bg = small["ood"][0]
    v = lambda a: variants(a)[layout]  # noqa: E731
    for dt in (np.float64, np.float32):
        b = bg.astype(dt)
        want = mlmap.fit(x, y, os, classes=CLASSES, background=b)
        assert want != mlmap.fit(x, y, os, classes=CLASSES)
        assert mlmap.fit(x, y, os, classes=CLASSES, background=v(b)) == want, layout
        stats = mlmap.FitStats(x, y, classes=CLASSES, background=v(b))
        assert stats == mlmap.FitStats(x, y, classes=CLASSES, background=b)
        edges = stats.edges()
        counts = mlmap.FitCounts(edges, v(x), y, background=v(b))
        assert counts == mlmap.FitCounts(edges, x, y, background=b)
        assert mlmap.finish(stats, counts) == want


@pytest.mark.parametrize("layout", ["unaligned", "field+1", "every-second-unaligned", "reversed",
                                    "fortran", "byteswapped"])
def test_tune_in_every_layout_equals_the_contiguous_copy(small, layout):
    (x, y, os), (vx_, vy_, vos_), (ox, _, _) = small["train"], small["val"], small["ood"]
    # Half of the never-seen objects join the validation rows, the other half the
    # training rows as background.
    ood, bg = ox[:150], ox[150:]
    grid = dict(classes=CLASSES, bins_ml=[8, 22], bins_map=[17], bins_bayes=[22], lambda_min=1e-4,
                lambda_max=1e-2, lambdas_per_decade=1)
    want_table, want_report = mlmap.tune(x, y, (vx_, vy_, vos_), os, ood=ood, background=bg,
                                         **grid)
    assert want_table.open_params is not None
    v = lambda a: variants(a)[layout]  # noqa: E731
    got_table, got_report = mlmap.tune(v(x), v(y), (v(vx_), v(vy_), v(vos_)), v(os), ood=v(ood),
                                       background=v(bg), **grid)
    assert got_table == want_table
    assert got_report == want_report


# --- Bad values inside odd layouts: the clean copy's messages ----------------------


def odd_layouts(a):
    return {k: v for k, v in variants(a).items() if k != "readonly"}


def test_bad_values_in_odd_layouts_raise_the_contiguous_copys_message(table):
    x = np.array([[2.0, -1.0, 0.5], [0.0, 3.0, -1.0], [1.0, 0.0, 2.5], [0.0, 0.0, 0.0]] * 2)
    y = np.array([0, 1, 2, -1] * 2)
    os = np.full(8, 0.5)
    bad_os, bad_y, bad_x = os.copy(), y.copy(), x.copy()
    bad_os[5], bad_y[6], bad_x[3, 1] = 1.5, 7, np.nan
    msg_os = r'^objectness: row index 5: objectness "1\.5" is not a number in \[0, 1\]$'
    msg_y = r"^labels: row index 6: label 7 is not a class index \(0 to 2\) or -1 \(background\)$"
    msg_fit_x = r'^logits: row index 3: column "class1": "NaN" is not a finite number$'
    msg_score_x = r"^logits: row index 3: logit of class 1 is NaN$"
    for dt in (np.float64, np.float32):
        for name, o in odd_layouts(bad_os.astype(dt)).items():
            with pytest.raises(ValueError, match=msg_os):
                table.ml(x, o)
            with pytest.raises(ValueError, match=msg_os):
                mlmap.fit(x, y, o)
            with pytest.raises(ValueError, match=msg_os):
                mlmap.evaluate(table, x, y, o)
        for name, b in odd_layouts(bad_x.astype(dt)).items():
            with pytest.raises(ValueError, match=msg_fit_x):
                mlmap.fit(b, y)
            with pytest.raises(ValueError, match=msg_fit_x):
                mlmap.FitStats(b, y)
            with pytest.raises(ValueError, match=msg_score_x):
                table.map(b)
            with pytest.raises(ValueError, match=msg_score_x):
                table.open(b)
            # The same rows given as background: the message names that array.
            with pytest.raises(ValueError, match="^background" + msg_fit_x[len("^logits"):]):
                mlmap.fit(x, y, background=b)
            with pytest.raises(ValueError, match="^background" + msg_fit_x[len("^logits"):]):
                mlmap.FitCounts(mlmap.FitStats(x, y).edges(), x, y, background=b)
    edges = mlmap.FitStats(x, y).edges()
    for dt in (np.int64, np.int32, np.int16):
        for name, b in odd_layouts(bad_y.astype(dt)).items():
            with pytest.raises(ValueError, match=msg_y):
                mlmap.fit(x, b)
            with pytest.raises(ValueError, match=msg_y):
                mlmap.FitStats(x, b)
            with pytest.raises(ValueError, match=msg_y):
                mlmap.FitCounts(edges, x, b)
            with pytest.raises(ValueError, match=msg_y):
                mlmap.evaluate(table, x, b)


def test_labels_of_every_integer_width_and_byte_order_are_read_exactly(table):
    x = np.array([[2.0, -1.0, 0.5], [0.0, 3.0, -1.0], [1.0, 0.0, 2.5], [0.0, 0.0, 0.0]])
    want = mlmap.fit(x, np.array([0, 1, 2, -1]), bayes=False).to_bytes()
    for dt in ("<i2", ">i2", ">i4", ">i8", "<i8"):
        assert mlmap.fit(x, np.array([0, 1, 2, -1], dtype=dt), bayes=False).to_bytes() == want
    # Unsigned labels: no background, and a value past int64 is reported exactly.
    big = np.array([0, 1, 2, 2**64 - 1], dtype=">u8")
    with pytest.raises(ValueError, match=r"^labels: row index 3: label 18446744073709551615 is not"):
        mlmap.fit(x, big)


# --- No panic, no OverflowError ----------------------------------------------------

BINS = r"an integer from 1 to 65535$"


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda x, y: mlmap.fit(x, y, bins_ml=-1), r"^bins_ml -1 is out of range: expected " + BINS),
        (lambda x, y: mlmap.fit(x, y, bins_map=2**70),
         r"^bins_map 1180591620717411303424 is out of range: expected " + BINS),
        (lambda x, y: mlmap.fit(x, y, bins_ml=np.int64(-3)), r"^bins_ml -3 is out of range"),
        (lambda x, y: mlmap.fit(x, y, bins_ml=0), r"^bins_ml 0 is out of range: expected " + BINS),
        (lambda x, y: mlmap.fit(x, y, bins_ml=65536), r"^bins_ml 65536 is out of range"),
        (lambda x, y: mlmap.fit(x, y, bayes={"bins": -1}),
         r"^bins_bayes -1 is out of range: expected an integer from 1 to 65535"),
        (lambda x, y: mlmap.FitStats(x, y).edges(bins_ml=-1), r"^bins_ml -1 is out of range"),
        (lambda x, y: mlmap.FitStats(x, y).edges(bins_map=-(2**80)), r"^bins_map -1208925819614629174706176 is out"),
        (lambda x, y: mlmap.tune(x, y, (x, y), bins_ml=[-1]),
         r"^bins_ml: bin counts must be in 1\.\.=65535, at least one \(got -1\)$"),
        (lambda x, y: mlmap.tune(x, y, (x, y), bins_bayes=[22, 2**64]),
         r"^bins_bayes: bin counts must be in 1\.\.=65535, at least one \(got 18446744073709551616\)$"),
        (lambda x, y: mlmap.tune(x, y, (x, y), lambdas_per_decade=-1),
         r"^lambdas_per_decade -1 is out of range: expected an integer from 1 to 1000$"),
        (lambda x, y: mlmap.tune(x, y, (x, y), lambdas_per_decade=10**15),
         r"^lambdas_per_decade 1000000000000000 is out of range"),
        (lambda x, y: mlmap.tune(x, y, (x, y), top=-1), r"^top -1 is out of range: expected an integer >= 0$"),
        (lambda x, y: mlmap.evaluate(mlmap.Table.load(DEFAULT_TABLE), x, y, ece_bins=-1),
         r"^ece_bins -1 is out of range: expected an integer from 1 to "),
        (lambda x, y: mlmap.evaluate(mlmap.Table.load(DEFAULT_TABLE), x, y, ece_bins=2**64),
         r"^ece_bins 18446744073709551616 is out of range"),
        (lambda x, y: mlmap.Table.load(DEFAULT_TABLE).histogram("ml", -1),
         r"^class index -1 is not in 0\.\.3$"),
        (lambda x, y: mlmap.Table.load(DEFAULT_TABLE).histogram("ml", 2**64),
         r"^class index 18446744073709551616 is not in 0\.\.3$"),
    ],
)
def test_integer_settings_out_of_range_raise_value_error(call, message):
    x = np.array([[2.0, -1.0, 0.5], [0.0, 3.0, -1.0], [1.0, 0.0, 2.5], [0.0, 0.0, 0.0]])
    y = np.array([0, 1, 2, -1])
    with pytest.raises(ValueError, match=message) as e:
        call(x, y)
    assert type(e.value) is ValueError  # not OverflowError, not a panic


def test_signatures_show_the_integer_defaults():
    import inspect

    def defaults(f):
        return {k: p.default for k, p in inspect.signature(f).parameters.items()}

    assert defaults(mlmap.fit)["bins_ml"] == 22 and defaults(mlmap.fit)["bins_map"] == 17
    assert defaults(mlmap.fit)["bayes"] is True
    assert defaults(mlmap.FitStats.edges)["bins_ml"] == 22
    assert defaults(mlmap.tune)["lambdas_per_decade"] == 3 and defaults(mlmap.tune)["top"] == 5
    assert defaults(mlmap.evaluate)["ece_bins"] == 10


def test_non_integer_settings_raise_type_error():
    x = np.array([[2.0, -1.0, 0.5], [0.0, 3.0, -1.0], [1.0, 0.0, 2.5]])
    with pytest.raises(TypeError, match="bins_ml"):
        mlmap.fit(x, np.array([0, 1, 2]), bins_ml=2.5)
    with pytest.raises(TypeError, match="bins_ml"):
        mlmap.fit(x, np.array([0, 1, 2]), bins_ml="22")


def test_more_columns_than_a_table_holds_is_refused_before_naming_them():
    for call in (lambda x, y: mlmap.fit(x, y), lambda x, y: mlmap.FitStats(x, y)):
        with pytest.raises(ValueError, match="65536"):
            call(np.zeros((1, 65536)), np.zeros(1, dtype=np.int64))
        # No rows and 2**40 columns: numpy allocates nothing, and neither may mlmap.
        with pytest.raises(ValueError, match="1099511627776"):
            call(np.zeros((0, 2**40)), np.zeros(0, dtype=np.int64))


def test_empty_and_degenerate_shapes_never_panic(table):
    assert table.ml(np.zeros((0, 3))).shape == (0, 3)
    assert table.ml(np.zeros((0, 3))[::-1]).shape == (0, 3)
    assert mlmap.decide(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)
    assert mlmap.decide(np.zeros((0, 2**40)), np.zeros((0, 2**40))).shape == (0,)
    with pytest.raises(ValueError, match=r"^logits: has 1099511627776 columns; the table has 3"):
        table.ml(np.zeros((0, 2**40)))
    with pytest.raises(ValueError, match=r"^scores: shape \(2, 0\) has no class to decide between$"):
        mlmap.decide(np.zeros((2, 0)), np.zeros((2, 0)))
    with pytest.raises(ValueError, match="^logits: holds no rows$"):
        mlmap.evaluate(table, np.zeros((0, 3)), np.zeros(0, dtype=np.int64))
    with pytest.raises(ValueError):
        mlmap.fit(np.zeros((0, 3)), np.zeros(0, dtype=np.int64))


# --- decide and NaN -------------------------------------------------------------------


def test_decide_refuses_nan_scores_and_logits():
    s = np.array([[0.2, 0.5, 0.3], [0.1, 0.1, 0.8]])
    x = np.array([[0.0, 1.0, 2.0], [3.0, 2.0, 1.0]])
    assert list(mlmap.decide(s, x)) == [1, 2]
    nan_s, nan_x = s.copy(), x.copy()
    nan_s[1, 2], nan_x[1, 0] = np.nan, np.nan
    all_nan = np.full_like(s, np.nan)
    msg_s = r"^scores: row index 1: the value of class 2 is NaN; a decision needs comparable values$"
    msg_x = r"^logits: row index 1: the value of class 0 is NaN; a decision needs comparable values$"
    for dt in (np.float64, np.float32):
        for v in [nan_s.astype(dt)] + list(odd_layouts(nan_s.astype(dt)).values()):
            with pytest.raises(ValueError, match=msg_s):
                mlmap.decide(v, x)
        for v in [nan_x.astype(dt)] + list(odd_layouts(nan_x.astype(dt)).values()):
            with pytest.raises(ValueError, match=msg_x):
                mlmap.decide(s, v)
        with pytest.raises(ValueError, match=r"^scores: row index 0: the value of class 0 is NaN"):
            mlmap.decide(all_nan.astype(dt), x)
    # Infinite values compare, so they decide.
    assert list(mlmap.decide(np.array([[0.1, np.inf]]), np.array([[-np.inf, 0.0]]))) == [1]


def test_scores_of_nan_logits_refused_in_every_layout(table):
    x = np.array([[0.0, 1.0, 2.0], [np.nan, 0.0, 0.0]], dtype=np.float32)
    for v in odd_layouts(x).values():
        with pytest.raises(ValueError, match=r"^logits: row index 1: logit of class 0 is NaN$"):
            table.bayes(v)


# --- Buffers ------------------------------------------------------------------------


def test_from_bytes_takes_any_contiguous_byte_buffer(table):
    raw = table.to_bytes()
    arr = np.frombuffer(raw, dtype=np.uint8)
    for data in (raw, bytearray(raw), memoryview(raw), memoryview(bytearray(raw)), arr,
                 arr.astype(np.int8), arr.copy(), unaligned(arr), memoryview(arr)):
        assert mlmap.Table.from_bytes(data) == table
        assert mlmap.Table.from_bytes(data).to_bytes() == raw
    twice = np.repeat(arr, 2)
    cases = {
        "the buffer is not contiguous": [twice[::2], memoryview(twice)[::2]],
        r'a buffer of 4-byte items \(format "f"\)': [np.zeros(10, dtype=np.float32)],
        r"a buffer of 8-byte items": [np.zeros(10)],
        "expected bytes, bytearray, a memoryview or a numpy uint8 array, not str$": ["not bytes"],
        "expected bytes, bytearray, a memoryview or a numpy uint8 array, not int$": [3],
        "expected bytes, bytearray, a memoryview or a numpy uint8 array, not list$": [list(raw)],
    }
    for message, objs in cases.items():
        for obj in objs:
            with pytest.raises(TypeError, match="^data: " + message):
                mlmap.Table.from_bytes(obj)


def test_fit_states_read_from_any_contiguous_byte_buffer(small):
    x, y, os = small["train"]
    stats = mlmap.FitStats(x, y, os, classes=CLASSES)
    edges = stats.edges()
    counts = mlmap.FitCounts(edges, x, y, os)
    for obj in (stats, edges, counts):
        raw = obj.to_bytes()
        for data in (bytearray(raw), memoryview(raw), np.frombuffer(raw, dtype=np.uint8)):
            assert type(obj).from_bytes(data) == obj
        with pytest.raises(TypeError, match="^data: the buffer is not contiguous"):
            type(obj).from_bytes(np.repeat(np.frombuffer(raw, np.uint8), 2)[::2])


# --- Quantized sections -------------------------------------------------------------


def test_a_quantized_section_is_kept_and_described(table, inspect, tmp_path, cli):
    raw = DEFAULT_TABLE.read_bytes()
    q8 = Q8_TABLE.read_bytes()
    assert q8[: len(raw)] == raw and len(q8) > len(raw)
    want = inspect(Q8_TABLE)["quantized"]
    t = mlmap.Table.load(Q8_TABLE)
    assert t.to_bytes() == q8 and t.size == len(q8)
    assert t.quantized == {"bits": want["bits"], "size": want["bytes"],
                           "heads": ("ml", "map", "bayes") if want["bayes"] else ("ml", "map")}
    assert want["bytes"] == len(q8) - len(raw)
    assert "quantized=int8" in repr(t)
    assert mlmap.Table.from_bytes(q8) == t and mlmap.Table.from_bytes(memoryview(q8)) == t
    assert pickle.loads(pickle.dumps(t)).to_bytes() == q8
    out = tmp_path / "again.mlmap"
    t.save(out)
    assert out.read_bytes() == q8
    # The file and the table alone are different files; their float scores are equal.
    assert t != table and table.quantized is None
    x = np.array([[2.0, -1.0, 0.5], [0.0, 3.0, -1.0]])
    for head in mlmap.HEADS:
        assert np.array_equal(t.scores(head, x), table.scores(head, x))
    # An int16 section without the Bayes head.
    q16 = tmp_path / "q16.mlmap"
    cli("quantize", "--table", DEFAULT_TABLE, "--scale", "0.01", "--bits", "16", "--no-bayes",
        "--output", q16)
    t16 = mlmap.Table.load(q16)
    assert t16.to_bytes() == q16.read_bytes()
    assert t16.quantized == {"bits": 16, "size": inspect(q16)["quantized"]["bytes"],
                             "heads": ("ml", "map")}


def test_a_bad_quantized_section_is_refused(small):
    raw = DEFAULT_TABLE.read_bytes()
    q8 = Q8_TABLE.read_bytes()
    section = q8[len(raw):]
    # Any changed byte in the section: refused (its CRC, or the table's length check).
    for i in range(0, len(section), max(1, len(section) // 50)):
        bad = bytearray(q8)
        bad[len(raw) + i] ^= 0x41
        with pytest.raises(mlmap.TableError):
            mlmap.Table.from_bytes(bytes(bad))
    # A valid section after another table: refused, naming the section.
    other = mlmap.fit(*small["train"], classes=CLASSES).to_bytes()
    with pytest.raises(mlmap.TableError, match="^quantized section: "):
        mlmap.Table.from_bytes(other + section)


# --- The parallel paths -------------------------------------------------------------


def test_large_arrays_in_odd_layouts_equal_the_contiguous_copy(table, data):
    """Enough rows that scoring runs on the thread pool (from 65,536 rows) and the fit
    splits its passes into ranges (from 262,144 rows)."""
    tr = data["train"]
    reps = 300_000 // len(tr) + 1
    x, y = np.tile(tr.logits, (reps, 1)), np.tile(tr.labels, reps)
    os = np.tile(tr.objectness, reps)
    assert len(x) > 262_144
    want_fit = mlmap.fit(x, y, os, classes=CLASSES).to_bytes()
    want_scores = {h: table.scores(h, x, os) for h in mlmap.HEADS}
    for layout in ("unaligned", "field+1", "fortran"):
        vx, vy, vos = (variants(a)[layout] for a in (x, y, os))
        assert mlmap.fit(vx, vy, vos, classes=CLASSES).to_bytes() == want_fit, layout
        for head in mlmap.HEADS:
            assert np.array_equal(bits(table.scores(head, vx, vos)), bits(want_scores[head]))
    # The first bad row of a parallel pass is the one reported, in any layout.
    bad = x.copy()
    bad[200_000, 2] = np.nan
    with pytest.raises(ValueError, match=r"^logits: row index 200000: logit of class 2 is NaN$"):
        table.ml(unaligned(bad))
    with pytest.raises(ValueError, match=r'^logits: row index 200000: column "pedestrian": "NaN"'):
        mlmap.fit(field(bad, 1), y, classes=CLASSES)
    # As many rows given as background: split into ranges too, the bytes of the same
    # rows labelled -1, and the first bad row of the background reported.
    want_bg = mlmap.fit(np.concatenate([tr.logits, x]),
                        np.concatenate([tr.labels, np.full(len(x), -1)]), classes=CLASSES)
    assert mlmap.fit(tr.logits, tr.labels, classes=CLASSES, background=unaligned(x)) == want_bg
    with pytest.raises(ValueError, match=r'^background: row index 200000: column "pedestrian"'):
        mlmap.fit(tr.logits, tr.labels, classes=CLASSES, background=field(bad, 1))
