//! The Python package's native module, `lobelight._lobelight`: the library's scenes and its
//! one renderer over either engine, with images handed back as numpy arrays. The Python side
//! (`lobelight/__init__.py`) writes dicts as scene text and hands arrays over by name; this
//! side copies each array once, into the library's mesh, and releases the GIL for the work.

use std::path::PathBuf;
use std::sync::Arc;

use glam::Vec3;
use numpy::{
    PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

use lobelight::bake::Progress;
use lobelight::camera::View;
use lobelight::error::Error;
use lobelight::frame::FrameConfig;
use lobelight::renderer::{BackendChoice, Engine, EngineChoice, Renderer};
use lobelight::scene::model::{LeftOut, Mesh};
use lobelight::scene::{self, Arrays, Scene};
use lobelight::tone::ToneConfig;

/// A scan's large arrays on huge pages, as the command allocates them.
#[global_allocator]
static ALLOCATOR: lobelight::large_pages::LargePages = lobelight::large_pages::LargePages;

create_exception!(
    _lobelight,
    LobelightError,
    PyException,
    "What lobelight refuses: a bad scene, file, array or parameter, or a device error. Its \
     message is the one line the command prints."
);

fn raise(e: Error) -> PyErr {
    LobelightError::new_err(e.to_string())
}

fn invalid(msg: String) -> PyErr {
    raise(Error::Invalid(msg))
}

/// A scene: its splats, materials, lights and camera, from a file or from scene text with
/// arrays.
#[pyclass(module = "lobelight._lobelight", name = "Scene", frozen)]
struct PyScene {
    scene: Arc<Scene>,
}

/// One array handed over: its name in the scene text and its parts.
type ArrayParts<'py> = (
    String,
    PyReadonlyArray2<'py, f32>,
    Option<PyReadonlyArray2<'py, f32>>,
    Option<PyReadonlyArray2<'py, f32>>,
    Option<PyReadonlyArray1<'py, f32>>,
    Option<PyReadonlyArray2<'py, u32>>,
);

/// An `n` × `width` array's rows as `T`s (`[f32; 3]`, `Vec3`, `[u32; 3]`): the one copy.
fn rows<T: bytemuck::Pod, E: numpy::Element + bytemuck::Pod>(
    name: &str,
    what: &str,
    a: &PyReadonlyArray2<'_, E>,
    width: usize,
) -> PyResult<Vec<T>> {
    let shape = a.shape();
    if shape[1] != width {
        return Err(invalid(format!(
            "array '{name}': {what} must be n × {width}, got {} × {}",
            shape[0], shape[1]
        )));
    }
    let flat = a
        .as_slice()
        .map_err(|_| invalid(format!("array '{name}': {what} is not contiguous")))?;
    Ok(bytemuck::cast_slice::<E, T>(flat).to_vec())
}

fn mesh_of(parts: &ArrayParts<'_>) -> PyResult<Mesh> {
    let (name, points, normals, colors, radii, faces) = parts;
    let positions: Vec<Vec3> = rows(name, "points", points, 3)?;
    let n = positions.len();
    let per_point = |what: &str, len: usize| {
        (len != n).then(|| invalid(format!("array '{name}': {len} {what} for {n} points")))
    };
    let normals = normals
        .as_ref()
        .map(|a| rows::<Vec3, f32>(name, "normals", a, 3))
        .transpose()?;
    let colors = colors
        .as_ref()
        .map(|a| rows::<[f32; 3], f32>(name, "colors", a, 3))
        .transpose()?;
    let radii = match radii {
        Some(r) => Some(
            r.as_slice()
                .map_err(|_| invalid(format!("array '{name}': radii is not contiguous")))?
                .to_vec(),
        ),
        None => None,
    };
    for (what, len) in [
        ("normals", normals.as_ref().map(Vec::len)),
        ("colors", colors.as_ref().map(Vec::len)),
        ("radii", radii.as_ref().map(Vec::len)),
    ] {
        if let Some(e) = len.and_then(|l| per_point(what, l)) {
            return Err(e);
        }
    }
    let faces = faces
        .as_ref()
        .map(|a| rows::<[u32; 3], u32>(name, "faces", a, 3))
        .transpose()?
        .unwrap_or_default();
    Ok(Mesh {
        positions,
        normals,
        colors,
        faces,
        radii,
        left_out: LeftOut::default(),
        ..Mesh::default()
    })
}

