"""`mlmap.Calibrator`, the scikit-learn estimator: it fits the table `mlmap.fit` fits,
scores with it bit for bit, names classes from DataFrame columns, takes class-name
labels, refuses bad input with `ValueError`, works in a `Pipeline`, and passes the
scikit-learn estimator checks that apply to a calibrator of logits."""

import pickle
import subprocess
import sys
import warnings

import numpy as np
import pandas as pd
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import FunctionTransformer
from sklearn.utils import estimator_checks as ec

import mlmap
from conftest import CLASSES

HEADS = ["ml", "map", "bayes", "open"]


def names_of(labels):
    return np.array([CLASSES[i] if i >= 0 else "background" for i in labels], dtype=object)


@pytest.mark.parametrize("head", HEADS)
def test_scores_are_those_of_the_table_mlmap_fit_fits(data, head):
    train, test = data["train"], data["test"]
    cal = mlmap.Calibrator(head=head, classes=CLASSES)
    assert cal.fit(train.logits, train.labels, train.objectness) is cal
    table = mlmap.fit(train.logits, train.labels, train.objectness, classes=CLASSES)
    assert cal.table_.to_bytes() == table.to_bytes()
    assert list(cal.classes_) == CLASSES
    assert cal.n_features_in_ == 3

    got = cal.predict_proba(test.logits, test.objectness)
    want = table.scores(head, test.logits, test.objectness)
    assert got.shape == (len(test), 3) and got.dtype == want.dtype
    assert got.tobytes() == want.tobytes()

    # The decision: the largest score, ties to the larger logit, computed here by hand.
    s, x = want.astype(np.float64), test.logits
    expect = []
    for srow, xrow in zip(s, x):
        best = max(range(3), key=lambda j: (srow[j], xrow[j]))
        expect.append(CLASSES[best])
    assert list(cal.predict(test.logits, test.objectness)) == expect


def test_default_settings_fit_the_default_table(data):
    train, test = data["train"], data["test"]
    cal = mlmap.Calibrator().fit(train.logits, train.labels)
    table = mlmap.fit(train.logits, train.labels)
    assert cal.table_ == table
    assert list(cal.classes_) == ["class0", "class1", "class2"]
    assert cal.head == "open"
    assert cal.predict_proba(test.logits).tobytes() == table.open(test.logits).tobytes()


def test_settings_reach_the_fit(data):
    train = data["train"]
    kw = dict(bins_ml=9, bins_map=5, lambda_ml=0.01, lambda_map=0.002, edges="matlab",
              tail="clamp", bayes={"bins": 7, "lambda": 0.01})
    cal = mlmap.Calibrator(head="bayes", **kw).fit(train.logits, train.labels, train.objectness)
    assert cal.table_ == mlmap.fit(train.logits, train.labels, train.objectness, **kw)
    assert (cal.table_.bins_ml, cal.table_.bins_map, cal.table_.bins_bayes) == (9, 5, 7)
    cal = mlmap.Calibrator(head="map", bayes=False).fit(train.logits, train.labels)
    assert cal.table_.heads == ("ml", "map")


def test_dataframe_columns_name_the_classes_and_string_labels_work(data):
    train, test = data["train"], data["test"]
    cols = ["pedestrian", "car", "cyclist"]  # not the data's order: names follow columns
    perm = [CLASSES.index(c) for c in cols]
    df = pd.DataFrame(train.logits[:, perm], columns=cols)
    y = pd.Series(names_of(train.labels))
    cal = mlmap.Calibrator(head="map").fit(df, y, pd.Series(train.objectness))
    assert list(cal.classes_) == cols
    assert cal.table_.classes == cols
    assert list(cal.feature_names_in_) == cols
    # The same table as integer labels in the columns' order.
    to_col = {CLASSES.index(c): i for i, c in enumerate(cols)}
    ints = np.array([to_col.get(int(v), -1) for v in train.labels])
    want = mlmap.fit(train.logits[:, perm], ints, train.objectness, classes=cols)
    assert cal.table_.to_bytes() == want.to_bytes()
    test_df = pd.DataFrame(test.logits[:, perm], columns=cols)
    got = cal.predict_proba(test_df, test.objectness)
    assert got.tobytes() == want.map(test.logits[:, perm], test.objectness).tobytes()
    pred = cal.predict(test_df, test.objectness)
    assert set(pred) <= set(cols)
    # The same rows with their columns in another order are refused, not misread.
    with pytest.raises(ValueError, match="are not the fitted columns"):
        cal.predict_proba(test_df[["car", "cyclist", "pedestrian"]])


