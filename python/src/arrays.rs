//! numpy arrays in: checked once at the boundary, then lent to the scoring and fitting
//! loops as plain slices that can cross into threads without the GIL.
//!
//! Arrays of any dtype, order, stride and alignment are accepted. An array is read in
//! place only when numpy reports it C-contiguous and aligned for its dtype (so every
//! stride is a whole number of elements and every element sits at an address Rust can
//! read); any other array (Fortran order, a strided or reversed view, a field of a
//! packed structured array, a buffer at an odd offset, a byte-swapped or another float
//! dtype) is copied once by `numpy.require` into a contiguous, aligned array of the
//! native dtype. Rust never derives a slice from an array's strides itself (DESIGN
//! §6.20).

use numpy::prelude::*;
use numpy::{PyArray1, PyArray2, PyArrayDescr, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArray};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyFloat, PyInt};

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

/// `a` itself when it is a C-contiguous, aligned, base-class array of `dtype`;
/// otherwise one copy that is (`numpy.require(a, dtype, "CAE")`).
fn well_behaved<'py>(
    a: &Bound<'py, PyUntypedArray>,
    dtype: &Bound<'py, PyArrayDescr>,
) -> PyResult<Bound<'py, PyUntypedArray>> {
    let np = a.py().import("numpy")?;
    let out = np.call_method1("require", (a, dtype, "CAE"))?;
    Ok(out.cast_into::<PyUntypedArray>()?)
}

/// The values of a well-behaved array as a slice of exactly `len` elements: a
/// `ValueError` (never a shorter slice) if numpy handed back anything else.
fn whole<'a, T>(
    slice: Result<&'a [T], numpy::AsSliceError>,
    len: usize,
    what: &str,
) -> PyResult<&'a [T]> {
    match slice {
        Ok(s) if s.len() == len => Ok(s),
        _ => Err(value_error(format!(
            "{what}: numpy did not provide a contiguous, aligned copy of the array"
        ))),
    }
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

/// A float array of `ndim` dimensions, well-behaved, as native `float32` (when it is
/// `float32`) or `float64` (every other float dtype is converted); integer, boolean,
/// complex or object arrays are refused.
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
    let f32_dtype = numpy::dtype::<f32>(py);
    let target = if dtype.is_equiv_to(&f32_dtype) {
        f32_dtype
    } else {
        numpy::dtype::<f64>(py)
    };
    well_behaved(&a, &target)
}

/// Row-major `N x K` floats, borrowed from numpy (in place or from its one copy).
#[derive(Debug, Clone, Copy)]
pub enum Rows<'a> {
    /// `float32`, C order.
    F32(&'a [f32]),
    /// `float64`, C order.
    F64(&'a [f64]),
}

impl<'a> Rows<'a> {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            Self::F32(s) => s.len(),
            Self::F64(s) => s.len(),
        }
    }

    /// The values in consecutive pieces of `size` (the last may be shorter).
    pub fn pieces(&self, size: usize) -> Vec<Rows<'a>> {
        let size = size.max(1);
        match *self {
            Self::F32(s) => s.chunks(size).map(Rows::F32).collect(),
            Self::F64(s) => s.chunks(size).map(Rows::F64).collect(),
        }
    }

    /// Values `range`, or `None` when the range is not inside.
    pub fn get(&self, range: std::ops::Range<usize>) -> Option<Rows<'a>> {
        match *self {
            Self::F32(s) => s.get(range).map(Rows::F32),
            Self::F64(s) => s.get(range).map(Rows::F64),
        }
    }
}

/// A logit matrix held for the duration of a call: a C-contiguous, aligned array
/// (the caller's, or numpy's one copy of it).
pub enum Matrix<'py> {
    /// `float32`.
    F32(PyReadonlyArray2<'py, f32>),
    /// `float64` (and every other float dtype, converted).
    F64(PyReadonlyArray2<'py, f64>),
}

/// An `N x K` logit matrix with its shape.
pub struct Logits<'py> {
    /// The data.
    pub data: Matrix<'py>,
    /// N.
    pub rows: usize,
    /// K.
    pub cols: usize,
    what: String,
}

