//! `terrain._terrain`, the native part of the Python package `terrain` (distribution
//! `terrain-renderer`): scenes, cameras and a renderer kept across calls, whose `render` returns
//! the picture and its ground truth as NumPy arrays (docs/python.md).
//!
//! Rules:
//! - One device per `Renderer`, opened when it is made and kept: a call renders, it never opens
//!   a device or builds pipelines again (`devices_opened` counts the openings, for the tests).
//! - The arrays are those `--outputs` writes (`terrain_engine::truth`), keyed by the same names,
//!   plus the camera's `K`, `world_to_camera` and `camera_to_world` (OpenCV's convention).
//! - Every library error is raised as `terrain.Error` with the library's one-line message.
//! - The GIL is released while a frame renders and is read back.
//!
//! Rejected: a module over the `terrain` command (one process per snapshot), which opens a device
//! and compiles the pipelines for every image.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use terrain_engine::scene::{self, Mode, Scene};
use terrain_engine::truth::{Extrinsics, Intrinsics, Output, Truth};
use terrain_engine::{GpuContext, Ground, View};

create_exception!(
    terrain,
    Error,
    PyException,
    "A scene, sketch, camera or device the renderer cannot use; its message is one line."
);

fn err(e: terrain_engine::Error) -> PyErr {
    Error::new_err(e.to_string())
}

fn fail(message: String) -> PyErr {
    Error::new_err(message)
}

static DEVICES_OPENED: AtomicUsize = AtomicUsize::new(0);

/// Devices this process's renderers have opened.
#[pyfunction]
fn devices_opened() -> usize {
    DEVICES_OPENED.load(Ordering::Relaxed)
}

/// A scene: the sketch (height map), its detail, light and camera (docs/scene.md).
#[pyclass(name = "Scene", module = "terrain", from_py_object)]
#[derive(Clone)]
struct PyScene {
    scene: Scene,
    path: PathBuf,
}

#[pymethods]
impl PyScene {
    /// Reads a scene file (.toml) or a sketch (a height map: GeoTIFF, .asc, .hgt, PNG, …) with
    /// every default; `overrides` are `key=value` strings as `--set` takes them.
    #[staticmethod]
    #[pyo3(signature = (path, overrides = Vec::new()))]
    fn load(path: PathBuf, overrides: Vec<String>) -> PyResult<PyScene> {
        let scene = Scene::load_with(&path, &overrides).map_err(err)?;
        Ok(PyScene { scene, path })
    }

    /// A sketch (height map) as a scene with every default.
    #[staticmethod]
    #[pyo3(signature = (path, overrides = Vec::new()))]
    fn from_sketch(path: PathBuf, overrides: Vec<String>) -> PyResult<PyScene> {
        if !scene::is_sketch_path(&path) {
            return Err(fail(format!(
                "sketch {}: not a height map's name (.tif, .asc, .hgt, .png, … or a glob, .vrt or \
                 tile pyramid); Scene.load reads scene files",
                path.display()
            )));
        }
        PyScene::load(path, overrides)
    }

    /// The file it was read from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// The default camera's image size, (width, height).
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.scene.camera.width, self.scene.camera.height)
    }

    fn __repr__(&self) -> String {
        format!("terrain.Scene.load({:?})", self.path.display().to_string())
    }
}

/// Where a camera stands and looks: `position` and `look_at` (world metres), or a place by
/// `map_xy`, or `lat_deg` and `lon_deg`, with `altitude_m`, aimed by `heading_deg` and
/// `pitch_deg` (docs/scene.md, `[camera]`).
#[pyclass(name = "Camera", module = "terrain", from_py_object, get_all)]
#[derive(Clone, Debug, Default)]
struct PyCamera {
    position: Option<[f64; 3]>,
    look_at: Option<[f64; 3]>,
    map_xy: Option<[f64; 2]>,
    lat_deg: Option<f64>,
    lon_deg: Option<f64>,
    altitude_m: Option<f64>,
    heading_deg: Option<f64>,
    pitch_deg: Option<f64>,
    fov_y_deg: Option<f64>,
}

