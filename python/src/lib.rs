//! `komplex`: the Komplex kernel and renderer from Python, in numpy batches.
//!
//! A [`Scene`] is a loaded scene file (the same JSON and the same errors as
//! the command line). Its queries take `(N, 3)` arrays and answer with
//! numpy arrays, the GIL released while the kernel's batch queries
//! (`complex::Complex::classify`, `cast_many`, `trace_many`) run on every
//! core. See docs/python.md.

use std::path::PathBuf;
use std::sync::RwLock;

use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;
use render::world::World;

mod arrays;

pyo3::create_exception!(
    komplex,
    SceneError,
    PyValueError,
    "A scene file that cannot be loaded: the message names the place (JSON path, line and column), as the command line does."
);

/// A Python exception for a failure of the `render` crate: a bad scene is a
/// [`SceneError`], bad options a `ValueError`, a missing file an `OSError`.
fn to_py(e: render::Error) -> PyErr {
    match &e {
        render::Error::Scene { .. } => SceneError::new_err(e.to_string()),
        render::Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            PyFileNotFoundError::new_err(e.to_string())
        }
        render::Error::Io { .. } | render::Error::Encode { .. } => PyOSError::new_err(e.to_string()),
        render::Error::Options(_) | render::Error::Data { .. } | render::Error::Interrupted => {
            PyValueError::new_err(e.to_string())
        }
    }
}

/// Reads a scene file (JSON); raises `SceneError` for a bad scene.
#[pyfunction]
fn load(py: Python<'_>, path: PathBuf) -> PyResult<Scene> {
    let world = py.detach(|| render::load(&path)).map_err(to_py)?;
    Ok(Scene::new(world))
}

/// Reads a scene from JSON text; raises `SceneError` for a bad scene.
#[pyfunction]
fn loads(py: Python<'_>, json: &str) -> PyResult<Scene> {
    let world = py
        .detach(|| render::format::SceneFile::load_str(json))
        .map_err(|source| to_py(render::Error::Scene { file: PathBuf::from("<string>"), source }))?;
    Ok(Scene::new(world))
}

/// Imports an OpenMC geometry (`geometry.xml`, or a `model.xml` holding
/// one) as a scene, as `komplex import-openmc` does: each block is named
/// `cell <id>` after its OpenMC cell, so `classify` answers OpenMC's cell
/// at each point. Raises `ValueError` naming the line and column of bad
/// input, `FileNotFoundError`/`OSError` when the file cannot be read.
#[pyfunction]
fn import_openmc(py: Python<'_>, path: PathBuf) -> PyResult<Scene> {
    let world = py
        .detach(|| {
            let imported = render::openmc::import_file(&path)?;
            imported.scene.to_world().map_err(|source| render::Error::Scene { file: path.clone(), source })
        })
        .map_err(to_py)?;
    Ok(Scene::new(world))
}

/// A loaded scene: its blocks under the priority rule, camera, lights and
/// materials.
#[pyclass(frozen, module = "komplex")]
struct Scene {
    /// Read-locked by every query; write-locked only by a render that
    /// changes the camera's size or the precision for its duration.
    world: RwLock<World>,
}

impl Scene {
    fn new(world: World) -> Self {
        Scene { world: RwLock::new(world) }
    }

    fn world(&self) -> std::sync::RwLockReadGuard<'_, World> {
        // A panic under the lock (none is expected) leaves the world whole:
        // every write restores what it changed first.
        self.world.read().unwrap_or_else(|e| e.into_inner())
    }
}

/// The first hits of a batch of rays (`Scene.cast`).
#[pyclass(frozen, module = "komplex")]
struct Hits {
    /// Distance along the (normalised) ray, `inf` where nothing is hit.
    #[pyo3(get)]
    t: Py<PyArray1<f64>>,
    /// 1-based block hit, `0` where nothing is hit.
    #[pyo3(get)]
    block: Py<PyArray1<u32>>,
    /// 1-based solid of that block, `0` where nothing is hit.
    #[pyo3(get)]
    solid: Py<PyArray1<u32>>,
    /// `(N, 3)` hit points, `nan` where nothing is hit.
    #[pyo3(get)]
    point: Py<PyArray2<f64>>,
    /// `(N, 3)` outward unit normals of the hit block, `nan` where nothing is hit.
    #[pyo3(get)]
    normal: Py<PyArray2<f64>>,
    /// Whether the ray enters the block there (else it leaves it).
    #[pyo3(get)]
    entering: Py<PyArray1<bool>>,
}