impl Logits<'_> {
    /// The rows, row-major: exactly `rows * cols` values.
    pub fn rows(&self) -> PyResult<Rows<'_>> {
        let len = self.rows.saturating_mul(self.cols);
        Ok(match &self.data {
            Matrix::F32(a) => Rows::F32(whole(a.as_slice(), len, &self.what)?),
            Matrix::F64(a) => Rows::F64(whole(a.as_slice(), len, &self.what)?),
        })
    }
}

/// Reads a logit matrix: 2-D, float, any order, stride or alignment.
pub fn logits<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Logits<'py>> {
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
    let data = if let Ok(x) = a.cast::<PyArray2<f32>>() {
        Matrix::F32(readonly2(x, what)?)
    } else {
        let x = a
            .cast::<PyArray2<f64>>()
            .map_err(|_| value_error(format!("{what}: expected float32 or float64")))?;
        Matrix::F64(readonly2(x, what)?)
    };
    let held = Logits {
        data,
        rows,
        cols,
        what: what.to_string(),
    };
    held.rows()?;
    Ok(held)
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

/// One value per row: a constant, or a column borrowed from numpy.
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
    /// Whether the column has a value for each of `n` rows.
    pub fn covers(&self, n: usize) -> bool {
        match self {
            Self::Const(_) => true,
            Self::F32(s) => s.len() == n,
            Self::F64(s) => s.len() == n,
        }
    }

    /// Value `i`, in `f64` (NaN past the end, which [`Column::covers`] rules out).
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
    /// A `float32` array (C-contiguous, aligned).
    F32(PyReadonlyArray1<'py, f32>, usize),
    /// A `float64` array (C-contiguous, aligned; other float dtypes converted).
    F64(PyReadonlyArray1<'py, f64>, usize),
}

impl Objectness<'_> {
    /// The values: a constant, or exactly one per row.
    pub fn column(&self) -> PyResult<Column<'_>> {
        Ok(match self {
            Self::Const(v) => Column::Const(*v),
            Self::F32(a, n) => Column::F32(whole(a.as_slice(), *n, "objectness")?),
            Self::F64(a, n) => Column::F64(whole(a.as_slice(), *n, "objectness")?),
        })
    }
}

/// Reads the objectness of `n` rows: `None` (1.0), a number, or an `(N,)` float
/// array of any stride or alignment; every value must be in `[0, 1]` (DESIGN §2).
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
    let held = if let Ok(x) = a.cast::<PyArray1<f32>>() {
        Objectness::F32(readonly1(x, what)?, n)
    } else {
        let x = a
            .cast::<PyArray1<f64>>()
            .map_err(|_| value_error(format!("{what}: expected float32 or float64")))?;
        Objectness::F64(readonly1(x, what)?, n)
    };
    check_objectness(held.column()?, n, what, false)?;
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