#[pymethods]
impl PyScene {
    /// Reads and builds a scene file (TOML, docs/scenes.md).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<PyScene> {
        let scene = py.detach(|| scene::load(&path)).map_err(raise)?;
        Ok(PyScene {
            scene: Arc::new(scene),
        })
    }

    /// Builds a scene from scene text, `path` naming it in errors and anchoring model paths,
    /// with the models that name an `array` taken from `arrays`: (name, points, normals,
    /// colours, radii, faces).
    #[staticmethod]
    fn parse(
        py: Python<'_>,
        text: String,
        path: PathBuf,
        arrays: Vec<ArrayParts<'_>>,
    ) -> PyResult<PyScene> {
        let mut meshes = Arrays::new();
        for parts in &arrays {
            meshes.insert(parts.0.clone(), mesh_of(parts)?);
        }
        drop(arrays);
        let scene = py
            .detach(|| scene::parse_with(&path, &text, &meshes))
            .map_err(raise)?;
        Ok(PyScene {
            scene: Arc::new(scene),
        })
    }

    /// How many splats the scene holds.
    #[getter]
    fn splats(&self) -> usize {
        self.scene.splats.len()
    }

    /// The camera's image size, (width, height).
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        let [w, h] = self.scene.camera.resolution;
        (w, h)
    }

    /// The names of its surfaces, in object-ID order: ID k + 1 is surface k.
    #[getter]
    fn surfaces(&self) -> Vec<String> {
        self.scene.surfaces.clone()
    }

    /// Bounds of its splats: ((x, y, z) lowest, (x, y, z) highest).
    #[getter]
    fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let (lo, hi) = self.scene.bounds();
        (lo.to_array(), hi.to_array())
    }

    fn __repr__(&self) -> String {
        let [w, h] = self.scene.camera.resolution;
        format!(
            "Scene({} splats, {} lights, {} surfaces, {w}×{h})",
            self.scene.splats.len(),
            self.scene.lights.len(),
            self.scene.surfaces.len()
        )
    }
}

/// The scene's renderer on one engine, chosen once: it bakes once and draws many views.
#[pyclass(module = "lobelight._lobelight", name = "Renderer")]
struct PyRenderer {
    renderer: Renderer,
    engine: Engine,
    /// Why the engine is the CPU mirror where a device was asked for or preferred.
    fallback: Option<String>,
    baked: bool,
    progress: bool,
    /// The last image's size, where one is drawn.
    last_size: Option<(u32, u32)>,
}

/// A camera: the scene's, with what the call gives in its place.
struct CameraArgs {
    eye: Option<[f32; 3]>,
    target: Option<[f32; 3]>,
    up: Option<[f32; 3]>,
    fov: Option<f32>,
    width: Option<u32>,
    height: Option<u32>,
}