#[pymethods]
impl PyCamera {
    #[new]
    #[pyo3(signature = (*, position = None, look_at = None, map_xy = None, lat_deg = None,
        lon_deg = None, altitude_m = None, heading_deg = None, pitch_deg = None, fov_y_deg = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        position: Option<[f64; 3]>,
        look_at: Option<[f64; 3]>,
        map_xy: Option<[f64; 2]>,
        lat_deg: Option<f64>,
        lon_deg: Option<f64>,
        altitude_m: Option<f64>,
        heading_deg: Option<f64>,
        pitch_deg: Option<f64>,
        fov_y_deg: Option<f64>,
    ) -> PyCamera {
        PyCamera {
            position,
            look_at,
            map_xy,
            lat_deg,
            lon_deg,
            altitude_m,
            heading_deg,
            pitch_deg,
            fov_y_deg,
        }
    }

    /// Pickles by its keywords (a dataset's cameras go to worker processes).
    fn __getnewargs_ex__<'py>(&self, py: Python<'py>) -> PyResult<((), Bound<'py, PyDict>)> {
        let kw = PyDict::new(py);
        kw.set_item("position", self.position)?;
        kw.set_item("look_at", self.look_at)?;
        kw.set_item("map_xy", self.map_xy)?;
        kw.set_item("lat_deg", self.lat_deg)?;
        kw.set_item("lon_deg", self.lon_deg)?;
        kw.set_item("altitude_m", self.altitude_m)?;
        kw.set_item("heading_deg", self.heading_deg)?;
        kw.set_item("pitch_deg", self.pitch_deg)?;
        kw.set_item("fov_y_deg", self.fov_y_deg)?;
        Ok(((), kw))
    }

    fn __repr__(&self) -> String {
        let mut parts = Vec::new();
        let mut put = |k: &str, v: Option<String>| {
            if let Some(v) = v {
                parts.push(format!("{k}={v}"));
            }
        };
        let triple = |v: [f64; 3]| format!("({}, {}, {})", v[0], v[1], v[2]);
        put("position", self.position.map(triple));
        put("look_at", self.look_at.map(triple));
        put(
            "map_xy",
            self.map_xy.map(|v| format!("({}, {})", v[0], v[1])),
        );
        for (k, v) in [
            ("lat_deg", self.lat_deg),
            ("lon_deg", self.lon_deg),
            ("altitude_m", self.altitude_m),
            ("heading_deg", self.heading_deg),
            ("pitch_deg", self.pitch_deg),
            ("fov_y_deg", self.fov_y_deg),
        ] {
            put(k, v.map(|v| v.to_string()));
        }
        format!("terrain.Camera({})", parts.join(", "))
    }
}

impl PyCamera {
    /// `scene` with this camera in place of its own (its image size kept).
    fn placed_in(&self, scene: &Scene) -> Scene {
        let mut s = scene.clone();
        let c = &mut s.camera;
        (c.position, c.look_at, c.map_xy) = (self.position, self.look_at, self.map_xy);
        (c.lat_deg, c.lon_deg, c.altitude_m) = (self.lat_deg, self.lon_deg, self.altitude_m);
        (c.heading_deg, c.pitch_deg) = (self.heading_deg, self.pitch_deg);
        if let Some(f) = self.fov_y_deg {
            c.fov_y_deg = f;
        }
        s
    }

    fn of_section(c: &scene::CameraSection) -> PyCamera {
        PyCamera {
            position: c.position,
            look_at: c.look_at,
            map_xy: c.map_xy,
            lat_deg: c.lat_deg,
            lon_deg: c.lon_deg,
            altitude_m: c.altitude_m,
            heading_deg: c.heading_deg,
            pitch_deg: c.pitch_deg,
            fov_y_deg: Some(c.fov_y_deg),
        }
    }
}

/// The renderer, held across threads only while the GIL is released around a frame.
struct Held(terrain_engine::Renderer);

// SAFETY: `Renderer` is not `Send` because its level-of-detail scheme is a `dyn Lod` without
// that bound (wgpu's types are `Send` on every native backend). The pyclass is `unsendable`, so
// Python touches it only from the thread that made it, and `Python::detach` runs its closure
// on the calling thread: the renderer never leaves that thread.
unsafe impl Send for Held {}

/// A renderer of one scene at one image size and mode, on a device of its own kept across
/// calls.
#[pyclass(name = "Renderer", module = "terrain", unsendable)]
struct PyRenderer {
    scene: Scene,
    mode: Mode,
    held: Held,
    /// The surface classes' renderer, made when `surface` is first asked for.
    classes: Option<Held>,
}

