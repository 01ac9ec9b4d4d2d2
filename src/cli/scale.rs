//! `lobelight bench scale`: generated terrain clouds of growing size (1, 3 and 10 M splats by
//! default), each written as a binary PLY with normals, then loaded, gridded, baked and drawn
//! on the device: the time of each step, the peak memory, and how each grows with the splat
//! count. The clouds and their scene files stay in the output folder (a later run reuses them),
//! so any step can be run again by hand with `lobelight render`. Bake options (`--photons`, …)
//! apply to every size.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;

use crate::bake::Progress;
use crate::camera::View;
use crate::cli::measure::median;
use crate::error::{Error, Result};
use crate::frame::FrameConfig;
use crate::renderer::{Engine, Renderer};
use crate::scene;
use crate::scene::file::CameraDesc;
use crate::timing::ms_since;

/// The splat counts `bench scale` measures unless told.
pub const DEFAULT_SIZES: [u64; 3] = [1_000_000, 3_000_000, 10_000_000];

/// The generated clouds' material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Material {
    /// Diffuse ground: the fit gathers irradiance alone (a lidar scan's case).
    Diffuse,
    /// Glossy Ward ground (specular 0.3, roughness 0.15): every splat's light needs lobes.
    Glossy,
}

impl Material {
    fn name(self) -> &'static str {
        match self {
            Material::Diffuse => "diffuse",
            Material::Glossy => "glossy",
        }
    }

    /// The scene file's material table.
    fn table(self) -> &'static str {
        match self {
            Material::Diffuse => "[materials.ground]\ndiffuse = [0.6, 0.55, 0.5]\n",
            Material::Glossy => {
                "[materials.ground]\ndiffuse = [0.4, 0.37, 0.33]\nspecular = 0.3\nroughness = 0.15\n"
            }
        }
    }
}

/// Moving frames timed per size (after one untimed frame), at `FRAME_SIZE`.
const TIMED_FRAMES: usize = 3;
const FRAME_SIZE: (u32, u32) = (512, 512);

/// Where the bake runs; the frames run on the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BakeEngine {
    Device,
    /// The CPU mirror, beside a software rasterizer (faster there).
    Mirror,
}

#[derive(Debug, Serialize)]
pub struct ScaleBench {
    pub adapter: String,
    pub backend: String,
    /// Where the bake ran (`device` or `mirror`).
    pub bake_engine: BakeEngine,
    pub material: Material,
    pub rows: Vec<ScaleRow>,
    /// How each time grows with the splat count from the smallest size to the largest: the
    /// exponent k in time ∝ splats^k (1 is linear).
    pub growth: Growth,
}

/// One cloud's figures. Times in milliseconds.
#[derive(Debug, Serialize)]
pub struct ScaleRow {
    pub splats: u64,
    pub file: String,
    pub file_bytes: u64,
    /// Reading the PLY into points and normals (`scene::model::load`), and its rate.
    pub read_ms: f64,
    pub read_mb_per_s: f64,
    /// The whole scene load: the read, then disks of the points (radii from the neighbour
    /// spacing, a k-d tree query per point) placed in the scene.
    pub load_ms: f64,
    /// Uploading the splats and building the splat grid on the device.
    pub grid_ms: f64,
    /// Building the mirror's splat grid, where the bake runs there (0 on the device).
    pub mirror_grid_ms: f64,
    /// Photons emitted by the bake (1 M, or `--photons`).
    pub photons: u64,
    pub photons_ms: f64,
    pub binning_ms: f64,
    pub em_ms: f64,
    /// Splats whose lobes were fitted, and glossy splats their shared fits served.
    pub splats_fitted: u32,
    pub splats_served: u32,
    /// Measures of a gather disk's covered share (one a coverage group of splats).
    pub coverages: u32,
    /// The direct bake: each splat's visibility of each light (0 where final gathering's
    /// served the frames: its time is in `em_ms`).
    pub direct_ms: f64,
    /// The part of `em_ms` that is final gathering's direct bake (every splat's, as the
    /// frames' is; 0 without final gathering).
    pub em_direct_ms: f64,
    /// Photons, binning, EM and the direct bake.
    pub bake_ms: f64,
    /// Median moving-camera frame at 512², tone map included.
    pub frame_ms: f64,
    /// The same of a close view straight down on a corner (`CORNER_VIEW`), which shows about
    /// a twelfth of the cloud: where most of a scan lies outside the view, the frame should
    /// cost what the part in view costs.
    pub corner_frame_ms: f64,
    /// Of the whole view's frame, each pass waited for (median of 3): the visibility pass
    /// with the selection before it, the attributes, the shade pass and the temporal pass (0);
    /// and the selection alone (the walk down the nodes, `splat_select`, the scan,
    /// `splat_list`), to tell what grows with the splats from what follows the pixels.
    pub passes_ms: [f64; 4],
    pub select_ms: f64,
    /// Peak resident memory of the process so far (sizes run smallest first, so it is this
    /// size's peak): on lavapipe device buffers live in it too. `None` off Linux.
    pub peak_rss_bytes: Option<u64>,
}