impl PyRenderer {
    /// The view the arguments give, checked as the command checks an image size.
    fn view(&self, c: &CameraArgs) -> PyResult<View> {
        let scene = self.renderer.scene();
        let mut desc = scene.camera.clone();
        let finite = |v: [f32; 3]| v.iter().all(|x| x.is_finite());
        for (what, v) in [("eye", c.eye), ("target", c.target), ("up", c.up)] {
            if v.is_some_and(|v| !finite(v)) {
                return Err(invalid(format!("camera {what} must be finite, got {v:?}")));
            }
        }
        desc.eye = c.eye.unwrap_or(desc.eye);
        desc.target = c.target.unwrap_or(desc.target);
        desc.up = c.up.unwrap_or(desc.up);
        if let Some(fov) = c.fov {
            if !(fov > 0.0 && fov < 180.0) {
                return Err(invalid(format!(
                    "fov must be in (0, 180) degrees, got {fov}"
                )));
            }
            desc.fov = fov;
        }
        let forward = Vec3::from(desc.target) - Vec3::from(desc.eye);
        if forward.length_squared() == 0.0 || forward.cross(desc.up.into()).length_squared() == 0.0
        {
            return Err(invalid(
                "the camera's eye, target and up must span a view: eye ≠ target, up not along \
                 the view"
                    .into(),
            ));
        }
        let [w, h] = desc.resolution;
        let (w, h) = (c.width.unwrap_or(w), c.height.unwrap_or(h));
        scene::check_resolution(w, h).map_err(invalid)?;
        self.engine.check_image(w, h).map_err(raise)?;
        if !self.engine.is_device() {
            scene.budget.check_image(w, h).map_err(invalid)?;
        }
        Ok(View::new(&desc, w, h))
    }

    fn bake_now<'py>(
        &mut self,
        py: Python<'py>,
        cache: Option<PathBuf>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let progress = Progress::new(self.progress);
        let renderer = &mut self.renderer;
        let (report, hit) = py
            .detach(|| renderer.bake_cached(cache.as_deref(), &progress))
            .map_err(raise)?;
        self.baked = true;
        let json = serde_json::json!({
            "photons": report.photons,
            "binning": report.binning,
            "em": report.em,
            "cache_hit": hit,
        });
        py.import("json")?
            .call_method1("loads", (json.to_string(),))
    }
}

/// Linear RGBA rows as an h × w × 3 array (alpha left out).
fn hdr_array<'py>(
    py: Python<'py>,
    hdr: &[[f32; 4]],
    view: &View,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let rgb: Vec<f32> = hdr.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
    let (w, h) = (view.width as usize, view.height as usize);
    PyArray1::from_vec(py, rgb).reshape([h, w, 3])
}

/// RGBA8 pixels (red in the low byte) as an h × w × 3 array of bytes.
fn rgba8_array<'py>(
    py: Python<'py>,
    rgba: &[u32],
    width: usize,
    height: usize,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let bytes: Vec<u8> = rgba
        .iter()
        .flat_map(|&p| [p as u8, (p >> 8) as u8, (p >> 16) as u8])
        .collect();
    PyArray1::from_vec(py, bytes).reshape([height, width, 3])
}

fn engine_choice(engine: &str) -> PyResult<EngineChoice> {
    match engine {
        "auto" => Ok(EngineChoice::Auto),
        "cpu" | "mirror" => Ok(EngineChoice::Mirror),
        "gpu" | "device" => Ok(EngineChoice::Device),
        other => Err(invalid(format!(
            "engine must be 'auto', 'cpu' or 'gpu', got '{other}'"
        ))),
    }
}

#[pymethods]
impl PyRenderer {
    /// Opens the engine (`auto`: the device, or the CPU mirror where there is none or where
    /// it is a software rasterizer; `cpu`; `gpu`) and prepares the scene on it.
    #[new]
    #[pyo3(signature = (scene, engine = "auto", progress = false))]
    fn new(py: Python<'_>, scene: &PyScene, engine: &str, progress: bool) -> PyResult<PyRenderer> {
        let choice = engine_choice(engine)?;
        let scene = scene.scene.clone();
        let (engine, fallback, renderer) = py
            .detach(|| {
                let (engine, fallback) = Engine::open(choice, BackendChoice::Auto)?;
                let renderer = Renderer::new(scene, &engine)?;
                Ok::<_, Error>((engine, fallback, renderer))
            })
            .map_err(raise)?;
        Ok(PyRenderer {
            renderer,
            engine,
            fallback: fallback.map(|f| f.to_string()),
            baked: false,
            progress,
            last_size: None,
        })
    }

