//! numpy inputs: any array-like of numbers becomes a C-contiguous `(N, 3)`
//! float64 array read in place, or a clear `ValueError` that says which
//! argument and row is wrong.

use std::sync::atomic::{AtomicUsize, Ordering};

use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;

/// `obj` as a C-contiguous `(N, 3)` float64 array: a float64 array that is
/// already one is read in place, anything else (lists, integer or float32
/// arrays, strided views) is converted by `numpy.ascontiguousarray(obj,
/// dtype=float64)`. `what` names the argument in errors.
pub(crate) fn rows3<'py>(py: Python<'py>, obj: &Bound<'py, PyAny>, what: &str) -> PyResult<PyReadonlyArray2<'py, f64>> {
    let numpy = py.import("numpy")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", numpy.getattr("float64")?)?;
    let array = numpy
        .call_method("ascontiguousarray", (obj,), Some(&kwargs))
        .map_err(|e| PyValueError::new_err(format!("{what} must be an (N, 3) array of numbers: {}", e.value(py))))?;
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err(format!("{what} must have shape (N, 3), got {shape:?}")));
    }
    let array: PyReadonlyArray2<'py, f64> = array.extract()?;
    debug_assert!(array.is_c_contiguous());
    Ok(array)
}

/// The flat `3N` values of an array from [`rows3`].
pub(crate) fn flat<'a>(array: &'a PyReadonlyArray2<'_, f64>) -> PyResult<&'a [f64]> {
    array.as_slice().map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The point in row `i` of a flat `(N, 3)` buffer.
#[inline]
pub(crate) fn point(flat: &[f64], i: usize) -> Point3<f64> {
    Point3::new(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2])
}

/// The ray of row `i` of origins and directions (the direction normalised),
/// or `None` for a zero or non-finite one.
#[inline]
pub(crate) fn ray(origins: &[f64], directions: &[f64], i: usize) -> Option<Ray> {
    let o = point(origins, i);
    let d = point(directions, i).coords;
    if !o.iter().all(|c| c.is_finite()) {
        return None;
    }
    Ray::new(o, Vector3::from(d)).ok()
}

/// The first row the parallel loops found bad (`usize::MAX`: none), so that
/// the error names the same row whatever the thread count.
pub(crate) struct FirstBad(AtomicUsize);

impl FirstBad {
    pub(crate) fn new() -> Self {
        FirstBad(AtomicUsize::new(usize::MAX))
    }

    pub(crate) fn report(&self, row: usize) {
        self.0.fetch_min(row, Ordering::Relaxed);
    }

    pub(crate) fn get(&self) -> Option<usize> {
        Some(self.0.load(Ordering::Relaxed)).filter(|&r| r != usize::MAX)
    }
}

/// `ValueError` for row `i` of `what`, which is not finite.
pub(crate) fn not_finite(what: &str, flat: &[f64], i: usize) -> PyErr {
    let r = [flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]];
    PyValueError::new_err(format!("{what}[{i}] is not finite: {r:?}"))
}

/// `ValueError` for ray `i`, whose origin is not finite or direction is zero or not finite.
pub(crate) fn bad_ray(origins: &[f64], directions: &[f64], i: usize) -> PyErr {
    let o = point(origins, i);
    if !o.iter().all(|c| c.is_finite()) {
        return not_finite("origins", origins, i);
    }
    let d = [directions[3 * i], directions[3 * i + 1], directions[3 * i + 2]];
    match Ray::new(o, Vector3::from(d)) {
        Err(e) => PyValueError::new_err(format!("directions[{i}] = {d:?}: {e}")),
        Ok(_) => PyValueError::new_err(format!("ray {i} is not usable")),
    }
}