/// Labels borrowed from a native integer array of any width.
#[derive(Debug, Clone, Copy)]
pub enum LabelColumn<'a> {
    I64(&'a [i64]),
    I32(&'a [i32]),
    I16(&'a [i16]),
    I8(&'a [i8]),
    U64(&'a [u64]),
    U32(&'a [u32]),
    U16(&'a [u16]),
    U8(&'a [u8]),
}

impl LabelColumn<'_> {
    /// Label `i`, exactly (`None` past the end).
    #[inline]
    pub fn get(&self, i: usize) -> Option<i128> {
        match self {
            Self::I64(s) => s.get(i).map(|&v| i128::from(v)),
            Self::I32(s) => s.get(i).map(|&v| i128::from(v)),
            Self::I16(s) => s.get(i).map(|&v| i128::from(v)),
            Self::I8(s) => s.get(i).map(|&v| i128::from(v)),
            Self::U64(s) => s.get(i).map(|&v| i128::from(v)),
            Self::U32(s) => s.get(i).map(|&v| i128::from(v)),
            Self::U16(s) => s.get(i).map(|&v| i128::from(v)),
            Self::U8(s) => s.get(i).map(|&v| i128::from(v)),
        }
    }

    /// Number of labels.
    pub fn len(&self) -> usize {
        match self {
            Self::I64(s) => s.len(),
            Self::I32(s) => s.len(),
            Self::I16(s) => s.len(),
            Self::I8(s) => s.len(),
            Self::U64(s) => s.len(),
            Self::U32(s) => s.len(),
            Self::U16(s) => s.len(),
            Self::U8(s) => s.len(),
        }
    }
}

/// A label array held for the duration of a call: C-contiguous, aligned, of a native
/// integer dtype (the caller's array, or numpy's one copy of it), or labels made here.
pub enum Labels<'py> {
    /// Labels made by the package (`-1` for every row taken as background).
    Owned(Vec<i8>),
    I64(PyReadonlyArray1<'py, i64>),
    I32(PyReadonlyArray1<'py, i32>),
    I16(PyReadonlyArray1<'py, i16>),
    I8(PyReadonlyArray1<'py, i8>),
    U64(PyReadonlyArray1<'py, u64>),
    U32(PyReadonlyArray1<'py, u32>),
    U16(PyReadonlyArray1<'py, u16>),
    U8(PyReadonlyArray1<'py, u8>),
}

impl Labels<'_> {
    /// The labels as a column of exactly `n` values.
    pub fn column(&self, n: usize, what: &str) -> PyResult<LabelColumn<'_>> {
        Ok(match self {
            Self::Owned(v) => LabelColumn::I8(whole(Ok(v.as_slice()), n, what)?),
            Self::I64(a) => LabelColumn::I64(whole(a.as_slice(), n, what)?),
            Self::I32(a) => LabelColumn::I32(whole(a.as_slice(), n, what)?),
            Self::I16(a) => LabelColumn::I16(whole(a.as_slice(), n, what)?),
            Self::I8(a) => LabelColumn::I8(whole(a.as_slice(), n, what)?),
            Self::U64(a) => LabelColumn::U64(whole(a.as_slice(), n, what)?),
            Self::U32(a) => LabelColumn::U32(whole(a.as_slice(), n, what)?),
            Self::U16(a) => LabelColumn::U16(whole(a.as_slice(), n, what)?),
            Self::U8(a) => LabelColumn::U8(whole(a.as_slice(), n, what)?),
        })
    }
}

/// Holds an `(N,)` integer label array of any width, signedness, byte order, stride or
/// alignment, read in place when numpy can lend it as it is, else copied once into
/// its native-byte-order dtype (every value kept exactly). The values are not checked
/// here: see [`labels`] and the fit's own checks.
pub fn label_array<'py>(obj: &Bound<'py, PyAny>, what: &str, n: usize) -> PyResult<Labels<'py>> {
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
    let dtype = a.dtype();
    let kind = dtype.kind();
    if kind != b'i' && kind != b'u' {
        return Err(value_error(format!(
            "{what}: dtype {:?} is not supported; expected an integer dtype \
             (a class index 0 to K-1, or -1 for background)",
            dtype_name(&a)
        )));
    }
    // The same width and signedness in the machine's byte order.
    let native = dtype
        .call_method1("newbyteorder", ("=",))?
        .cast_into::<PyArrayDescr>()?;
    let a = well_behaved(&a, &native)?;
    macro_rules! borrow {
        ($($t:ty => $v:ident),*) => {$(
            if let Ok(x) = a.cast::<PyArray1<$t>>() {
                return Ok(Labels::$v(readonly1(x, what)?));
            }
        )*};
    }
    borrow!(i64 => I64, i32 => I32, i16 => I16, i8 => I8,
            u64 => U64, u32 => U32, u16 => U16, u8 => U8);
    Err(value_error(format!(
        "{what}: dtype {:?} is not supported; expected an integer dtype of 8 to 64 bits",
        dtype_name(&a)
    )))
}

/// Reads `n` labels: an `(N,)` integer array, `0..K-1` a class and `-1` background;
/// any other value is refused with the data files' message.
pub fn labels(obj: &Bound<'_, PyAny>, what: &str, n: usize, k: usize) -> PyResult<Vec<i64>> {
    let held = label_array(obj, what, n)?;
    let col = held.column(n, what)?;
    let classes = i128::try_from(k).unwrap_or(i128::MAX);
    let mut out = Vec::with_capacity(n);
    for i in 0..col.len() {
        let v = col.get(i).unwrap_or(i128::MIN);
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

/// `ValueError("{name} {value} is out of range: expected {expected}")`, the message of
/// a fit parameter out of range.
pub fn out_of_range(name: &str, value: &str, expected: &str) -> PyErr {
    value_error(format!(
        "{name} {value} is out of range: expected {expected}"
    ))
}

/// An integer argument as Python gave it (an `int`, a numpy integer, anything with
/// `__index__`): its value when it fits a `usize`, else its decimal text, so that a
/// negative or too-large value becomes a `ValueError` naming the parameter (and not
/// an `OverflowError`). Anything that is not an integer is a `TypeError`.
#[derive(Debug, Clone)]
pub struct Count(Result<usize, String>);

impl Count {
    /// A default value.
    pub const fn new(v: usize) -> Self {
        Self(Ok(v))
    }

    /// The value when it is a `usize`.
    pub fn value(&self) -> Option<usize> {
        self.0.as_ref().ok().copied()
    }

    /// The value as Python wrote it.
    pub fn text(&self) -> String {
        match &self.0 {
            Ok(v) => v.to_string(),
            Err(t) => t.clone(),
        }
    }

    /// The value when it lies in `range`, else [`out_of_range`] naming `name`.
    pub fn get(
        &self,
        name: &str,
        range: std::ops::RangeInclusive<usize>,
        expected: &str,
    ) -> PyResult<usize> {
        self.value()
            .filter(|v| range.contains(v))
            .ok_or_else(|| out_of_range(name, &self.text(), expected))
    }
}

impl<'a, 'py> FromPyObject<'a, 'py> for Count {
    type Error = PyErr;

    fn extract(b: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let index = b.py().import("operator")?.getattr("index")?;
        let i = index.call1((b,))?;
        Ok(Self(match i.extract::<usize>() {
            Ok(v) => Ok(v),
            Err(_) => Err(i.str()?.to_string()),
        }))
    }
}

/// The bytes of `obj`: `bytes`, `bytearray`, a `memoryview` or any other C-contiguous
/// buffer of single bytes (a numpy `uint8` or `int8` array). A buffer of wider items or
/// a non-contiguous one (a strided view) is a `TypeError`, as is an object without the
/// buffer protocol.
pub fn buffer_bytes(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<u8>> {
    if let Ok(b) = obj.cast::<PyBytes>() {
        return Ok(b.as_bytes().to_vec());
    }
    let expected = "expected bytes, bytearray, a memoryview or a numpy uint8 array";
    let memoryview = obj.py().import("builtins")?.getattr("memoryview")?;
    let view = memoryview.call1((obj,)).map_err(|_| {
        let type_name = obj
            .get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string());
        PyTypeError::new_err(format!("{what}: {expected}, not {type_name}"))
    })?;
    let itemsize: usize = view.getattr("itemsize")?.extract()?;
    if itemsize != 1 {
        let format: String = view.getattr("format")?.extract()?;
        return Err(PyTypeError::new_err(format!(
            "{what}: a buffer of {itemsize}-byte items (format {format:?}); {expected}"
        )));
    }
    let contiguous: bool = view.getattr("c_contiguous")?.extract()?;
    if !contiguous {
        return Err(PyTypeError::new_err(format!(
            "{what}: the buffer is not contiguous (a strided view); pass a contiguous copy, \
             e.g. bytes(data)"
        )));
    }
    let copy = view.call_method0("tobytes")?;
    Ok(copy.cast::<PyBytes>()?.as_bytes().to_vec())
}
