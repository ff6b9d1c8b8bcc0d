"""Property tests of the scores' invariants (DESIGN §1.3) through the Python package."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import mlmap
from conftest import DEFAULT_TABLE, ROOT

TABLE = mlmap.Table.load(DEFAULT_TABLE)
# An open head with a temperature and an unknown category (T = 1.75, epsilon = 0.05).
OPEN_TABLE = mlmap.Table.load(ROOT / "tests" / "golden" / "layer" / "small_open.mlmap")

# Logits around and beyond the training support, infinities included.
logit = st.one_of(
    st.floats(-12.0, 12.0, width=32),
    st.floats(-2.0**100, 2.0**100, width=32),
    st.sampled_from([np.inf, -np.inf]),
)
matrices = st.integers(1, 40).flatmap(
    lambda n: hnp.arrays(np.float32, (n, 3), elements=logit)
)
objectness = st.floats(0.0, 1.0, width=32)


@settings(max_examples=200, deadline=None)
@given(x=matrices, os=objectness)
def test_ml_and_map_rows_are_in_range_and_sum_to_objectness(x, os):
    for head in ("ml", "map"):
        s = TABLE.scores(head, x, os)
        assert s.shape == x.shape and s.dtype == np.float32
        assert np.all(np.isfinite(s))
        assert np.all(s >= 0.0) and np.all(s <= np.float32(os))
        np.testing.assert_allclose(s.astype(np.float64).sum(axis=1), os, rtol=1e-5, atol=1e-7)


@settings(max_examples=200, deadline=None)
@given(x=matrices, os=objectness)
def test_bayes_rows_are_in_range_and_sum_to_at_most_objectness(x, os):
    s = TABLE.bayes(x, os)
    assert np.all(np.isfinite(s))
    assert np.all(s >= 0.0) and np.all(s <= np.float32(os))
    # A background category takes its share: at most OS (within rounding).
    assert np.all(s.astype(np.float64).sum(axis=1) <= os * (1 + 1e-5) + 1e-7)


@settings(max_examples=200, deadline=None)
@given(x=matrices, os=objectness)
def test_open_rows_are_in_range_and_decide_as_the_logits(x, os):
    # DESIGN 1.8: scores in [0, OS], summing to at most OS; a positive multiple of
    # softmax(z / T), so the decision is the detector's own.
    for table in (TABLE, OPEN_TABLE):
        s = table.open(x, os)
        assert np.all(np.isfinite(s))
        assert np.all(s >= 0.0) and np.all(s <= np.float32(os))
        assert np.all(s.astype(np.float64).sum(axis=1) <= os * (1 + 1e-5) + 1e-7)
        assert np.array_equal(mlmap.decide(s, x), mlmap.decide(x, x))


@settings(max_examples=100, deadline=None)
@given(x=matrices, os=st.lists(objectness, min_size=40, max_size=40))
def test_each_row_is_scored_alone(x, os):
    # A row's scores do not depend on the other rows of the batch, nor on the layout.
    os = np.array(os[: len(x)], dtype=np.float32)
    for head in mlmap.HEADS:
        whole = TABLE.scores(head, x, os)
        for i in range(len(x)):
            assert np.array_equal(whole[i], TABLE.scores(head, x[i : i + 1], os[i])[0])
        assert np.array_equal(whole, TABLE.scores(head, np.asfortranarray(x), os))


@settings(max_examples=100, deadline=None)
@given(x=matrices, os=objectness)
def test_scaling_objectness_scales_ml_and_map(x, os):
    # OS multiplies the normalised vector: OS = 0 gives zeros, and the ratio of two
    # objectness values is kept up to f32 rounding.
    for head in ("ml", "map"):
        assert np.all(TABLE.scores(head, x, 0.0) == 0.0)
        one = TABLE.scores(head, x, 1.0).astype(np.float64)
        np.testing.assert_allclose(TABLE.scores(head, x, os), one * np.float32(os),
                                   rtol=1e-6, atol=1e-7)