def test_string_labels_give_the_table_of_integer_labels(data):
    train, test = data["train"], data["test"]
    a = mlmap.Calibrator(classes=CLASSES).fit(train.logits, names_of(train.labels))
    b = mlmap.Calibrator(classes=CLASSES).fit(train.logits, train.labels)
    assert a.table_.to_bytes() == b.table_.to_bytes()
    # numpy unicode arrays as well as object arrays
    c = mlmap.Calibrator(classes=CLASSES).fit(train.logits, names_of(train.labels).astype(str))
    assert c.table_ == a.table_
    # score: accuracy on the rows labelled with a class, by hand.
    pred = a.predict(test.logits)
    keep = test.labels >= 0
    want = np.mean(pred[keep] == names_of(test.labels)[keep])
    assert a.score(test.logits, names_of(test.labels)) == pytest.approx(want, abs=1e-12)
    assert a.score(test.logits, test.labels) == pytest.approx(want, abs=1e-12)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda d: (dict(), d.logits[:, :1], d.labels), r"at least 2 columns"),
        (lambda d: (dict(), d.logits[:, 0], d.labels), r"2-D array"),
        (lambda d: (dict(), d.logits[:0], d.labels[:0]), r"no rows"),
        (lambda d: (dict(), d.logits.astype(str), d.labels), r"expected numbers"),
        (lambda d: (dict(), d.logits, d.labels[:-1]), r"labels for \d+ rows"),
        (lambda d: (dict(), d.logits, d.labels[:, None]), r"1-D array of labels"),
        (lambda d: (dict(classes=CLASSES), d.logits, np.where(d.labels == 0, "truck", names_of(d.labels))),
         r"label 'truck' is not a class name \(car, cyclist, pedestrian\) or 'background'"),
        (lambda d: (dict(), d.logits, names_of(d.labels)), r"label 'car' is not a class name"),
        (lambda d: (dict(), d.logits, d.labels + 0.5), r"whole numbers"),
        (lambda d: (dict(), d.logits, np.where(d.labels == 0, 3, d.labels)),
         r"label 3 is not a class index"),
        (lambda d: (dict(head="softmax"), d.logits, d.labels), r"head: 'softmax' is not one of"),
        (lambda d: (dict(head="open", bayes=False), d.logits, d.labels), r"needs the Bayes head"),
        (lambda d: (dict(classes=["a", "b"]), d.logits, d.labels), r"2 names for 3 logit columns"),
        (lambda d: (dict(bins_ml=0), d.logits, d.labels), r"bins"),
        (lambda d: (dict(tune=True, val_size=1.0), d.logits, d.labels), r"val_size"),
    ],
)
def test_bad_input_raises_value_error(data, make, message):
    kw, x, y = make(data["train"])
    with pytest.raises(ValueError, match=message):
        mlmap.Calibrator(**kw).fit(x, y)


def test_bad_input_at_prediction_raises(data):
    train, test = data["train"], data["test"]
    with pytest.raises(NotFittedError):
        mlmap.Calibrator().predict_proba(test.logits)
    cal = mlmap.Calibrator(head="map").fit(train.logits, train.labels)
    with pytest.raises(ValueError, match="fitted on 3"):
        cal.predict_proba(np.hstack([test.logits, test.logits[:, :1]]))
    with pytest.raises(ValueError, match="objectness"):
        cal.predict_proba(test.logits, test.objectness[:-1])
    bad = test.logits.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError):
        cal.predict(bad)
    df = pd.DataFrame(train.logits, columns=["a", "b", "c"])
    with pytest.raises(ValueError, match="differ from the DataFrame's columns"):
        mlmap.Calibrator(classes=CLASSES).fit(df, train.labels)


