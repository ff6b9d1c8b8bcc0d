//! numpy arrays in: checked once at the boundary, then lent to the scoring and fitting
//! loops as plain slices that can cross into threads without the GIL.
//!
//! Floating-point arrays of any dtype, order and stride are accepted. A C-contiguous
//! `float32` or `float64` array is read in place; anything else (Fortran order, a
//! strided view, another float dtype) is copied once into a contiguous buffer.

use numpy::prelude::*;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArray};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyFloat, PyInt};

use mlmap::host::dataset::{DataError, DataErrorKind, Location};

/// `ValueError(msg)`.
pub fn value_error(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// `obj` as a numpy array (`numpy.asarray` for anything else, e.g. a list).
fn as_ndarray<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj,))?;
    Ok(a.cast_into::<PyUntypedArray>()?)
}

/// `"float32"`, `"int64"`, ... as numpy names the array's dtype.
fn dtype_name(a: &Bound<'_, PyUntypedArray>) -> String {
    a.dtype().to_string()
}

/// The shape of `a` as numpy prints it (`(3, 2)`, `(4,)`).
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// A float array of `ndim` dimensions as native `float32` or `float64` (another float
/// dtype is converted to `float64`); integer, boolean or object arrays are refused.
fn float_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
    ndim: usize,
    expected: &str,
) -> PyResult<Bound<'py, PyUntypedArray>> {
    let a = as_ndarray(obj)?;
    if a.ndim() != ndim {
        return Err(value_error(format!(
            "{what}: shape {} is not {expected}",
            shape_text(a.shape())
        )));
    }
    let dtype = a.dtype();
    if dtype.kind() != b'f' {
        return Err(value_error(format!(
            "{what}: dtype {:?} is not supported; expected float32 or float64",
            dtype_name(&a)
        )));
    }
    let py = obj.py();
    let native =
        dtype.is_equiv_to(&numpy::dtype::<f32>(py)) || dtype.is_equiv_to(&numpy::dtype::<f64>(py));
    if native {
        return Ok(a);
    }
    let converted = a.call_method1("astype", ("float64",))?;
    Ok(converted.cast_into::<PyUntypedArray>()?)
}

/// Row-major `N x K` floats, borrowed from numpy or copied.
#[derive(Debug, Clone, Copy)]
pub enum Rows<'a> {
    /// `float32`, C order.
    F32(&'a [f32]),
    /// `float64`, C order.
    F64(&'a [f64]),
}

/// A logit matrix held for the duration of a call.
pub enum Matrix<'py> {
    /// A C-contiguous `float32` array, read in place.
    F32(PyReadonlyArray2<'py, f32>),
    /// A C-contiguous `float64` array, read in place.
    F64(PyReadonlyArray2<'py, f64>),
    /// A copy of an array in another layout.
    Owned32(Vec<f32>),
    /// A copy of a `float64` array in another layout (fitting reads `f64`).
    Owned64(Vec<f64>),
}

/// An `N x K` logit matrix with its shape.
pub struct Logits<'py> {
    /// The data.
    pub data: Matrix<'py>,
    /// N.
    pub rows: usize,
    /// K.
    pub cols: usize,
}

impl Logits<'_> {
    /// The rows, row-major.
    pub fn rows(&self) -> Rows<'_> {
        match &self.data {
            // The constructor keeps only C-contiguous arrays here, so these never fail.
            Matrix::F32(a) => Rows::F32(a.as_slice().unwrap_or(&[])),
            Matrix::F64(a) => Rows::F64(a.as_slice().unwrap_or(&[])),
            Matrix::Owned32(v) => Rows::F32(v),
            Matrix::Owned64(v) => Rows::F64(v),
        }
    }
}

