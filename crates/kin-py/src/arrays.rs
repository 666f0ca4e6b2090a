//! numpy arrays in and out, and the row runner of the calls without a batch solve in kin-core
//! (the Jacobian, the singularity measure, the body FK): every row solved on its own, its
//! result and its code written in place, the GIL released, rayon across cores for large
//! batches. Leg IK/FK and body IK go through kin-core's batch solves instead
//! ([`crate::batch`]).

use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use rayon::prelude::*;

/// Rows per rayon task (a multiple of every form's lanes, `kin_core::batch::LANES` and
/// `kin_core::batch::avx512::LANES`, so that every task's chunks are full); batches of fewer than two chunks run on the calling thread.
pub const CHUNK_ROWS: usize = 16_384;

/// A float array read from Python: float32 used as it is, float64 narrowed to f32 row by row
/// (kin-core computes in f32).
pub enum Floats<'py> {
    /// float32 elements.
    F32(numpy::PyReadonlyArrayDyn<'py, f32>),
    /// float64 elements.
    F64(numpy::PyReadonlyArrayDyn<'py, f64>),
}

/// The elements of a C-contiguous view.
pub enum Slice<'a> {
    /// float32 elements.
    F32(&'a [f32]),
    /// float64 elements.
    F64(&'a [f64]),
}

impl Slice<'_> {
    /// The elements as f32: borrowed when they are float32, else narrowed into a copy.
    pub fn to_f32(&self) -> std::borrow::Cow<'_, [f32]> {
        match self {
            Slice::F32(s) => std::borrow::Cow::Borrowed(s),
            Slice::F64(s) => std::borrow::Cow::Owned(s.par_iter().map(|&v| v as f32).collect()),
        }
    }

    /// Element `i` as f32.
    #[inline(always)]
    pub fn get(&self, i: usize) -> f32 {
        match self {
            Slice::F32(s) => s[i],
            Slice::F64(s) => s[i] as f32,
        }
    }

    /// `W` elements from `start`.
    #[inline(always)]
    pub fn row<const W: usize>(&self, start: usize) -> [f32; W] {
        core::array::from_fn(|k| self.get(start + k))
    }
}

/// An array's elements in C order with its number of rows: borrowed from numpy when the array
/// is C-contiguous, else copied once.
pub struct Rows<'py> {
    /// Number of rows (the first axis).
    pub n: usize,
    array: Floats<'py>,
    copy: Option<Owned>,
}

enum Owned {
    F32(Vec<f32>),
    F64(Vec<f64>),
}

impl Rows<'_> {
    /// The elements, C order.
    pub fn slice(&self) -> Slice<'_> {
        match (&self.copy, &self.array) {
            (Some(Owned::F32(v)), _) => Slice::F32(v),
            (Some(Owned::F64(v)), _) => Slice::F64(v),
            (None, Floats::F32(a)) => Slice::F32(a.as_slice().unwrap_or(&[])),
            (None, Floats::F64(a)) => Slice::F64(a.as_slice().unwrap_or(&[])),
        }
    }
}

/// `(N, 3)`-style description of a shape for messages: `inner` are the trailing axes.
pub fn shape_text(inner: &[usize]) -> String {
    let mut s = String::from("(N");
    for d in inner {
        s.push_str(&format!(", {d}"));
    }
    s.push(')');
    s
}

/// Reads `obj` as a float array of shape `(N, *inner)`: a float32 or float64 ndarray, or a
/// sequence that numpy turns into float64. `what` names the argument in errors.
///
/// # Errors
/// `TypeError` for another dtype or an object numpy cannot read as floats, `ValueError` for
/// another shape; both name the expected shape.
pub fn read<'py>(obj: &Bound<'py, PyAny>, inner: &[usize], what: &str) -> PyResult<Rows<'py>> {
    let expected = shape_text(inner);
    let floats = extract_floats(obj, what, &expected)?;
    let shape: Vec<usize> = match &floats {
        Floats::F32(a) => a.shape().to_vec(),
        Floats::F64(a) => a.shape().to_vec(),
    };
    if shape.len() != inner.len() + 1 || shape[1..] != *inner {
        return Err(PyValueError::new_err(format!(
            "{what}: expected an array of shape {expected}, got shape {}",
            tuple_text(&shape)
        )));
    }
    let copy = match &floats {
        Floats::F32(a) if !a.is_c_contiguous() => {
            Some(Owned::F32(a.as_array().iter().copied().collect()))
        }
        Floats::F64(a) if !a.is_c_contiguous() => {
            Some(Owned::F64(a.as_array().iter().copied().collect()))
        }
        _ => None,
    };
    Ok(Rows {
        n: shape[0],
        array: floats,
        copy,
    })
}

/// `(a, b, c)` Python-style.
fn tuple_text(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

fn extract_floats<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
    expected: &str,
) -> PyResult<Floats<'py>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f32>>() {
        return Ok(Floats::F32(a.try_readonly()?));
    }
    if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        return Ok(Floats::F64(a.try_readonly()?));
    }
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Err(PyTypeError::new_err(format!(
            "{what}: expected a float32 or float64 array of shape {expected}, got dtype {}",
            a.dtype()
        )));
    }
    // A list or tuple: numpy's own conversion, as float64.
    let np = obj.py().import("numpy")?;
    let converted = np.call_method1("asarray", (obj, "float64")).map_err(|e| {
        PyTypeError::new_err(format!(
            "{what}: expected a float32 or float64 array of shape {expected} ({e})"
        ))
    })?;
    let a = converted.cast::<PyArrayDyn<f64>>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{what}: expected a float32 or float64 array of shape {expected}"
        ))
    })?;
    Ok(Floats::F64(a.try_readonly()?))
}

/// Runs `row(i, out_row)` for every row `i < n`, writing `W` outputs per row into `out`
/// (`n·W` long) and the row's code into `codes`, in parallel for large batches. `row` writes
/// its outputs only on success; a failed row's outputs stay zero.
pub fn for_rows<C, F>(n: usize, width: usize, out: &mut [f32], codes: &mut [C], row: F)
where
    C: Send,
    F: Fn(usize, &mut [f32]) -> C + Sync,
{
    debug_assert_eq!(out.len(), n * width);
    debug_assert_eq!(codes.len(), n);
    let chunk = |first: usize, out: &mut [f32], codes: &mut [C]| {
        for (k, (o, c)) in out
            .chunks_exact_mut(width.max(1))
            .zip(codes.iter_mut())
            .enumerate()
        {
            *c = row(first + k, o);
        }
    };
    if n < 2 * CHUNK_ROWS || width == 0 {
        chunk(0, out, codes);
    } else {
        out.par_chunks_mut(CHUNK_ROWS * width)
            .zip(codes.par_chunks_mut(CHUNK_ROWS))
            .enumerate()
            .for_each(|(k, (o, c))| chunk(k * CHUNK_ROWS, o, c));
    }
}