#[derive(Debug, Default, Serialize)]
pub struct Growth {
    pub load: f64,
    pub grid: f64,
    pub bake: f64,
    /// The lobe fit (EM) alone.
    pub em: f64,
    /// EM without final gathering's direct bake (`em_direct_ms`): what grows with the fits
    /// and the lit splats' estimate, apart from a stage that grows with every splat.
    pub em_without_direct: f64,
    pub frame: f64,
    pub peak_rss: Option<f64>,
    /// The largest cloud's frame time over the smallest's (a frame whose work followed what it
    /// draws, not the scene, would keep it near 1).
    pub frame_ratio: f64,
    /// The same ratio from frames drawn in turn: the median over rounds of one frame of each,
    /// the smallest cloud loaded and baked again beside the largest after the rows. Where the
    /// machine's load drifts, this is the figure to quote. None with one size.
    pub frame_ratio_interleaved: Option<f64>,
}

/// Bake settings from the command line, applied to each generated scene.
pub type Settings<'a> = &'a dyn Fn(&mut crate::scene::Scene) -> Result<()>;

/// Runs the scale benchmark for clouds of `sizes` splats of `material`, writing them to `dir`:
/// the frames on `device`, the bake on `baking` (the device, or the mirror beside it).
pub fn scale(
    (device, baking): (&Engine, &Engine),
    (sizes, material): (&[u64], Material),
    dir: &Path,
    settings: Settings,
) -> Result<ScaleBench> {
    if sizes.is_empty() || sizes.contains(&0) {
        return Err(Error::Invalid(
            "bench scale needs splat counts above 0 (--sizes 1000000,3000000)".into(),
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let mut sizes = sizes.to_vec();
    sizes.sort_unstable();
    let mut rows = Vec::new();
    // The largest cloud stays loaded and the smallest's scene file is kept, for their frames
    // in turn after the rows.
    let (mut largest, mut smallest_scene) = (None, None);
    for &n in &sizes {
        eprintln!("bench scale: {n} {} splats", material.name());
        let scene_path = write_terrain(dir, n, material)?;
        smallest_scene.get_or_insert_with(|| scene_path.clone());
        // One cloud on the device at a time, so that each row's peak memory is its own.
        drop(largest.take());
        let (row, drawn) = measure((device, baking), &scene_path, n, settings)?;
        rows.push(row);
        largest = Some(drawn);
    }
    let mut growth = growth(&rows);
    if let (Some(large), [smallest, _, ..], Some(path)) =
        (largest.as_mut(), sizes.as_slice(), &smallest_scene)
    {
        eprintln!(
            "bench scale: the {smallest}-splat cloud again, its frames and the largest's in turn"
        );
        let (mut small, _) = bake_cloud((device, baking), path, *smallest, settings)?;
        growth.frame_ratio_interleaved = Some(interleaved_ratio(&mut small, large)?);
    }
    Ok(ScaleBench {
        adapter: device.adapter(),
        backend: device.backend().into(),
        bake_engine: match baking.is_device() {
            true => BakeEngine::Device,
            false => BakeEngine::Mirror,
        },
        material,
        rows,
        growth,
    })
}

/// A generated cloud loaded, baked and ready to draw.
struct Drawn {
    scene: Arc<crate::scene::Scene>,
    renderer: Renderer,
}

/// `ScaleRow::corner_frame_ms`'s view: 0.7 above the terrain's corner quarter's centre, looking
/// straight down (45°: 0.58 × 0.58 of its 2 × 2).
const CORNER_VIEW: ([f32; 3], [f32; 3]) = ([-0.5, 0.7, -0.5], [-0.5, 0.0, -0.5]);

impl Drawn {
    /// One moving frame at `FRAME_SIZE` from the scene's camera, tone map included, waited
    /// for: its milliseconds.
    fn frame_ms(&mut self) -> Result<f64> {
        let camera = self.scene.camera.clone();
        self.frame_ms_from(&camera)
    }

    /// The same from `CORNER_VIEW`.
    fn corner_frame_ms(&mut self) -> Result<f64> {
        let camera = CameraDesc {
            eye: CORNER_VIEW.0,
            target: CORNER_VIEW.1,
            up: [0.0, 0.0, -1.0],
            ..self.scene.camera.clone()
        };
        self.frame_ms_from(&camera)
    }

    /// The scene camera's frame with each pass waited for (`Renderer::draw_timed`).
    fn passes_ms(&mut self) -> Result<[f64; 4]> {
        let view = View::new(&self.scene.camera, FRAME_SIZE.0, FRAME_SIZE.1);
        let passes = self.renderer.draw_timed(&view, &FrameConfig::default())?;
        passes.ok_or_else(on_a_device)
    }

    /// The scene camera's frame's selection alone (`Renderer::select_timed`).
    fn select_ms(&mut self) -> Result<f64> {
        let view = View::new(&self.scene.camera, FRAME_SIZE.0, FRAME_SIZE.1);
        let ms = self.renderer.select_timed(&view, &FrameConfig::default())?;
        ms.ok_or_else(on_a_device)
    }

    fn frame_ms_from(&mut self, camera: &CameraDesc) -> Result<f64> {
        let view = View::new(camera, FRAME_SIZE.0, FRAME_SIZE.1);
        let t = Instant::now();
        self.renderer
            .draw(&view, &FrameConfig::default(), 0, |_| {})?;
        self.renderer.tone(&crate::tone::ToneConfig::default())?;
        Ok(ms_since(t))
    }
}

fn on_a_device() -> Error {
    Error::internal("bench scale times each pass on a device")
}

/// Rounds of the smallest and largest clouds' frames in turn (`interleaved_ratio`).
const INTERLEAVED_ROUNDS: usize = 7;

/// The median over `INTERLEAVED_ROUNDS` of the largest cloud's frame time over the smallest's,
/// each round one frame of each, after one untimed frame of each: a busy machine's load
/// drifts over the minutes between the two rows' frames, not between two frames in turn.
fn interleaved_ratio(small: &mut Drawn, large: &mut Drawn) -> Result<f64> {
    small.frame_ms()?;
    large.frame_ms()?;
    let mut ratios = Vec::with_capacity(INTERLEAVED_ROUNDS);
    for _ in 0..INTERLEAVED_ROUNDS {
        let a = small.frame_ms()?;
        let b = large.frame_ms()?;
        ratios.push(b / a.max(1e-9));
    }
    Ok(median(ratios))
}

/// Loads, bakes and times cloud `n`'s frames: its row, and the cloud ready to draw again.
fn measure(
    engines: (&Engine, &Engine),
    scene_path: &Path,
    n: u64,
    settings: Settings,
) -> Result<(ScaleRow, Drawn)> {
    let (mut drawn, mut row) = bake_cloud(engines, scene_path, n, settings)?;
    row.frame_ms = median(timed(|| drawn.frame_ms())?);
    row.corner_frame_ms = median(timed(|| drawn.corner_frame_ms())?);
    let passes = timed(|| drawn.passes_ms())?;
    row.passes_ms = std::array::from_fn(|k| median(passes.iter().map(|p| p[k]).collect()));
    row.select_ms = median(timed(|| drawn.select_ms())?);
    row.peak_rss_bytes = crate::cli::measure::peak_rss_bytes();
    Ok((row, drawn))
}

/// `TIMED_FRAMES` measures of `measure`, after one untimed (its first frame builds and
/// compiles what later frames reuse).
fn timed<T>(mut measure: impl FnMut() -> Result<T>) -> Result<Vec<T>> {
    measure()?;
    (0..TIMED_FRAMES).map(|_| measure()).collect()
}

/// Loads and bakes cloud `n`: the cloud ready to draw, and its row but for the frames.
fn bake_cloud(
    (device, baking): (&Engine, &Engine),
    scene_path: &Path,
    n: u64,
    settings: Settings,
) -> Result<(Drawn, ScaleRow)> {
    let ply = terrain_file(scene_path.parent().unwrap_or(Path::new(".")), n);
    let file_bytes = std::fs::metadata(&ply)
        .map_err(|e| Error::io(&ply, e))?
        .len();
    // The parse alone, timed apart (the scene load below reads the file again).
    let t = Instant::now();
    drop(scene::model::load(&ply)?);
    let read_ms = ms_since(t);
    let t = Instant::now();
    let mut scene = scene::load(scene_path)?;
    let load_ms = ms_since(t);
    settings(&mut scene)?;
    let scene = Arc::new(scene);
    let mut renderer = Renderer::new(scene.clone(), device)?;
    let grid_ms = renderer.grid_ms();
    // Where final gathering ran, its direct bake serves the frames (its time is in the EM's):
    // a direct bake of its own here would count it twice.
    let lit = renderer.bake_lit(baking, &Progress::new(true))?;
    let (baked, direct_ms, mirror_grid_ms) = (lit.bake, lit.direct_ms, lit.grid_ms);
    let stage = |r: &crate::bake::StageReport| r.ms.unwrap_or(0.0);
    let (photons_ms, binning_ms, em_ms) = (
        stage(&baked.photons),
        stage(&baked.binning),
        stage(&baked.em),
    );
    let row = ScaleRow {
        splats: scene.splats.len() as u64,
        file: ply.display().to_string(),
        file_bytes,
        read_ms,
        read_mb_per_s: file_bytes as f64 / 1e6 / (read_ms / 1e3).max(1e-9),
        load_ms,
        grid_ms,
        mirror_grid_ms,
        photons: scene.bake.photons,
        photons_ms,
        binning_ms,
        em_ms,
        splats_fitted: baked.em.splats_fitted.unwrap_or(0),
        splats_served: baked.em.splats_served.unwrap_or(0),
        coverages: baked.em.coverages.unwrap_or(0),
        direct_ms,
        em_direct_ms: baked.em.direct_bake_ms.unwrap_or(0.0),
        bake_ms: photons_ms + binning_ms + em_ms + direct_ms,
        frame_ms: 0.0,
        corner_frame_ms: 0.0,
        passes_ms: [0.0; 4],
        select_ms: 0.0,
        peak_rss_bytes: None,
    };
    Ok((Drawn { scene, renderer }, row))
}

/// The exponent k of time ∝ splats^k between the first and last rows.
fn growth(rows: &[ScaleRow]) -> Growth {
    let (Some(a), Some(b)) = (rows.first(), rows.last()) else {
        return Growth::default();
    };
    let span = (b.splats as f64 / a.splats.max(1) as f64).ln();
    if rows.len() < 2 || span <= 0.0 {
        return Growth::default();
    }
    let k = |x: f64, y: f64| (y.max(1e-9) / x.max(1e-9)).ln() / span;
    Growth {
        load: k(a.load_ms, b.load_ms),
        grid: k(a.grid_ms, b.grid_ms),
        bake: k(a.bake_ms, b.bake_ms),
        em: k(a.em_ms, b.em_ms),
        em_without_direct: k(a.em_ms - a.em_direct_ms, b.em_ms - b.em_direct_ms),
        frame: k(a.frame_ms, b.frame_ms),
        frame_ratio: b.frame_ms / a.frame_ms.max(1e-9),
        frame_ratio_interleaved: None,
        peak_rss: match (a.peak_rss_bytes, b.peak_rss_bytes) {
            (Some(x), Some(y)) => Some(k(x as f64, y as f64)),
            _ => None,
        },
    }
}

fn terrain_file(dir: &Path, n: u64) -> PathBuf {
    dir.join(format!("terrain_{n}.ply"))
}

/// The height field of the generated terrain and its gradient.
fn height(x: f32, z: f32) -> (f32, f32, f32) {
    let h = 0.15 * (3.0 * x).sin() * (2.0 * z).cos() + 0.05 * (9.0 * x + 4.0 * z).sin();
    let dx = 0.45 * (3.0 * x).cos() * (2.0 * z).cos() + 0.45 * (9.0 * x + 4.0 * z).cos();
    let dz = -0.3 * (3.0 * x).sin() * (2.0 * z).sin() + 0.2 * (9.0 * x + 4.0 * z).cos();
    (h, dx, dz)
}

/// Writes the terrain of `n` points (a binary PLY with normals, unless one of that size is
/// already there) and its scene file in `material` (`terrain_N.toml`, glossy
/// `terrain_N_glossy.toml`); returns the scene file's path.
fn write_terrain(dir: &Path, n: u64, material: Material) -> Result<PathBuf> {
    let ply = terrain_file(dir, n);
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\n\
         property float y\nproperty float z\nproperty float nx\nproperty float ny\n\
         property float nz\nend_header\n"
    );
    let expected = header.len() as u64 + n * 24;
    let current = std::fs::metadata(&ply).map(|m| m.len()).ok();
    if current != Some(expected) {
        let file = std::fs::File::create(&ply).map_err(|e| Error::io(&ply, e))?;
        let mut out = std::io::BufWriter::with_capacity(1 << 20, file);
        let io = |e| Error::io(&ply, e);
        out.write_all(header.as_bytes()).map_err(io)?;
        let side = (n as f64).sqrt().ceil() as u64;
        let step = 2.0 / (side.max(2) - 1) as f32;
        for i in 0..n {
            let (x, z) = (
                -1.0 + (i % side) as f32 * step,
                -1.0 + (i / side) as f32 * step,
            );
            let (y, dx, dz) = height(x, z);
            let len = (dx * dx + 1.0 + dz * dz).sqrt();
            for v in [x, y, z, -dx / len, 1.0 / len, -dz / len] {
                out.write_all(&v.to_le_bytes()).map_err(io)?;
            }
        }
        out.flush().map_err(io)?;
    }
    let scene = match material {
        Material::Diffuse => dir.join(format!("terrain_{n}.toml")),
        Material::Glossy => dir.join(format!("terrain_{n}_glossy.toml")),
    };
    let text = format!(
        "# A generated {} terrain of {n} points (lobelight bench scale).\n\n\
         [camera]\neye = [0.0, 1.6, 2.2]\ntarget = [0.0, 0.0, 0.0]\nfov = 45\n\
         resolution = [512, 512]\n\n{}\n\
         [[light]]\ntype = \"directional\"\ndirection = [-0.6, -1.0, -0.4]\n\
         irradiance = [2.0, 1.9, 1.7]\n\n[[object]]\nshape = \"model\"\n\
         path = \"terrain_{n}.ply\"\nmaterial = \"ground\"\n",
        material.name(),
        material.table()
    );
    std::fs::write(&scene, text).map_err(|e| Error::io(&scene, e))?;
    Ok(scene)
}

fn mib(bytes: u64) -> String {
    format!("{:.0} MiB", bytes as f64 / (1 << 20) as f64)
}

impl std::fmt::Display for ScaleBench {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "device {} ({}), {} clouds, the bake on {}",
            self.adapter,
            self.backend,
            self.material.name(),
            match self.bake_engine {
                BakeEngine::Device => "the device",
                BakeEngine::Mirror => "the CPU mirror",
            }
        )?;
        writeln!(
            f,
            "{:>10} {:>8} {:>8} {:>8} {:>8} {:>9} {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} {:>9} {:>9}",
            "splats",
            "read ms",
            "MB/s",
            "load ms",
            "grid ms",
            "photons",
            "binning",
            "EM ms",
            "fits",
            "direct ms",
            "frame ms",
            "select ms",
            "corner ms",
            "peak"
        )?;
        for r in &self.rows {
            writeln!(
                f,
                "{:>10} {:>8.0} {:>8.0} {:>8.0} {:>8.0} {:>9.0} {:>8.0} {:>8.0} {:>8} {:>9.0} {:>9.0} {:>9.1} {:>9.0} {:>9}",
                r.splats,
                r.read_ms,
                r.read_mb_per_s,
                r.load_ms,
                r.grid_ms,
                r.photons_ms,
                r.binning_ms,
                r.em_ms,
                r.splats_fitted,
                r.direct_ms,
                r.frame_ms,
                r.select_ms,
                r.corner_frame_ms,
                r.peak_rss_bytes.map_or("-".into(), mib)
            )?;
        }
        let g = &self.growth;
        write!(
            f,
            "growth (time ∝ splats^k): load {:.2}, grid {:.2}, bake {:.2} (EM {:.2}, without its \
             direct bake {:.2}), frame {:.2} ({:.2}x from the smallest cloud to the largest)",
            g.load, g.grid, g.bake, g.em, g.em_without_direct, g.frame, g.frame_ratio
        )?;
        if let Some(r) = g.frame_ratio_interleaved {
            write!(f, "; frames in turn {r:.2}x")?;
        }
        if let Some(m) = g.peak_rss {
            write!(f, ", peak memory {m:.2}")?;
        }
        Ok(())
    }
}