    /// Where it runs: "cpu" (the CPU mirror) or the device's backend ("vulkan", ...).
    #[getter]
    fn engine(&self) -> &'static str {
        self.engine.backend()
    }

    /// The engine in words: the adapter's name, or the CPU mirror and its threads.
    #[getter]
    fn adapter(&self) -> String {
        self.engine.adapter_and_threads()
    }

    /// Why the engine is the CPU mirror where a device was asked for or preferred, else None.
    #[getter]
    fn fallback(&self) -> Option<String> {
        self.fallback.clone()
    }

    /// Whether the scene's light is baked.
    #[getter]
    fn baked(&self) -> bool {
        self.baked
    }

    /// Bakes the scene's light (photons, lobes) for the views to come: from `cache` when that
    /// file was made for this scene and these bake settings, else baked and saved there.
    /// Returns the stages' report as a dict (the command's `--json` stages).
    #[pyo3(signature = (cache = None))]
    fn bake<'py>(
        &mut self,
        py: Python<'py>,
        cache: Option<PathBuf>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.bake_now(py, cache)
    }

    /// Draws a view: `method` "lobes" (the renderer: the bake's lobes, direct light by
    /// shadow rays, `spp` refinement frames; 0 is the frame a moving camera gets) or "path"
    /// (the path tracer of the same splats, `spp` samples a pixel). Bakes first where
    /// "lobes" needs it. Returns linear HDR radiance, height × width × 3, float32.
    #[pyo3(signature = (spp = 16, method = "lobes", eye = None, target = None, up = None, fov = None, width = None, height = None))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        spp: u32,
        method: &str,
        eye: Option<[f32; 3]>,
        target: Option<[f32; 3]>,
        up: Option<[f32; 3]>,
        fov: Option<f32>,
        width: Option<u32>,
        height: Option<u32>,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let cam = CameraArgs {
            eye,
            target,
            up,
            fov,
            width,
            height,
        };
        let view = self.view(&cam)?;
        let cfg = FrameConfig::default();
        let path = match method {
            "lobes" => false,
            "path" => true,
            other => {
                return Err(invalid(format!(
                    "method must be 'lobes' or 'path', got '{other}'"
                )));
            }
        };
        if path && spp == 0 {
            return Err(invalid("the path tracer needs spp of 1 or more".into()));
        }
        if !path && !self.baked {
            self.bake_now(py, None)?;
        }
        let renderer = &mut self.renderer;
        let hdr = py
            .detach(|| {
                if path {
                    renderer.draw_path(&view, &cfg, spp, |_| {})?;
                } else {
                    renderer.draw(&view, &cfg, spp, |_| {})?;
                }
                renderer.read_hdr()
            })
            .map_err(raise)?;
        self.last_size = Some((view.width, view.height));
        hdr_array(py, &hdr, &view)
    }

    /// Which surface each pixel shows (`Scene.surfaces`: ID k + 1 is surface k; 0 none,
    /// 65535 an edge between surfaces), height × width, uint16.
    #[pyo3(signature = (eye = None, target = None, up = None, fov = None, width = None, height = None))]
    #[allow(clippy::too_many_arguments)]
    fn object_ids<'py>(
        &self,
        py: Python<'py>,
        eye: Option<[f32; 3]>,
        target: Option<[f32; 3]>,
        up: Option<[f32; 3]>,
        fov: Option<f32>,
        width: Option<u32>,
        height: Option<u32>,
    ) -> PyResult<Bound<'py, PyArray2<u16>>> {
        let view = self.view(&CameraArgs {
            eye,
            target,
            up,
            fov,
            width,
            height,
        })?;
        let renderer = &self.renderer;
        let ids = py
            .detach(|| renderer.object_ids(&view, &FrameConfig::default()))
            .map_err(raise)?;
        PyArray1::from_vec(py, ids).reshape([view.height as usize, view.width as usize])
    }

    /// The last image tone-mapped as the command's PNG is (log-average, `key`, `exposure` in
    /// stops): height × width × 3, uint8, sRGB.
    #[pyo3(signature = (key = 0.18, exposure = 0.0))]
    fn tone_map<'py>(
        &mut self,
        py: Python<'py>,
        key: f32,
        exposure: f32,
    ) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let tone = tone_config(key, exposure)?;
        let (w, h) = self
            .last_size
            .ok_or_else(|| invalid("nothing drawn yet: call render first".into()))?;
        let renderer = &mut self.renderer;
        let toned = py.detach(|| renderer.tone_map(&tone)).map_err(raise)?;
        rgba8_array(py, &toned.rgba, w as usize, h as usize)
    }
}