/// Every ray's partition into segments owned by one block or none
/// (`Scene.trace`): ray `i`'s segments are `offsets[i]:offsets[i + 1]`.
#[pyclass(frozen, module = "komplex")]
struct Traces {
    /// `(N + 1,)` start of each ray's segments in the flat arrays.
    #[pyo3(get)]
    offsets: Py<PyArray1<i64>>,
    /// Where each segment starts along its ray.
    #[pyo3(get)]
    start: Py<PyArray1<f64>>,
    /// Where it ends (`inf` for a ray's last one).
    #[pyo3(get)]
    end: Py<PyArray1<f64>>,
    /// 1-based owning block, `0` for empty space.
    #[pyo3(get)]
    block: Py<PyArray1<u32>>,
}

#[pymethods]
impl Traces {
    fn __len__(&self, py: Python<'_>) -> usize {
        self.offsets.bind(py).len().saturating_sub(1)
    }
}

#[pymethods]
impl Hits {
    fn __len__(&self, py: Python<'_>) -> usize {
        self.t.bind(py).len()
    }
}

/// Rays per parallel task: `Complex::cast_many`'s chunk.
const CHUNK: usize = 256;

/// The most blocks `Scene.blocks` lists (instances and lattices expanded).
const MAX_BLOCKS_LISTED: usize = 1 << 20;
/// Points per parallel task: `Complex::classify`'s chunk.
const POINT_CHUNK: usize = 1024;

/// `ValueError` unless origins and directions have as many rows.
fn same_length(origins: &[f64], directions: &[f64]) -> PyResult<()> {
    if origins.len() == directions.len() {
        return Ok(());
    }
    Err(PyValueError::new_err(format!(
        "origins and directions must have the same length, got {} and {}",
        origins.len() / 3,
        directions.len() / 3
    )))
}

/// `BlockId` as the 1-based index of the EXR `id.block` channel, 0 for none.
fn one_based(id: Option<complex::BlockId>) -> u32 {
    id.map_or(0, |b| b.0 + 1)
}

#[pymethods]
impl Scene {
    /// The owner of each point under the priority rule: `(N,)` uint32 of
    /// 1-based block indices, `0` outside every block.
    fn classify<'py>(&self, py: Python<'py>, points: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArray1<u32>>> {
        let array = arrays::rows3(py, points, "points")?;
        let flat = arrays::flat(&array)?;
        let world = self.world();
        let complex = &world.complex;
        let bad = arrays::FirstBad::new();
        let mut owners = vec![0u32; flat.len() / 3];
        // `Complex::classify`'s loop, reading the numpy buffer and writing
        // the answer array in place (no copy of either).
        py.detach(|| {
            owners.par_chunks_mut(POINT_CHUNK).enumerate().for_each(|(c, out)| {
                for (k, o) in out.iter_mut().enumerate() {
                    let p = arrays::point(flat, c * POINT_CHUNK + k);
                    if !p.iter().all(|x| x.is_finite()) {
                        bad.report(c * POINT_CHUNK + k);
                    }
                    *o = one_based(complex.contains_point(&p));
                }
            })
        });
        if let Some(i) = bad.get() {
            return Err(arrays::not_finite("points", flat, i));
        }
        Ok(owners.into_pyarray(py))
    }