#[pymethods]
impl PyRenderer {
    /// `size`: N or (width, height), default the scene's; `mode`: "warped", "geomipmap",
    /// "bruteforce", "reference" (or "clipmaps" on a planet), default the scene's.
    #[new]
    #[pyo3(signature = (scene, size = None, mode = None))]
    fn new(
        py: Python<'_>,
        scene: &PyScene,
        size: Option<Bound<'_, PyAny>>,
        mode: Option<&str>,
    ) -> PyResult<PyRenderer> {
        let mut s = scene.scene.clone();
        if let Some(size) = size {
            (s.camera.width, s.camera.height) = image_size(&size)?;
        }
        let mode = match mode {
            None => s.render.mode,
            Some(m) => Mode::parse(m)
                .ok_or_else(|| fail(format!("mode {m:?}: give one of {}", Mode::choices())))?,
        };
        s.render.mode = mode;
        let built = py.detach(|| -> terrain_engine::Result<Held> {
            let atlas = scene::load_atlas(&s)?;
            let ctx = GpuContext::new(&terrain_engine::needs(&s, mode, &atlas))?;
            DEVICES_OPENED.fetch_add(1, Ordering::Relaxed);
            let r = terrain_engine::Renderer::with_context(ctx, &s, atlas, mode, View::Shaded)?;
            Ok(Held(r))
        });
        Ok(PyRenderer {
            scene: s,
            mode,
            held: built.map_err(err)?,
            classes: None,
        })
    }

    /// Renders the view from `camera` (a `Camera`; default the scene's own) and returns a dict
    /// of NumPy arrays: each of `outputs` ("rgb" uint8 (H, W, 3); "depth", "distance" float32
    /// (H, W); "positions" float64 (H, W, 4); "latlon" float64 (H, W, 2); "normals" float32
    /// (H, W, 3); "surface" uint8 (H, W), indices into `SURFACE_CLASSES`), and the camera's "K"
    /// (3×3), "world_to_camera" and "camera_to_world" (4×4).
    #[pyo3(signature = (camera = None, outputs = vec!["rgb".to_string()]))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        camera: Option<PyCamera>,
        outputs: Vec<String>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let wanted = terrain_engine::truth::parse_outputs(&outputs.join(",")).map_err(fail)?;
        let scene = match &camera {
            Some(c) => c.placed_in(&self.scene),
            None => self.scene.clone(),
        };
        if wanted.contains(&Output::Surface) && self.classes.is_none() {
            let r = &self.held.0;
            let made = terrain_engine::truth::surface_renderer(r, &self.scene, self.mode);
            self.classes = Some(Held(made.map_err(err)?));
        }
        // `move` takes the `&mut Held`s whole (a closure otherwise captures the fields inside).
        let (held, classes) = (&mut self.held, self.classes.as_mut());
        let job = (&scene, &wanted[..]);
        let rendered = py.detach(move || render(&mut held.0, classes, job.0, job.1));
        let r = rendered.map_err(err)?;
        let (w, h) = (r.camera.width as usize, r.camera.height as usize);
        let dict = PyDict::new(py);
        let rgb: Vec<u8> = r
            .rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        if wanted.contains(&Output::Rgb) {
            dict.set_item("rgb", array(py, rgb, &[h, w, 3])?)?;
        }
        if let Some(t) = &r.truth {
            let held = &self.held.0;
            let ground = Ground::new(&scene, held.atlas(), &held.detail);
            for &o in &wanted {
                match o {
                    Output::Rgb | Output::Flow => {}
                    Output::Depth => dict.set_item("depth", array(py, t.depth(), &[h, w])?)?,
                    Output::Distance => {
                        dict.set_item("distance", array(py, t.distance(), &[h, w])?)?
                    }
                    Output::Positions => {
                        dict.set_item("positions", array(py, t.positions.clone(), &[h, w, 4])?)?
                    }
                    Output::Latlon => {
                        let ll = t.latlon(held.atlas()).map_err(err)?;
                        dict.set_item("latlon", array(py, ll, &[h, w, 2])?)?
                    }
                    Output::Normals => {
                        let n = t.normals(&ground).map_err(err)?;
                        dict.set_item("normals", array(py, n, &[h, w, 3])?)?
                    }
                    Output::Surface => {
                        let c = r.classes.clone().unwrap_or_default();
                        dict.set_item("surface", array(py, c, &[h, w])?)?
                    }
                }
            }
        }
        let k = Intrinsics::of(&r.camera);
        let e = Extrinsics::of(&r.camera);
        dict.set_item("K", array(py, k.k.concat(), &[3, 3])?)?;
        dict.set_item(
            "world_to_camera",
            array(py, e.world_to_camera.concat(), &[4, 4])?,
        )?;
        dict.set_item(
            "camera_to_world",
            array(py, e.camera_to_world.concat(), &[4, 4])?,
        )?;
        Ok(dict)
    }

    /// The terrain's height (metres) at world point (x, y), its finest detail included; None
    /// where nothing is drawn (beyond the sketch with `sketch.outside = "void"`).
    fn height_at(&self, x: f64, y: f64) -> PyResult<Option<f64>> {
        let r = &self.held.0;
        let ground = Ground::new(&self.scene, r.atlas(), &r.detail);
        ground.height_at(glam::DVec2::new(x, y), 0.0).map_err(err)
    }

    /// The image size, (width, height).
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.scene.camera.width, self.scene.camera.height)
    }

    /// The level-of-detail scheme it draws with.
    #[getter]
    fn mode(&self) -> &'static str {
        self.mode.name()
    }

    /// The adapter it renders on, as wgpu names it.
    #[getter]
    fn adapter(&self) -> String {
        self.held.0.ctx().adapter_name()
    }

    fn __repr__(&self) -> String {
        let (w, h) = self.size();
        format!("terrain.Renderer({w}×{h}, mode={:?})", self.mode.name())
    }
}