/// An HDR image (height × width × 3, linear float32) tone-mapped as the command's PNG is, on
/// the CPU: height × width × 3, uint8, sRGB.
#[pyfunction]
#[pyo3(signature = (hdr, key = 0.18, exposure = 0.0))]
fn tone_map<'py>(
    py: Python<'py>,
    hdr: PyReadonlyArray3<'py, f32>,
    key: f32,
    exposure: f32,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let (flat, w, h) = image_rows(&hdr)?;
    let tone = tone_config(key, exposure)?;
    let rgba: Vec<[f32; 4]> = flat
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2], 1.0])
        .collect();
    let (toned, _) = py
        .detach(|| lobelight::cpu::host::tone_map(&tone, &rgba))
        .map_err(raise)?;
    rgba8_array(py, &toned, w as usize, h as usize)
}

/// The tone map the command's `--key` and `--exposure` give, checked as it checks them.
fn tone_config(key: f32, exposure: f32) -> PyResult<ToneConfig> {
    let tone = ToneConfig {
        key,
        exposure,
        ..ToneConfig::default()
    };
    tone.validate().map_err(raise)?;
    Ok(tone)
}

/// An image array's pixels, rows from the top, and its (width, height): height × width × 3,
/// contiguous.
fn image_rows<'a, T: numpy::Element>(
    a: &'a PyReadonlyArray3<'_, T>,
) -> PyResult<(&'a [T], u32, u32)> {
    let shape = a.shape();
    if shape[2] != 3 {
        return Err(invalid(format!(
            "an image must be height × width × 3, got {shape:?}"
        )));
    }
    let pixels = a
        .as_slice()
        .map_err(|_| invalid("the image is not contiguous".into()))?;
    Ok((pixels, shape[1] as u32, shape[0] as u32))
}

/// Writes an image: uint8 height × width × 3 (a tone-mapped image) as PNG, or float32 height ×
/// width × 3 (linear radiance) as EXR, by the file's extension.
#[pyfunction]
fn save(py: Python<'_>, path: PathBuf, image: &Bound<'_, PyAny>) -> PyResult<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let written = match ext.as_deref() {
        Some("png") => {
            let a: PyReadonlyArray3<'_, u8> = image
                .extract()
                .map_err(|_| invalid("a PNG is written from uint8 pixels (tone_map's)".into()))?;
            let (bytes, w, h) = image_rows(&a)?;
            let bytes = bytes.to_vec();
            py.detach(|| image::RgbImage::from_raw(w, h, bytes).map(|i| i.save(&path)))
        }
        Some("exr") => {
            let a: PyReadonlyArray3<'_, f32> = image.extract().map_err(|_| {
                invalid("an EXR is written from float32 radiance (render's)".into())
            })?;
            let (floats, w, h) = image_rows(&a)?;
            let floats = floats.to_vec();
            py.detach(|| image::Rgb32FImage::from_raw(w, h, floats).map(|i| i.save(&path)))
        }
        _ => {
            return Err(invalid(format!(
                "{}: the image must end in .png (uint8) or .exr (float32)",
                path.display()
            )));
        }
    };
    match written {
        Some(Ok(())) => Ok(()),
        Some(Err(e)) => Err(invalid(format!("{}: {e}", path.display()))),
        None => Err(invalid("the image's size does not match its pixels".into())),
    }
}

#[pymodule]
fn _lobelight(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_class::<PyRenderer>()?;
    m.add_function(wrap_pyfunction!(tone_map, m)?)?;
    m.add_function(wrap_pyfunction!(save, m)?)?;
    m.add("LobelightError", m.py().get_type::<LobelightError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