/// Reads a logit matrix: 2-D, float, any order. `keep_f64` keeps a copy of a `float64`
/// array in `float64` (fitting reads logits in `f64`, as the data files); otherwise
/// copies are `float32` (scoring rounds to `f32` anyway).
pub fn logits<'py>(obj: &Bound<'py, PyAny>, what: &str, keep_f64: bool) -> PyResult<Logits<'py>> {
    let a = float_array(
        obj,
        what,
        2,
        "(N, K): one row per detection, one column per class",
    )?;
    let (rows, cols) = match a.shape() {
        [n, k] => (*n, *k),
        _ => (0, 0),
    };
    let c_order = a.is_c_contiguous();
    let data = if let Ok(x) = a.cast::<PyArray2<f32>>() {
        let x = readonly2(x, what)?;
        if c_order {
            Matrix::F32(x)
        } else {
            Matrix::Owned32(x.as_array().iter().copied().collect())
        }
    } else {
        let x = a
            .cast::<PyArray2<f64>>()
            .map_err(|_| value_error(format!("{what}: expected float32 or float64")))?;
        let x = readonly2(x, what)?;
        if c_order {
            Matrix::F64(x)
        } else if keep_f64 {
            Matrix::Owned64(x.as_array().iter().copied().collect())
        } else {
            Matrix::Owned32(x.as_array().iter().map(|&v| v as f32).collect())
        }
    };
    Ok(Logits { data, rows, cols })
}

fn readonly2<'py, T: numpy::Element>(
    a: &Bound<'py, PyArray2<T>>,
    what: &str,
) -> PyResult<PyReadonlyArray2<'py, T>> {
    a.try_readonly()
        .map_err(|e| value_error(format!("{what}: cannot be read: {e}")))
}

fn readonly1<'py, T: numpy::Element>(
    a: &Bound<'py, PyArray1<T>>,
    what: &str,
) -> PyResult<PyReadonlyArray1<'py, T>> {
    a.try_readonly()
        .map_err(|e| value_error(format!("{what}: cannot be read: {e}")))
}

/// One value per row: a constant, or a column borrowed or copied.
#[derive(Debug, Clone, Copy)]
pub enum Column<'a> {
    /// The same value for every row.
    Const(f64),
    /// `float32` values.
    F32(&'a [f32]),
    /// `float64` values.
    F64(&'a [f64]),
}

impl Column<'_> {
    /// Value `i`, in `f64`.
    #[inline]
    pub fn get(&self, i: usize) -> f64 {
        match self {
            Self::Const(v) => *v,
            Self::F32(s) => s.get(i).map_or(f64::NAN, |&v| f64::from(v)),
            Self::F64(s) => s.get(i).copied().unwrap_or(f64::NAN),
        }
    }

    /// Value `i` in the layer's precision.
    #[inline]
    pub fn get_f32(&self, i: usize) -> f32 {
        match self {
            Self::Const(v) => *v as f32,
            Self::F32(s) => s.get(i).copied().unwrap_or(f32::NAN),
            Self::F64(s) => s.get(i).map_or(f32::NAN, |&v| v as f32),
        }
    }
}

/// An objectness column held for the duration of a call.
pub enum Objectness<'py> {
    /// No array: a constant.
    Const(f64),
    /// A contiguous `float32` array.
    F32(PyReadonlyArray1<'py, f32>),
    /// A contiguous `float64` array.
    F64(PyReadonlyArray1<'py, f64>),
    /// A copy of a strided array.
    Owned(Vec<f64>),
}

impl Objectness<'_> {
    /// The values.
    pub fn column(&self) -> Column<'_> {
        match self {
            Self::Const(v) => Column::Const(*v),
            Self::F32(a) => Column::F32(a.as_slice().unwrap_or(&[])),
            Self::F64(a) => Column::F64(a.as_slice().unwrap_or(&[])),
            Self::Owned(v) => Column::F64(v),
        }
    }
}

/// Reads the objectness of `n` rows: `None` (1.0), a number, or an `(N,)` float
/// array; every value must be in `[0, 1]` (DESIGN §2).
pub fn objectness<'py>(
    obj: Option<&Bound<'py, PyAny>>,
    what: &str,
    n: usize,
) -> PyResult<Objectness<'py>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Objectness::Const(1.0));
    };
    let scalar = obj.is_instance_of::<PyFloat>()
        || obj.is_instance_of::<PyInt>()
        || as_ndarray(obj)
            .is_ok_and(|a| a.ndim() == 0 && matches!(a.dtype().kind(), b'f' | b'i' | b'u'));
    if scalar {
        let v: f64 = obj.extract()?;
        check_objectness(Column::Const(v), 1, what, true)?;
        return Ok(Objectness::Const(v));
    }
    let a = float_array(obj, what, 1, "(N,): one objectness per row")?;
    let len = a.shape().first().copied().unwrap_or(0);
    if len != n {
        return Err(value_error(format!(
            "{what}: has {len} rows but the logits have {n}"
        )));
    }
    let contiguous = a.is_c_contiguous();
    let held = if let Ok(x) = a.cast::<PyArray1<f32>>() {
        let x = readonly1(x, what)?;
        if contiguous {
            Objectness::F32(x)
        } else {
            Objectness::Owned(x.as_array().iter().map(|&v| f64::from(v)).collect())
        }
    } else {
        let x = a
            .cast::<PyArray1<f64>>()
            .map_err(|_| value_error(format!("{what}: expected float32 or float64")))?;
        let x = readonly1(x, what)?;
        if contiguous {
            Objectness::F64(x)
        } else {
            Objectness::Owned(x.as_array().to_vec())
        }
    };
    check_objectness(held.column(), n, what, false)?;
    Ok(held)
}