/// What one render leaves: the picture, its camera, its pixels' points and surface classes when
/// asked for.
struct Rendered {
    rgba: Vec<u8>,
    camera: terrain_engine::Camera,
    truth: Option<Truth>,
    classes: Option<Vec<u8>>,
}

fn render(
    r: &mut terrain_engine::Renderer,
    classes: Option<&mut Held>,
    scene: &Scene,
    wanted: &[Output],
) -> terrain_engine::Result<Rendered> {
    if wanted.contains(&Output::Flow) {
        return Err(terrain_engine::Error::Value {
            key: "outputs",
            reason: "flow is between a flight's frames: `terrain fly --outputs flow` writes it"
                .into(),
        });
    }
    let camera = scene::camera_of(scene, r.atlas())?;
    // Each snapshot as if alone, as `terrain batch` renders its items.
    r.forget();
    r.relight(scene);
    let frame = r.render_settled(&camera)?;
    let truth = match wanted.iter().any(|&o| o != Output::Rgb) {
        true => Some(Truth::new(&camera, &r.read_positions(&camera)?)?),
        false => None,
    };
    let classes = match (classes, wanted.contains(&Output::Surface)) {
        (Some(c), true) => Some(terrain_engine::truth::surface_classes(&mut c.0, &camera)?),
        _ => None,
    };
    Ok(Rendered {
        rgba: frame.rgba,
        camera,
        truth,
        classes,
    })
}

/// `values` as a NumPy array of `shape`.
fn array<'py, T: numpy::Element>(
    py: Python<'py>,
    values: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    Ok(PyArray1::from_vec(py, values).reshape(shape)?.into_any())
}

/// N or (width, height).
fn image_size(size: &Bound<'_, PyAny>) -> PyResult<(u32, u32)> {
    let (w, h) = match size.extract::<u32>() {
        Ok(n) => (n, n),
        Err(_) => size.extract::<(u32, u32)>().map_err(|_| {
            fail(format!(
                "size {size}: give N or (width, height), whole pixels"
            ))
        })?,
    };
    if !(1..=16384).contains(&w) || !(1..=16384).contains(&h) {
        return Err(fail(format!("size {w}×{h}: each side 1 to 16384 pixels")));
    }
    Ok((w, h))
}

/// `n` random cameras over `scene`'s sketch, a pure function of (`seed`, index): those of a
/// jobs file's `[random]` with that seed, in order.
#[pyfunction]
#[pyo3(signature = (scene, n, seed = 0))]
fn random_cameras(py: Python<'_>, scene: &PyScene, n: usize, seed: u64) -> PyResult<Vec<PyCamera>> {
    let s = &scene.scene;
    let made = py.detach(|| -> terrain_engine::Result<Vec<PyCamera>> {
        let atlas = scene::load_atlas(s)?;
        let reach = scene::detail_of(s, &atlas).reach_m();
        (0..n)
            .map(|i| {
                let (placed, _) = scene::random_camera(s, &atlas, reach, seed, i)?;
                Ok(PyCamera::of_section(&placed.camera))
            })
            .collect()
    });
    made.map_err(err)
}

/// The native module.
#[pymodule]
fn _terrain(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_class::<PyCamera>()?;
    m.add_class::<PyRenderer>()?;
    m.add_function(wrap_pyfunction!(random_cameras, m)?)?;
    m.add_function(wrap_pyfunction!(devices_opened, m)?)?;
    m.add("Error", m.py().get_type::<Error>())?;
    let names: Vec<&str> = terrain_engine::truth::SURFACE_CLASSES
        .iter()
        .map(|(name, _)| *name)
        .collect();
    m.add("SURFACE_CLASSES", names)?;
    Ok(())
}