def test_in_a_pipeline_after_a_model(data):
    """A model whose output is turned into logits by a step, then the calibrator."""
    train, test = data["train"], data["test"]
    rng = np.random.default_rng(1)
    w = rng.normal(size=(3, 3)) + 3 * np.eye(3)
    model = FunctionTransformer(lambda f: f @ w)  # stands in for a detector's last layer
    feats_train = train.logits @ np.linalg.inv(w)
    feats_test = test.logits @ np.linalg.inv(w)
    pipe = Pipeline([("model", model), ("cal", mlmap.Calibrator(head="map", classes=CLASSES))])
    pipe.fit(feats_train, names_of(train.labels))
    alone = mlmap.Calibrator(head="map", classes=CLASSES).fit(feats_train @ w, train.labels)
    assert pipe.named_steps["cal"].table_ == alone.table_
    assert pipe.predict_proba(feats_test).tobytes() == alone.predict_proba(feats_test @ w).tobytes()
    assert list(pipe.predict(feats_test)) == list(alone.predict(feats_test @ w))
    # Settings through the pipeline, and a clone refits to the same table.
    pipe.set_params(cal__head="ml")
    assert pipe.predict_proba(feats_test).tobytes() == alone.table_.ml(feats_test @ w).tobytes()
    again = clone(pipe).fit(feats_train, train.labels)
    assert again.named_steps["cal"].table_ == alone.table_
    assert again.named_steps["cal"].head == "ml"


def test_fitted_calibrator_pickles(data):
    train, test = data["train"], data["test"]
    cal = mlmap.Calibrator(classes=CLASSES).fit(train.logits, train.labels, train.objectness)
    back = pickle.loads(pickle.dumps(cal))
    assert back.table_ == cal.table_ and list(back.classes_) == CLASSES
    assert back.predict_proba(test.logits).tobytes() == cal.predict_proba(test.logits).tobytes()


def test_tune_fits_on_a_held_out_split(data):
    train = data["train"]
    cal = mlmap.Calibrator(tune=True, classes=CLASSES, val_size=0.3, random_state=5)
    cal.fit(train.logits, train.labels, train.objectness)
    n = len(train)
    order = np.random.default_rng(5).permutation(n)
    n_val = round(0.3 * n)
    val, tr = np.sort(order[:n_val]), np.sort(order[n_val:])
    table, report = mlmap.tune(
        train.logits[tr], train.labels[tr],
        (train.logits[val], train.labels[val], train.objectness[val]),
        train.objectness[tr], classes=CLASSES,
    )
    assert cal.table_.to_bytes() == table.to_bytes()
    assert cal.tune_report_ == report
    assert cal.table_.open_params["temperature"] != 1.0 or cal.table_.open_params["epsilon"] != 0.0


# -- scikit-learn's estimator checks -----------------------------------------------

def _checks_data(k=3, n=120, seed=0):
    rng = np.random.default_rng(seed)
    y = np.arange(n) % k
    x = rng.normal(size=(n, k)) + 2.5 * np.eye(k)[y]
    return x, y


@pytest.mark.parametrize(
    "check",
    [
        ec.check_get_params_invariance,
        ec.check_set_params,
        ec.check_no_attributes_set_in_init,
        ec.check_parameters_default_constructible,
        ec.check_dont_overwrite_parameters,
        ec.check_estimators_unfitted,
        ec.check_n_features_in,
        ec.check_fit_score_takes_y,
        ec.check_estimator_repr,
        ec.check_do_not_raise_errors_in_init_or_set_params,
    ],
    ids=lambda c: c.__name__,
)
def test_sklearn_check(check):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check("Calibrator", mlmap.Calibrator())


def test_fit_returns_self_and_clone():
    x, y = _checks_data()
    cal = mlmap.Calibrator(head="map", bins_ml=8)
    assert cal.fit(x, y) is cal
    c = clone(cal)
    assert c.get_params() == cal.get_params() and not hasattr(c, "table_")
    assert c.fit(x, y).table_ == cal.table_
    assert c.set_params(head="ml") is c and c.head == "ml"
    with pytest.raises(ValueError):
        c.set_params(heads="ml")


