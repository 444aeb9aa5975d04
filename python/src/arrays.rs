//! numpy inputs: any array-like of numbers becomes rows of three float64
//! values, or a clear `ValueError` that says which argument and row is wrong.

use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use quadric::nalgebra::{Point3, Vector3};
use quadric::Ray;

/// `obj` as an `(N, 3)` float64 array (lists, tuples and integer or
/// float32 arrays are converted, as `numpy.asarray(obj, dtype=float64)`
/// does), each row finite. `what` names the argument in errors.
pub(crate) fn rows3(py: Python<'_>, obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 3]>> {
    let numpy = py.import("numpy")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", numpy.getattr("float64")?)?;
    let array = numpy
        .call_method("asarray", (obj,), Some(&kwargs))
        .map_err(|e| PyValueError::new_err(format!("{what} must be an (N, 3) array of numbers: {}", e.value(py))))?;
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err(format!("{what} must have shape (N, 3), got {shape:?}")));
    }
    let array: PyReadonlyArray2<'_, f64> = array.extract()?;
    let view = array.as_array();
    let mut rows = Vec::with_capacity(array.len() / 3);
    for (i, row) in view.outer_iter().enumerate() {
        let r = [row[0], row[1], row[2]];
        if !r.iter().all(|c| c.is_finite()) {
            return Err(PyValueError::new_err(format!("{what}[{i}] is not finite: {r:?}")));
        }
        rows.push(r);
    }
    Ok(rows)
}

/// Points from an `(N, 3)` array-like.
pub(crate) fn points(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<Vec<Point3<f64>>> {
    Ok(rows3(py, obj, "points")?.into_iter().map(Point3::from).collect())
}

/// Rays from `(N, 3)` origins and directions of the same length; directions
/// are normalised (`t` is then a distance), a zero direction is an error.
pub(crate) fn rays(py: Python<'_>, origins: &Bound<'_, PyAny>, directions: &Bound<'_, PyAny>) -> PyResult<Vec<Ray>> {
    let o = rows3(py, origins, "origins")?;
    let d = rows3(py, directions, "directions")?;
    if o.len() != d.len() {
        return Err(PyValueError::new_err(format!(
            "origins and directions must have the same length, got {} and {}",
            o.len(),
            d.len()
        )));
    }
    o.into_iter()
        .zip(d)
        .enumerate()
        .map(|(i, (o, d))| {
            Ray::new(Point3::from(o), Vector3::from(d))
                .map_err(|e| PyValueError::new_err(format!("directions[{i}] = {d:?}: {e}")))
        })
        .collect()
}