/// Refuses an objectness that is NaN or outside `[0, 1]`, with the data files' message.
fn check_objectness(col: Column<'_>, n: usize, what: &str, scalar: bool) -> PyResult<()> {
    let bad = (0..n).find(|&i| !(0.0..=1.0).contains(&col.get(i)));
    match bad {
        None => Ok(()),
        Some(i) => {
            let text = format!("{}", col.get(i));
            let e = DataError::new(what, DataErrorKind::ObjectnessRange { text });
            let e = if scalar {
                e
            } else {
                e.at(Location::Row(i as u64))
            };
            Err(value_error(e.to_string()))
        }
    }
}

/// Reads `n` labels: an `(N,)` integer array, `0..K-1` a class and `-1` background;
/// any other value is refused with the data files' message.
pub fn labels(obj: &Bound<'_, PyAny>, what: &str, n: usize, k: usize) -> PyResult<Vec<i64>> {
    let a = as_ndarray(obj)?;
    if a.ndim() != 1 {
        return Err(value_error(format!(
            "{what}: shape {} is not (N,): one label per row",
            shape_text(a.shape())
        )));
    }
    let len = a.shape().first().copied().unwrap_or(0);
    if len != n {
        return Err(value_error(format!(
            "{what}: has {len} rows but the logits have {n}"
        )));
    }
    let kind = a.dtype().kind();
    if kind != b'i' && kind != b'u' {
        return Err(value_error(format!(
            "{what}: dtype {:?} is not supported; expected an integer dtype \
             (a class index 0 to K-1, or -1 for background)",
            dtype_name(&a)
        )));
    }
    let values = int_values(&a, what)?;
    let classes = i128::try_from(k).unwrap_or(i128::MAX);
    let mut out = Vec::with_capacity(n);
    for (i, &v) in values.iter().enumerate() {
        if v < -1 || v >= classes {
            let e = DataError::new(
                what,
                DataErrorKind::LabelIndex {
                    value: v,
                    classes: k,
                },
            )
            .at(Location::Row(i as u64));
            return Err(value_error(e.to_string()));
        }
        // In -1..K, so it fits.
        out.push(i64::try_from(v).unwrap_or(-1));
    }
    Ok(out)
}

/// The values of an integer array of any width and signedness, exactly.
fn int_values(a: &Bound<'_, PyUntypedArray>, what: &str) -> PyResult<Vec<i128>> {
    macro_rules! try_int {
        ($($t:ty),*) => {$(
            if let Ok(x) = a.cast::<PyArray1<$t>>() {
                let x = readonly1(x, what)?;
                return Ok(x.as_array().iter().map(|&v| i128::from(v)).collect());
            }
        )*};
    }
    try_int!(i64, i32, i16, i8, u64, u32, u16, u8);
    // Another integer type (a byte-swapped one): through numpy's int64 conversion,
    // refusing values it cannot hold.
    let np = a.py().import("numpy")?;
    let fits: bool = np
        .call_method1("can_cast", (a.dtype(), "int64"))?
        .extract()?;
    if !fits {
        return Err(value_error(format!(
            "{what}: dtype {:?} is not supported; expected an integer dtype",
            dtype_name(a)
        )));
    }
    let converted = a.call_method1("astype", ("int64",))?;
    let x = converted
        .cast::<PyArray1<i64>>()
        .map_err(|_| value_error(format!("{what}: expected integers")))?;
    let x = readonly1(x, what)?;
    Ok(x.as_array().iter().map(|&v| i128::from(v)).collect())
}