#: The checks of `check_estimator` that do not apply to a calibrator of logits, and why.
#: A calibrator's input is a detector's logits, one column per class, and every column
#: needs training rows of its class: the checks' random data (more feature columns than
#: classes in `y`, or labels beyond the columns) is refused with `ValueError`, and
#: `classes_` are the columns' names, not `np.unique(y)`.
COLUMNS_ARE_CLASSES = "random X with more columns than y has classes (every class needs rows)"
LABELS_ARE_COLUMNS = "labels beyond X's columns: a label is a column index or name"
PREDICT_GIVES_NAMES = "predict gives class names (strings); the check subtracts predictions"
EXPECTED_FAILURES = {
    "check_estimators_overwrite_params": LABELS_ARE_COLUMNS,
    "check_estimators_fit_returns_self": LABELS_ARE_COLUMNS,
    "check_readonly_memmap_input": LABELS_ARE_COLUMNS,
    "check_classifier_data_not_an_array": LABELS_ARE_COLUMNS,
    "check_n_features_in_after_fitting": COLUMNS_ARE_CLASSES,
    "check_positive_only_tag_during_fit": COLUMNS_ARE_CLASSES,
    "check_estimators_dtypes": COLUMNS_ARE_CLASSES,
    "check_pipeline_consistency": COLUMNS_ARE_CLASSES,
    "check_estimators_nan_inf": COLUMNS_ARE_CLASSES,
    "check_estimators_pickle": COLUMNS_ARE_CLASSES,
    "check_fit2d_1sample": "one row cannot hold a row of every class",
    "check_dtype_object": "logits are numbers: an object array is refused",
    "check_classifiers_classes": "string labels must be the class (column) names",
    "check_classifiers_train": "classes_ are the column names, not np.unique(y)",
    "check_supervised_y_2d": "a 2-D y is refused with ValueError (one label per row)",
    "check_methods_sample_order_invariance": PREDICT_GIVES_NAMES,
    "check_methods_subset_invariance": PREDICT_GIVES_NAMES,
    "check_fit_idempotent": PREDICT_GIVES_NAMES,
}


def test_check_estimator_fails_only_where_it_does_not_apply():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the skip of the array API check is logged
        results = ec.check_estimator(
            mlmap.Calibrator(), expected_failed_checks=EXPECTED_FAILURES, on_fail=None
        )
    ran = {r["check_name"]: r for r in results}
    for name in ("check_get_params_invariance", "check_set_params",
                 "check_no_attributes_set_in_init", "check_parameters_default_constructible"):
        assert ran[name]["status"] == "passed", ran[name]
    unexpected = [(r["check_name"], repr(r["exception"])) for r in results
                  if r["status"] == "failed"]
    assert unexpected == []
    # The list holds only checks that fail: each one listed ran and failed as expected.
    assert {r["check_name"] for r in results if r["status"] == "xfail"} == set(EXPECTED_FAILURES)
    assert sum(r["status"] == "passed" for r in results) >= 30


def test_without_scikit_learn_get_and_set_params_work():
    code = """
import sys
sys.modules["sklearn"] = None
import numpy as np, mlmap
c = mlmap.Calibrator(head="map", bins_ml=9)
p = c.get_params()
assert p["head"] == "map" and p["bins_ml"] == 9 and p["bayes"] is True, p
assert c.set_params(head="ml", tune=False) is c and c.head == "ml"
try:
    c.set_params(nope=1)
except ValueError:
    pass
else:
    raise SystemExit("set_params took an unknown parameter")
x = np.array([[2.0, 0.0], [0.0, 2.0], [1.5, 0.2], [0.1, 1.0]] * 10)
y = np.array([0, 1, 0, 1] * 10)
try:
    c.predict(x)
except ValueError:
    pass
assert c.fit(x, y) is c and list(c.classes_) == ["class0", "class1"]
print("ok")
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"