    /// The first hit of each ray within `max_t` (directions are normalised).
    #[pyo3(signature = (origins, directions, max_t = f64::INFINITY))]
    fn cast(
        &self,
        py: Python<'_>,
        origins: &Bound<'_, PyAny>,
        directions: &Bound<'_, PyAny>,
        max_t: f64,
    ) -> PyResult<Hits> {
        if max_t.is_nan() || max_t < 0.0 {
            return Err(PyValueError::new_err(format!("max_t must be a number >= 0, got {max_t}")));
        }
        let (origins, directions) =
            (arrays::rows3(py, origins, "origins")?, arrays::rows3(py, directions, "directions")?);
        let (o, d) = (arrays::flat(&origins)?, arrays::flat(&directions)?);
        same_length(o, d)?;
        let n = o.len() / 3;
        let world = self.world();
        let complex = &world.complex;
        let bad = arrays::FirstBad::new();
        // Zeroed (pages mapped lazily); every entry is written below, by
        // the worker that casts its ray.
        let (mut t, mut block, mut solid) = (vec![0.0f64; n], vec![0u32; n], vec![0u32; n]);
        let (mut point, mut normal, mut entering) = (vec![0.0f64; 3 * n], vec![0.0f64; 3 * n], vec![false; n]);
        // `Complex::cast_many` a chunk at a time, each chunk's answers
        // written straight into the output arrays.
        py.detach(|| {
            let columns = t.par_chunks_mut(CHUNK).zip(block.par_chunks_mut(CHUNK)).zip(solid.par_chunks_mut(CHUNK));
            let rows = point.par_chunks_mut(3 * CHUNK).zip(normal.par_chunks_mut(3 * CHUNK));
            columns.zip(rows).zip(entering.par_chunks_mut(CHUNK)).enumerate().for_each_init(
                || (Vec::with_capacity(CHUNK), Vec::with_capacity(CHUNK)),
                |(rays, hits), (c, ((((t, block), solid), (point, normal)), entering))| {
                    let start = c * CHUNK;
                    rays.clear();
                    for i in start..start + t.len() {
                        match arrays::ray(o, d, i) {
                            Some(r) => rays.push(r),
                            None => return bad.report(i),
                        }
                    }
                    hits.clear();
                    hits.resize(rays.len(), None);
                    if complex.cast_many(rays, max_t, hits).is_err() {
                        return; // equal lengths: cannot happen
                    }
                    for (k, h) in hits.iter().enumerate() {
                        let (p, nm) = (&mut point[3 * k..3 * k + 3], &mut normal[3 * k..3 * k + 3]);
                        match h {
                            Some(h) => {
                                t[k] = h.t;
                                block[k] = h.block.0 + 1;
                                solid[k] = h.solid + 1;
                                p.copy_from_slice(h.point.coords.as_slice());
                                nm.copy_from_slice(h.normal.as_slice());
                                entering[k] = h.entering;
                            }
                            None => {
                                t[k] = f64::INFINITY;
                                p.fill(f64::NAN);
                                nm.fill(f64::NAN);
                            }
                        }
                    }
                },
            )
        });
        if let Some(i) = bad.get() {
            return Err(arrays::bad_ray(o, d, i));
        }
        let matrix = |v: Vec<f64>| -> PyResult<Py<PyArray2<f64>>> { Ok(v.into_pyarray(py).reshape([n, 3])?.unbind()) };
        Ok(Hits {
            t: t.into_pyarray(py).unbind(),
            block: block.into_pyarray(py).unbind(),
            solid: solid.into_pyarray(py).unbind(),
            point: matrix(point)?,
            normal: matrix(normal)?,
            entering: entering.into_pyarray(py).unbind(),
        })
    }

    /// Each ray's partition into segments, ragged (directions are normalised).
    fn trace(&self, py: Python<'_>, origins: &Bound<'_, PyAny>, directions: &Bound<'_, PyAny>) -> PyResult<Traces> {
        let (origins, directions) =
            (arrays::rows3(py, origins, "origins")?, arrays::rows3(py, directions, "directions")?);
        let (o, d) = (arrays::flat(&origins)?, arrays::flat(&directions)?);
        same_length(o, d)?;
        let rays: Vec<Option<quadric::Ray>> =
            py.detach(|| (0..o.len() / 3).into_par_iter().map(|i| arrays::ray(o, d, i)).collect());
        if let Some(i) = rays.iter().position(Option::is_none) {
            return Err(arrays::bad_ray(o, d, i));
        }
        let rays: Vec<quadric::Ray> = rays.into_iter().flatten().collect();
        let world = self.world();
        let traces = py.detach(|| {
            let mut traces = complex::Traces::new();
            world.complex.trace_many(&rays, &mut traces);
            traces
        });
        let segments = traces.segments();
        Ok(Traces {
            offsets: traces.offsets().iter().map(|&o| o as i64).collect::<Vec<_>>().into_pyarray(py).unbind(),
            start: segments.iter().map(|s| s.start).collect::<Vec<_>>().into_pyarray(py).unbind(),
            end: segments.iter().map(|s| s.end).collect::<Vec<_>>().into_pyarray(py).unbind(),
            block: segments.iter().map(|s| one_based(s.owner)).collect::<Vec<_>>().into_pyarray(py).unbind(),
        })
    }

    /// Renders the scene's camera view (as `komplex render`, with the
    /// scene's integrator) and returns the EXR channels as `(height, width)`
    /// arrays: `R G B A Z N.X N.Y N.Z` float32 and `id.block id.object`
    /// uint32; under adaptive sampling (`noise`) also `spp` uint32 and
    /// `error` float32.
    #[pyo3(signature = (width = None, height = None, spp = None, threads = None, precision = None, samples = None, noise = None, seed = None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        width: Option<u32>,
        height: Option<u32>,
        spp: Option<u32>,
        threads: Option<usize>,
        precision: Option<&str>,
        samples: Option<u32>,
        noise: Option<f64>,
        seed: Option<u64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let precision = precision
            .map(|p| match p {
                "fast" => Ok(complex::Precision::Fast),
                "accurate" => Ok(complex::Precision::Accurate),
                "certified" => Ok(complex::Precision::Certified),
                other => Err(PyValueError::new_err(format!(
                    "precision must be 'fast', 'accurate' or 'certified', got {other:?}"
                ))),
            })
            .transpose()?;
        if let Some(n) = samples {
            if !(1..=16).contains(&n) {
                return Err(PyValueError::new_err(format!("samples must be between 1 and 16, got {n}")));
            }
        }
        if let Some(n) = spp {
            if !(1..=render::limits::MAX_SPP).contains(&n) {
                let max = render::limits::MAX_SPP;
                return Err(PyValueError::new_err(format!("spp must be between 1 and {max}, got {n}")));
            }
        }
        if let Some(t) = noise {
            if !(t.is_finite() && t > 0.0) {
                return Err(PyValueError::new_err(format!("noise must be a finite number > 0, got {t}")));
            }
        }
        let frame = py.detach(|| -> Result<render::frame::Frame, render::Error> {
            let options = render::frame::Options { threads, ..Default::default() };
            let plain = width.is_none()
                && height.is_none()
                && samples.is_none()
                && spp.is_none()
                && noise.is_none()
                && seed.is_none()
                && precision.is_none();
            if plain {
                return render::frame::render(&self.world(), options, &|| {}).map(|(f, _)| f);
            }
            // Changed for this render only, under the write lock.
            let mut world = self.world.write().unwrap_or_else(|e| e.into_inner());
            let camera = world
                .camera
                .resized(width, height)
                .map_err(|e| render::Error::Options(format!("width/height: {e}")))?;
            let saved = (world.camera, world.settings.clone(), world.complex.precision());
            world.camera = camera;
            let settings = &mut world.settings;
            settings.samples = samples.unwrap_or(settings.samples);
            settings.spp = spp.or(settings.spp);
            settings.noise = noise.or(settings.noise);
            settings.seed = seed.unwrap_or(settings.seed);
            world.complex.set_precision(precision.unwrap_or(saved.2));
            let result = render::frame::render(&world, options, &|| {}).map(|(f, _)| f);
            world.camera = saved.0;
            world.settings = saved.1;
            world.complex.set_precision(saved.2);
            result
        });
        let frame = frame.map_err(to_py)?;
        let (h, w) = (frame.height as usize, frame.width as usize);
        let out = PyDict::new(py);
        let adaptive = frame.has_adaptive();
        let render::frame::Frame {
            rgb: [r, g, b], alpha, depth, normal: [nx, ny, nz], block, object, spp, error, ..
        } = frame;
        for (name, plane) in
            [("R", r), ("G", g), ("B", b), ("A", alpha), ("Z", depth), ("N.X", nx), ("N.Y", ny), ("N.Z", nz)]
        {
            out.set_item(name, plane.into_pyarray(py).reshape([h, w])?)?;
        }
        out.set_item("id.block", block.into_pyarray(py).reshape([h, w])?)?;
        out.set_item("id.object", object.into_pyarray(py).reshape([h, w])?)?;
        if adaptive {
            out.set_item("spp", spp.into_pyarray(py).reshape([h, w])?)?;
            out.set_item("error", error.into_pyarray(py).reshape([h, w])?)?;
        }
        Ok(out)
    }

    /// Every block's volume as the complex owns it, its own volume and the
    /// union's, each with its standard error: `komplex volume --json` as
    /// Python data. `box` is `(xmin, ymin, zmin, xmax, ymax, zmax)`.
    #[pyo3(signature = (tolerance = complex::DEFAULT_VOLUME_TOLERANCE, seed = 0, r#box = None))]
    fn volumes<'py>(
        &self,
        py: Python<'py>,
        tolerance: f64,
        seed: u64,
        r#box: Option<[f64; 6]>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let options = render::measure::MeasureOptions { tolerance, seed, bounds: r#box };
        let json = py.detach(|| render::measure::volumes(&self.world(), &options).map(|r| r.to_json()));
        from_json(py, &json.map_err(to_py)?)
    }

    /// Every pair of blocks whose own regions share a positive volume, with
    /// the volume, its error and a point inside both: `komplex overlaps
    /// --json` as Python data.
    #[pyo3(signature = (tolerance = complex::DEFAULT_VOLUME_TOLERANCE, seed = 0, r#box = None))]
    fn overlaps<'py>(
        &self,
        py: Python<'py>,
        tolerance: f64,
        seed: u64,
        r#box: Option<[f64; 6]>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let options = render::measure::MeasureOptions { tolerance, seed, bounds: r#box };
        let json = py.detach(|| render::measure::overlaps(&self.world(), &options).map(|r| r.to_json()));
        from_json(py, &json.map_err(to_py)?)
    }

    /// The blocks in priority order: dicts with `index` (1-based, as
    /// `classify` and `id.block`), `name`, `material` (its name),
    /// `transparent`, and `box` (`(min, max)` corners, `±inf` on unbounded
    /// axes; `None` for a block shown to be empty).
    #[getter]
    fn blocks<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let world = self.world();
        let n = world.complex.len();
        if n > MAX_BLOCKS_LISTED {
            return Err(PyValueError::new_err(format!(
                "the scene has {n} blocks (instances and lattices expanded), more than the {MAX_BLOCKS_LISTED} \
                 `blocks` lists"
            )));
        }
        let list = PyList::empty(py);
        for i in 0..n {
            let id = complex::BlockId(i as u32);
            let (block, info) = (world.complex.block(id), world.block_info(id));
            let d = PyDict::new(py);
            d.set_item("index", i + 1)?;
            d.set_item("name", block.name())?;
            d.set_item("material", &world.materials()[info.material].name)?;
            d.set_item("transparent", block.is_transparent())?;
            let bx = world.complex.block_aabb(complex::BlockId(i as u32));
            if bx.is_empty() {
                d.set_item("box", py.None())?;
            } else {
                let corner = |p: &quadric::nalgebra::Point3<f64>| (p.x, p.y, p.z);
                d.set_item("box", (corner(&bx.min), corner(&bx.max)))?;
            }
            list.append(d)?;
        }
        Ok(list)
    }

    /// The number of blocks (instances and lattices expanded).
    fn __len__(&self) -> usize {
        self.world().complex.len()
    }

    fn __repr__(&self) -> String {
        let world = self.world();
        format!(
            "<komplex.Scene: {} blocks, {}x{} camera>",
            world.complex.len(),
            world.camera.width(),
            world.camera.height()
        )
    }
}

/// `json.loads(text)`: the command line's JSON report as Python data.
fn from_json<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// The Komplex kernel and renderer from Python.
#[pymodule]
fn komplex(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(loads, m)?)?;
    m.add_function(wrap_pyfunction!(import_openmc, m)?)?;
    m.add_class::<Scene>()?;
    m.add_class::<Hits>()?;
    m.add_class::<Traces>()?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
