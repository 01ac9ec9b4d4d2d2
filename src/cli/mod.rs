//! The `lobelight` application: the command line and the commands, above the library.
//! Nothing below `cli` imports from it. The flags and `--json` keys are a contract for
//! scripts and benchmarks (docs/cli.md): extend them, never rename them.

pub mod bench;
pub mod cluster;
pub mod compare;
pub mod convolution;
pub mod info;
pub mod join;
pub mod measure;
mod output;
pub mod plot;
pub mod rebake;
pub mod render;
pub mod scale;
pub mod sweep;
pub mod view;

use std::path::PathBuf;
use std::process::ExitCode;

use crate::em::{EmConfig, Estimate, LobeFamily};
use crate::frame::{Direct, FrameConfig, Show, Splatter};
use crate::photons::PhotonConfig;
use crate::renderer::{BackendChoice, Engine, EngineChoice, Fallback};
use crate::scene::file::StoreRange;
use crate::tone::{ToneConfig, ToneMode};
use crate::{Error, Result, scene};
use clap::{Args, Parser, Subcommand, ValueEnum};

#[derive(Parser)]
#[command(
    name = "lobelight",
    version,
    about = "Global illumination on splats with Gaussian lobes, on the GPU"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// The memory budget of what a scene makes (its splats and decompressed files), e.g.
    /// `8G`; past it the scene is refused with the spacing or subsampling that fits. Default:
    /// half the machine's memory (or of `ulimit -v`); a scene file's `max_memory` sets it
    /// where this is not given.
    #[arg(long, global = true, value_parser = crate::budget::parse_size)]
    max_memory: Option<u64>,
    /// Refuse a model file at its first point that cannot be read or is not finite, instead
    /// of skipping such points and counting them (as `info`, `--stats` and `--json` report).
    #[arg(long, global = true)]
    strict: bool,
}

/// Where stages run, shared by the subcommands.
#[derive(Args, Clone, Copy)]
struct DeviceArgs {
    /// Run the CPU mirror instead of the GPU.
    #[arg(long)]
    cpu: bool,
    /// Run on the GPU adapter even where it is a software rasterizer (lavapipe, llvmpipe),
    /// whose bake and still images the CPU mirror renders faster.
    #[arg(long, conflicts_with = "cpu")]
    gpu: bool,
    /// Graphics API (default: WGPU_BACKEND, else Vulkan, else GL).
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    backend: BackendChoice,
}

/// `--shard K/N`: two whole numbers with K below N; or `auto`, the scheduler's (`shard_from`).
fn parse_shard(s: &str) -> std::result::Result<(u32, u32), String> {
    if s == "auto" {
        return shard_from(|name| std::env::var(name).ok());
    }
    let bad = || format!("`{s}` is not K/N (two whole numbers, K below N, e.g. 0/4) or auto");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n) = (
        k.trim().parse::<u32>().map_err(|_| bad())?,
        n.trim().parse::<u32>().map_err(|_| bad())?,
    );
    if k < n { Ok((k, n)) } else { Err(bad()) }
}

/// Where `--shard auto` finds the shard count of a Kubernetes Indexed Job, which sets the
/// index (`JOB_COMPLETION_INDEX`) but not the count: the Job's manifest passes its
/// `completions` here.
pub const SHARD_COUNT_VAR: &str = "LOBELIGHT_SHARDS";

/// `--shard auto`: this task's shard K/N from the scheduler that started it, through `get`
/// (the environment): a SLURM job array (`SLURM_ARRAY_TASK_ID` in steps of
/// `SLURM_ARRAY_TASK_STEP` from `SLURM_ARRAY_TASK_MIN`, `SLURM_ARRAY_TASK_COUNT` tasks), or a
/// Kubernetes Indexed Job (`JOB_COMPLETION_INDEX` of `SHARD_COUNT_VAR`).
pub fn shard_from(get: impl Fn(&str) -> Option<String>) -> std::result::Result<(u32, u32), String> {
    let number = |name: &str| -> std::result::Result<Option<u32>, String> {
        get(name)
            .map(|v| {
                (v.trim().parse::<u32>()).map_err(|_| format!("{name}={v} is no whole number"))
            })
            .transpose()
    };
    let shard = if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
        let count = number("SLURM_ARRAY_TASK_COUNT")?
            .ok_or("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")?;
        let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
        let k = id
            .checked_sub(min)
            .filter(|d| d % step == 0)
            .map(|d| d / step);
        let range = || {
            format!(
                "task {id} of a SLURM array of {count} from {min} in steps of {step} is not \
                 one of a range (--array=0-{}): give --shard K/N",
                count.saturating_sub(1)
            )
        };
        (k.ok_or_else(range)?, count)
    } else if let Some(index) = number("JOB_COMPLETION_INDEX")? {
        let count = number(SHARD_COUNT_VAR)?.ok_or_else(|| {
            format!(
                "JOB_COMPLETION_INDEX is {index} but the shard count is unknown: set \
                 {SHARD_COUNT_VAR} to the Job's completions"
            )
        })?;
        (index, count)
    } else {
        return Err(
            "--shard auto: neither a SLURM array (SLURM_ARRAY_TASK_ID) nor a \
                    Kubernetes Indexed Job (JOB_COMPLETION_INDEX) started this task: give \
                    --shard K/N"
                .into(),
        );
    };
    match shard {
        (k, n) if k < n => Ok((k, n)),
        (k, n) => Err(format!("--shard auto: task {k} of {n} is past the count")),
    }
}

impl DeviceArgs {
    /// The engine these flags choose where the work would take `auto` (`EngineChoice`):
    /// `--cpu` the mirror, `--gpu` or a named backend the device, a software rasterizer too.
    /// One line on stderr says where the engine is not the device asked for.
    fn engine(&self, auto: EngineChoice) -> Result<Engine> {
        let choice = if self.cpu {
            EngineChoice::Mirror
        } else if self.gpu || self.backend != BackendChoice::Auto {
            EngineChoice::Device
        } else {
            auto
        };
        let (engine, fallback) = Engine::open(choice, self.backend)?;
        match fallback {
            Some(why @ Fallback::Software(_)) => {
                eprintln!("lobelight: {why} (--gpu runs them on it)")
            }
            Some(why) => eprintln!("lobelight: {why}"),
            None => {}
        }
        Ok(engine)
    }

    /// Where the bake runs beside the device `draw` that draws: the mirror where it is a
    /// software rasterizer and neither `--gpu` nor `--backend` asks for it (the mirror outruns
    /// it at baking), else the device itself.
    fn bake_engine(&self, draw: &Engine) -> Engine {
        match draw.is_software() && !self.gpu && self.backend == BackendChoice::Auto {
            true => Engine::Mirror,
            false => draw.clone(),
        }
    }
}

/// Bake settings that override the scene file's `[bake]`.
#[derive(Args, Clone)]
struct BakeArgs {
    /// Photons to emit.
    #[arg(long)]
    photons: Option<u64>,
    /// Seed of the bake's random numbers (the photons') and of the path tracer's; the frames'
    /// shadow rays keep theirs. The same scene and seed give the same image on one device.
    #[arg(long)]
    seed: Option<u32>,
    /// Which hits store photons.
    #[arg(long, value_enum)]
    store: Option<StoreRange>,
    /// EM iterations of the lobe fit.
    #[arg(long)]
    iterations: Option<u32>,
    /// Lobes per splat (1–8).
    #[arg(long)]
    lobes: Option<u32>,
    /// Photon search radius (scene units).
    #[arg(long)]
    radius: Option<f32>,
    /// Lobe family.
    #[arg(long, value_enum)]
    family: Option<LobeFamily>,
    /// Sparse EM (responsibilities under 0.02 frozen between full updates).
    #[arg(long)]
    sparse: bool,
    /// Keep all `--lobes` on every fitted splat (no pruning of the lobes its photons do not
    /// need).
    #[arg(long)]
    fixed_lobes: bool,
    /// Most candidate photons one splat's lobe fit visits per pass (0: all); past it an even
    /// subset, reweighted (irradiance still sums every photon).
    #[arg(long, value_name = "N")]
    fit_candidates: Option<u32>,
    /// Final gathering: glossy splats fit their lobes to N × N rays cast from their centres
    /// (each bringing back the baked light of the diffuse surface it meets) instead of to the
    /// photons within the search radius (0: the photons).
    #[arg(long, value_name = "N")]
    gather: Option<u32>,
    /// Where the splats' photon irradiance comes from: each splat's deposit shared with its
    /// neighbours (time bounded by splats; with final gathering) or every photon within the
    /// search radius.
    #[arg(long, value_enum)]
    estimate: Option<Estimate>,
    /// Shared fits: fitted splats within one cell of this many search radii, facing alike,
    /// share one lobe fit whose rays all of them cast (0: each splat fits its own lobes).
    #[arg(long, value_name = "RADII")]
    share: Option<f32>,
    /// The photons' estimate widened where the light is smooth: each splat takes the widest of
    /// its own and its surface's means within half of and all of this many search radii that
    /// agrees with the narrower within their noise (0: no smoothing).
    #[arg(long, value_name = "RADII")]
    smooth: Option<f32>,
}

impl BakeArgs {
    fn apply(&self, scene: &mut scene::Scene) -> Result<()> {
        if let Some(n) = self.photons {
            scene.bake.photons = n;
        }
        if let Some(s) = self.seed {
            scene.bake.seed = s;
        }
        if let Some(s) = self.store {
            scene.bake.store = s;
        }
        if let Some(i) = self.iterations {
            scene.bake.iterations = i;
        }
        if let Some(k) = self.lobes {
            scene.bake.lobes = k;
        }
        if let Some(r) = self.radius {
            scene.bake.radius = Some(r);
            (scene.check_radius()).map_err(|m| Error::Invalid(format!("--radius: {m}")))?;
        }
        if let Some(f) = self.family {
            scene.bake.family = f;
        }
        if let Some(n) = self.fit_candidates {
            scene.bake.fit_candidates = n;
        }
        if let Some(n) = self.gather {
            scene.bake.gather = n;
        }
        if let Some(e) = self.estimate {
            scene.bake.estimate = e;
        }
        if let Some(r) = self.share {
            scene.bake.share = r;
        }
        if let Some(r) = self.smooth {
            scene.bake.smooth = r;
        }
        scene.bake.sparse |= self.sparse;
        scene.bake.prune &= !self.fixed_lobes;
        PhotonConfig::from_scene(scene).validate()?;
        EmConfig::from_scene(scene).validate()
    }
}

/// Settings of a frame: shading and tone mapping; none of them needs a new bake.
#[derive(Args, Clone)]
struct LookArgs {
    /// Tone mapping of PNG output (EXR keeps linear radiance).
    #[arg(long, value_enum, default_value_t = ToneMode::Reinhard)]
    tonemap: ToneMode,
    /// The display value the log-average luminance maps to.
    #[arg(long, default_value_t = 0.18)]
    key: f32,
    /// Exposure in stops, after the operator.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// Area lights: shadow-ray samples per pixel along each edge (N² in all).
    #[arg(long, default_value_t = 4)]
    area_samples: u32,
    /// Which light to show: all of it, or one part.
    #[arg(long, value_enum, default_value_t = Show::Full)]
    show: Show,
    /// Direct light of a moving frame: the bake's per-splat visibility, or shadow rays per
    /// pixel. Still images (`render`, a resting viewer) refine with shadow rays.
    #[arg(long, value_enum, default_value_t = Direct::Baked)]
    direct: Direct,
    /// How splats become pixels: two raster passes, the compute splatter over screen tiles,
    /// or whichever is faster on this kind of device.
    #[arg(long, value_enum, default_value_t = Splatter::Auto)]
    splatter: Splatter,
    /// Level of detail of a moving frame, in pixels: neighbouring splats are drawn merged into
    /// one larger disk wherever that disk projects at most this many pixels in radius (0: every
    /// splat as it is). Still images draw them all.
    #[arg(long, default_value_t = crate::frame::DEFAULT_LOD)]
    lod: f32,
    /// Rays a pixel and refinement frame that trace glossy surfaces' indirect light, each
    /// bringing back the baked light of the surface it meets (0: their lobes give it, as in a
    /// moving frame). Still images only.
    #[arg(long, value_name = "N", default_value_t = crate::frame::DEFAULT_GLOSSY_RAYS)]
    glossy_rays: u32,
    /// Temporal anti-aliasing of moving frames: each jittered and blended with the ones
    /// before it, reprojected (by default each is drawn alone at the pixel centres; see
    /// docs/measurements.md, "Moving frames that remember").
    #[arg(long)]
    taa: bool,
    /// What the camera sees where it sees nothing: `sky` (the sky and the sun's disk; black
    /// without them), `black`, or a linear colour `r,g,b`. Default: the scene's `background`.
    #[arg(long, value_parser = scene::file::Background::parse)]
    background: Option<scene::file::Background>,
}

impl LookArgs {
    /// The scene's background as the command line sets it.
    fn apply_background(&self, scene: &mut scene::Scene) {
        if let Some(b) = self.background {
            scene.camera.background = b;
        }
    }

    fn frame(&self) -> FrameConfig {
        FrameConfig {
            area_samples: self.area_samples,
            show: self.show.terms(),
            direct: self.direct,
            splatter: self.splatter,
            lod: self.lod,
            glossy_rays: self.glossy_rays,
            temporal: self.taa,
            ..FrameConfig::default()
        }
    }

    fn tone(&self) -> ToneConfig {
        ToneConfig {
            mode: self.tonemap,
            key: self.key,
            exposure: self.exposure,
            ..ToneConfig::default()
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// Splats, lights, materials, bounds, grid and memory of a scene, and the device in use.
    Info(InfoArgs),
    /// Render a scene to an image: PNG (tone-mapped) or EXR (linear HDR).
    Render(RenderArgs),
    /// Difference of image A against the reference B: relMSE, PSNR, SMAPE, FLIP, mean
    /// relative difference, pixels within 5 %, RMSE, energy (EXR for radiance, FLIP on the
    /// tone-mapped pair; PNG compares display values).
    Compare(CompareArgs),
    /// A window that draws the scene in real time: direct light at once, global illumination
    /// when the bake (on a second thread) is in. Keys: see docs/viewer.md (H in the window).
    View(ViewArgs),
    /// Measure a stage: throughput and the figures that show it did the right work.
    Bench(BenchArgs),
    /// The numbered frames a sequence's shards wrote (`render --views FILE --shard K/N -o
    /// NAME_####.png`), joined in order into one MP4 video.
    Join(JoinArgs),
}

/// The arguments of `lobelight join`.
#[derive(Args)]
struct JoinArgs {
    /// The frames' numbered name, as the shards were given it: NAME_####.png (a run of #), or
    /// NAME.png for NAME_NNNN.png.
    frames: PathBuf,
    /// The video, .mp4.
    #[arg(short, long)]
    output: PathBuf,
    /// Frames a second.
    #[arg(long, default_value_t = scene::views::DEFAULT_FPS)]
    fps: f32,
}

/// The arguments of `lobelight info`.
#[derive(Args)]
struct InfoArgs {
    scene: PathBuf,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    device: DeviceArgs,
}

/// The arguments of `lobelight render`.
#[derive(Args)]
struct RenderArgs {
    scene: PathBuf,
    /// Output image, .png or .exr.
    #[arg(short, long)]
    output: PathBuf,
    /// What to draw: `lobes` renders; `photons` shows the stored photons as points.
    #[arg(long, value_enum, default_value_t = render::Method::Lobes)]
    method: render::Method,
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Load the bake from FILE when it was made for this scene and these bake settings;
    /// else bake and save it there.
    #[arg(long, value_name = "FILE")]
    cache: Option<PathBuf>,
    /// Samples per pixel of the still image: refinement frames, each jittered within the
    /// pixel and with its share of the shadow rays, averaged (1: one exact frame at the
    /// pixel centres, no anti-aliasing; 0: the frame a moving camera gets, with --direct).
    #[arg(long, default_value_t = render::DEFAULT_SPP, value_parser = clap::value_parser!(u32).range(0..=65536))]
    spp: u32,
    #[command(flatten)]
    bake: BakeArgs,
    #[command(flatten)]
    look: LookArgs,
    #[command(flatten)]
    device: DeviceArgs,
    /// Print per-stage figures on stderr.
    #[arg(long)]
    stats: bool,
    /// Print the figures as one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Also write which surface each pixel shows (16-bit grey PNG; names in FILE.json
    /// beside it), for `compare --objects`.
    #[arg(long, value_name = "FILE.png")]
    object_ids: Option<PathBuf>,
    /// An image sequence from one bake: the cameras FILE lists ([[view]] tables, an [orbit],
    /// a [path] of keyframes, or a nerfstudio camera-path .json), each written to OUT
    /// numbered (a run of # in its name, else _NNNN), or as one video where OUT ends in .mp4.
    #[arg(long, value_name = "FILE")]
    views: Option<PathBuf>,
    /// Frames a second of an .mp4 video. Default: the views file's (its [path]'s or the
    /// camera path's `fps`), else 30.
    #[arg(long, requires = "views")]
    fps: Option<f32>,
    /// With --views: draw only the views whose index is K modulo N (K in 0..N), so N
    /// machines that share the bake cache split the sequence; `auto`: K and N from a SLURM
    /// job array or a Kubernetes Indexed Job (with LOBELIGHT_SHARDS, its completions).
    #[arg(long, value_name = "K/N", value_parser = parse_shard, requires = "views")]
    shard: Option<(u32, u32)>,
}

/// The arguments of `lobelight compare`.
#[derive(Args)]
struct CompareArgs {
    a: PathBuf,
    b: PathBuf,
    /// Write the per-pixel relative difference as a heat map (red 5 %, yellow ≥ 25 %).
    #[arg(long, value_name = "OUT.png")]
    heatmap: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Also report the figures per object, over the pixels this object-ID image gives
    /// each (render --object-ids; edge pixels left out).
    #[arg(long, value_name = "IDS.png")]
    objects: Option<PathBuf>,
}

/// The arguments of `lobelight view`.
#[derive(Args)]
struct ViewArgs {
    scene: PathBuf,
    #[arg(long)]
    width: Option<u32>,
    #[arg(long)]
    height: Option<u32>,
    /// Scripted run: draw N frames once the bake is in, then exit.
    #[arg(long, value_name = "N")]
    frames: Option<u32>,
    /// Refinement frames a resting camera adds to its still image, each jittered and with
    /// its share of shadow rays (render --spp's frames; 0: never refine, every frame a
    /// moving frame).
    #[arg(long, default_value_t = render::DEFAULT_SPP, value_parser = clap::value_parser!(u32).range(0..=65536))]
    spp: u32,
    /// With --frames: save the last frame here (PNG).
    #[arg(long, value_name = "OUT.png", requires = "frames")]
    screenshot: Option<PathBuf>,
    /// Moving frames' target time: where they would take longer they are drawn at a lower
    /// internal resolution (the title shows it) and upsampled to the window; a resting
    /// camera refines at the window's size. 0: always the window's size. Default 33, but
    /// a scripted run (--frames) draws at the window's size unless given.
    #[arg(long, value_name = "MS")]
    target_ms: Option<f64>,
    /// With --frames: degrees the camera turns about its up axis before each frame after
    /// the first (a scripted orbit: every frame a moving frame).
    #[arg(
        long,
        value_name = "DEGREES",
        requires = "frames",
        default_value_t = 0.0
    )]
    turn: f32,
    /// Load the bake from FILE when it was made for this scene and these bake settings
    /// (an instant start); else bake and save it there.
    #[arg(long, value_name = "FILE")]
    cache: Option<PathBuf>,
    /// What the window shows first (keys R and M switch).
    #[arg(long, value_enum, default_value_t = render::Method::Lobes)]
    method: render::Method,
    #[command(flatten)]
    bake: BakeArgs,
    #[command(flatten)]
    look: LookArgs,
    /// Graphics API (default: WGPU_BACKEND, else Vulkan, else GL).
    #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
    backend: BackendChoice,
    /// Bake on the window's adapter even where it is a software rasterizer (lavapipe,
    /// llvmpipe), whose bakes the CPU mirror runs faster; frames are drawn on it either way.
    #[arg(long)]
    gpu: bool,
}

/// The arguments of `lobelight bench`.
#[derive(Args)]
struct BenchArgs {
    #[arg(value_enum)]
    what: BenchKind,
    /// Scenes to measure (all kinds but `convolution`, which needs none).
    scenes: Vec<PathBuf>,
    /// Where files the benchmark writes go (`convolution` heat maps; `sweep` tables,
    /// charts and reference images).
    #[arg(short, long, value_name = "DIR", default_value = ".")]
    output: PathBuf,
    #[command(flatten)]
    bake: BakeArgs,
    #[command(flatten)]
    look: LookArgs,
    #[command(flatten)]
    device: DeviceArgs,
    /// Print one JSON object per scene on stdout (an array for several scenes).
    #[arg(long)]
    json: bool,
    /// `frame` only: also draw 10 moving frames of the scene's camera in a 1280×720 window
    /// (needs a display; one scene), the figures under the key `window`.
    #[arg(long)]
    window: bool,
    /// `frame --window` only: the window draws a 30-frame orbit instead, with this target
    /// frame time (the viewer's `--target-ms`; 33 is its default), under the key
    /// `window_orbit`, each checked frame against its view's still image.
    #[arg(long, value_name = "MS", requires = "window")]
    target_ms: Option<f64>,
    /// `sweep` only: turn only these knobs (path, photons, iterations, radius, lobes,
    /// splats, family, prune, share, smooth), comma-separated; default all.
    #[arg(long, value_delimiter = ',')]
    knobs: Vec<String>,
    /// `scale` only: the splat counts of the generated clouds, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = scale::DEFAULT_SIZES)]
    sizes: Vec<u64>,
    /// `scale` only: the generated clouds' material.
    #[arg(long, value_enum, default_value_t = scale::Material::Diffuse)]
    material: scale::Material,
    /// `cluster` only: the dense cloud's splat count.
    #[arg(long, value_name = "N", default_value_t = cluster::DEFAULT_CLUSTER)]
    cluster_splats: u64,
    /// `frame` only: moving frames of a scripted orbit (the scene's camera turned by
    /// half a degree a frame) each compared with its view's still image, under the key
    /// `orbit` (0: none).
    #[arg(long, value_name = "FRAMES", default_value_t = bench::ORBIT_FRAMES)]
    orbit: u32,
}

#[derive(Clone, Copy, ValueEnum)]
enum BenchKind {
    /// Photon emission and tracing: photons_per_s, stored count, per-stage ms.
    Photons,
    /// Photon binning and the lobe fit: fits_per_s, em_ms, mean photons, fit error.
    Em,
    /// Frames of the baked scene at 512² and 1920×1080: frame_ms, fps, shade and tone map.
    Frame,
    /// What a moved light costs: the viewer's preview and full re-bake on the scene already
    /// on the device, rebake_ms, preview_ms and the preview's error.
    Rebake,
    /// The lobe × BRDF shading formulas against quadrature: relative L2 and energy errors
    /// of the thesis's form and ours, with heat maps (no scene).
    Convolution,
    /// Bake time, frame time and error against the photon-map reference while one setting
    /// varies at a time (photons, iterations, radius, lobes, splats, family): tables and charts.
    Sweep,
    /// Generated terrain clouds of growing size (`--sizes`, default 1, 3 and 10 M splats)
    /// written as PLY to the output folder: load, grid, bake and frame time, peak memory and
    /// how each grows with the splat count (no scene).
    Scale,
    /// Rays through a small dense cloud (`--cluster-splats`, default 200 k, in 1 % of the
    /// room) against rays through the room with an ordinary block: photons/s, gathering
    /// rays/s and how many times slower the cloud's are (no scene; written to the output
    /// folder).
    Cluster,
}

fn to_json<T: serde::Serialize>(value: &T) -> Result<serde_json::Value> {
    serde_json::to_value(value).map_err(|e| Error::Invalid(e.to_string()))
}

/// A line on stdout. A reader that went away (`| head`) is not an error of ours: the output
/// simply stops, where `println!` would panic.
fn say(args: std::fmt::Arguments) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout().lock(), "{args}");
}

/// A command's figures: one JSON object, or its human-readable text.
fn print_report<T: serde::Serialize + std::fmt::Display>(json: bool, report: &T) -> Result<()> {
    if json {
        print_json(report)
    } else {
        say(format_args!("{report}"));
        Ok(())
    }
}

fn print_json<T: serde::Serialize>(value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::Invalid(e.to_string()))?;
    say(format_args!("{text}"));
    Ok(())
}

/// `--target-ms` of `view` and `bench frame --window`: a time, 0 for none.
fn checked_target_ms(ms: f64) -> Result<f64> {
    match ms.is_finite() && ms >= 0.0 {
        true => Ok(ms),
        false => Err(Error::Invalid(format!(
            "--target-ms must be a time of 0 ms or more, not {ms}"
        ))),
    }
}

/// Loads a scene, saying on stderr where a model's points were skipped (they could not be
/// read or were not finite: `--strict` refuses them).
fn load_scene(path: &std::path::Path) -> Result<scene::Scene> {
    let scene = scene::load(path)?;
    if let (n @ 1.., Some(first)) = scene.skipped_points() {
        eprintln!(
            "warning: skipped {n} model points that could not be read or are not finite (the \
             first: {first}); --strict refuses them"
        );
    }
    Ok(scene)
}

fn run(cli: Cli) -> Result<()> {
    if let Some(bytes) = cli.max_memory {
        crate::budget::set_default(bytes);
    }
    scene::model::reading::set_strict(cli.strict);
    match cli.command {
        Command::Info(args) => info_command(args),
        Command::Render(args) => render_command(args),
        Command::View(args) => view_command(args),
        Command::Compare(args) => compare_command(args),
        Command::Bench(args) => bench_command(args),
        Command::Join(args) => join_command(args),
    }
}

/// `lobelight join`.
fn join_command(args: JoinArgs) -> Result<()> {
    if render::ImageFormat::of(&args.output)? != render::ImageFormat::Mp4 {
        return Err(Error::Invalid(format!(
            "{}: join writes a video: its name must end in .mp4",
            args.output.display()
        )));
    }
    scene::path::check_fps(args.fps).map_err(|m| Error::Invalid(format!("--fps: {m}")))?;
    output::check_writable(&args.output, "video")?;
    let frames = join::join(&args.frames, &args.output, args.fps, true)?;
    eprintln!(
        "wrote {} ({frames} frames at {} fps)",
        args.output.display(),
        args.fps
    );
    Ok(())
}

/// `lobelight bench`: the kinds with inputs of their own one function each, the kinds run over
/// scenes (photons, em, frame, rebake) one.
fn bench_command(args: BenchArgs) -> Result<()> {
    match args.what {
        BenchKind::Convolution => bench_convolution(args),
        BenchKind::Scale => bench_scale(args),
        BenchKind::Cluster => bench_cluster(args),
        BenchKind::Sweep => bench_sweep(args),
        _ => bench_scenes(args),
    }
}

/// `lobelight info`.
fn info_command(args: InfoArgs) -> Result<()> {
    let InfoArgs {
        scene,
        json,
        device,
    } = args;
    let scene = std::sync::Arc::new(load_scene(&scene)?);
    let engine = device.engine(EngineChoice::Device)?;
    let info = info::info(&scene, &engine)?;
    print_report(json, &info)?;
    Ok(())
}

/// `lobelight render`.
fn render_command(args: RenderArgs) -> Result<()> {
    let RenderArgs {
        scene,
        output,
        method,
        width,
        height,
        cache,
        spp,
        bake,
        look,
        device,
        stats,
        json,
        object_ids,
        views,
        fps,
        shard,
    } = args;
    if let Some(path) = &object_ids {
        compare::check_ids_path(path)?;
        output::check_writable(path, "object-ID image")?;
    }
    // Where the work will be written, before the work.
    output::check_writable(&output, "image")?;
    if let Some(path) = &cache {
        output::check_writable(path, "bake cache")?;
    }
    let mut scene = load_scene(&scene)?;
    bake.apply(&mut scene)?;
    look.apply_background(&mut scene);
    let list = match &views {
        Some(path) => scene::views::load_list(path, &scene.camera)?,
        None => scene::views::ViewList::default(),
    };
    let fps = fps.or(list.fps).unwrap_or(scene::views::DEFAULT_FPS);
    scene::path::check_fps(fps).map_err(|m| Error::Invalid(format!("--fps: {m}")))?;
    let views = list.cameras;
    let scene = std::sync::Arc::new(scene);
    let engine = device.engine(EngineChoice::Auto)?;
    let opts = render::Options {
        views,
        fps,
        shard,
        method,
        width,
        height,
        progress: !json,
        frame: look.frame(),
        tone: look.tone(),
        cache,
        spp,
    };
    let report = render::render(&scene, &engine, &opts, &output)?;
    if let Some(path) = object_ids {
        render::write_object_ids(&scene, &opts, &path)?;
    }
    if json {
        print_json(&report)?;
    } else if stats {
        eprintln!("{report}");
    } else if let Some(v) = &report.video {
        eprintln!(
            "wrote {} ({} frames at {} fps, {}×{})",
            report.output, v.frames, v.fps, report.width, report.height
        );
    } else if let (Some(first), Some(last)) = (report.views.first(), report.views.last()) {
        eprintln!(
            "wrote {} views ({} … {}, {}×{})",
            report.views.len(),
            first.output,
            last.output,
            report.width,
            report.height
        );
    } else {
        eprintln!(
            "wrote {} ({}×{})",
            report.output, report.width, report.height
        );
    }
    Ok(())
}

/// `lobelight view`.
fn view_command(args: ViewArgs) -> Result<()> {
    let ViewArgs {
        scene,
        width,
        height,
        frames,
        spp,
        screenshot,
        target_ms,
        turn,
        cache,
        method,
        bake,
        look,
        backend,
        gpu,
    } = args;
    let default_ms = match frames {
        Some(_) => 0.0,
        None => crate::cli::view::DEFAULT_TARGET_MS,
    };
    let target_ms = checked_target_ms(target_ms.unwrap_or(default_ms))?;
    for (path, what) in [(&screenshot, "screenshot"), (&cache, "bake cache")] {
        if let Some(path) = path {
            output::check_writable(path, what)?;
        }
    }
    if !turn.is_finite() {
        return Err(Error::Invalid(format!("--turn must be finite, not {turn}")));
    }
    let mut scene = load_scene(&scene)?;
    bake.apply(&mut scene)?;
    look.apply_background(&mut scene);
    let [w0, h0] = scene.camera.resolution;
    let (width, height) = (width.unwrap_or(w0), height.unwrap_or(h0));
    scene::check_resolution(width, height).map_err(Error::Invalid)?;
    let opts = crate::cli::view::ViewOptions {
        width,
        height,
        backend,
        frame: look.frame(),
        tone: look.tone(),
        method,
        frames,
        screenshot,
        cache,
        spp,
        gpu_bake: gpu,
        target_ms,
        turn,
    };
    opts.frame.validate()?;
    if method == render::Method::Path {
        return Err(Error::Invalid(
            "the viewer draws the lobes, the reference or the photons; the path tracer \
             renders still images: lobelight render --method path"
                .into(),
        ));
    }
    opts.tone.validate()?;
    crate::cli::view::view(scene, opts)?;
    Ok(())
}

/// `lobelight compare`.
fn compare_command(args: CompareArgs) -> Result<()> {
    let CompareArgs {
        a,
        b,
        heatmap,
        json,
        objects,
    } = args;
    let (pa, wa, ha) = compare::read_image(&a)?;
    let (pb, wb, hb) = compare::read_image(&b)?;
    if (wa, ha) != (wb, hb) {
        return Err(Error::Invalid(format!(
            "{} is {wa}×{ha} but {} is {wb}×{hb}",
            a.display(),
            b.display()
        )));
    }
    let values = compare::values_of(&b);
    if compare::values_of(&a) != values {
        return Err(Error::Invalid(format!(
            "{} and {} hold different kinds of values (radiance in EXR, display values \
             otherwise): compare two EXR or two PNG images",
            a.display(),
            b.display()
        )));
    }
    let mut d = compare::difference_of(&pa, &pb, wa, ha, values)?;
    if let Some(path) = objects {
        let (ids, wi, hi, names) = compare::read_object_ids(&path)?;
        if (wi, hi) != (wa, ha) {
            return Err(Error::Invalid(format!(
                "{} is {wi}×{hi} but the images are {wa}×{ha}",
                path.display()
            )));
        }
        d.objects = compare::per_object(&pa, &pb, &ids, &names)?;
    }
    if let Some(path) = heatmap {
        compare::heatmap(&compare::relative(&pa, &pb), wa, ha, &path)?;
    }
    if json {
        print_json(&d)?;
    } else {
        let flip = d.flip.map_or("—".to_string(), |f| format!("{f:.4}"));
        say(format_args!(
            "relMSE {:.4e}, PSNR {:.2} dB, SMAPE {:.4}, FLIP {flip}\n\
             mean relative {:.4} %, within 5 %: {:.2} % of {} pixels, max {:.3}, rmse {:.4e}, energy {:+.4} %",
            d.rel_mse,
            d.psnr,
            d.smape,
            100.0 * d.mean_relative,
            100.0 * d.within_5_percent,
            d.pixels,
            d.max_relative,
            d.rmse,
            100.0 * d.energy
        ));
        for o in &d.objects {
            say(format_args!(
                "{:<28} {:>7} px  mean {:.5} vs {:.5}  bias {:+7.2} %  relMSE {:.4e}  SMAPE {:.4}",
                o.name,
                o.pixels,
                o.mean,
                o.reference_mean,
                100.0 * o.bias,
                o.rel_mse,
                o.smape
            ));
        }
    }
    Ok(())
}

/// `lobelight bench convolution`.
fn bench_convolution(args: BenchArgs) -> Result<()> {
    let BenchArgs { output, json, .. } = args;
    let r = crate::cli::convolution::convolution_bench(&output, Default::default())?;
    print_report(json, &r)?;
    Ok(())
}

/// `lobelight bench scale`.
fn bench_scale(args: BenchArgs) -> Result<()> {
    let BenchArgs {
        output,
        bake,
        device,
        json,
        sizes,
        material,
        ..
    } = args;
    let draw = device.engine(EngineChoice::Device)?;
    if !draw.is_device() {
        return Err(Error::Invalid(
            "bench scale draws its frames on a device and needs a GPU adapter (lavapipe \
             will do; where it is one, the bake runs on the CPU mirror)"
                .into(),
        ));
    }
    // The bake where still images bake: on the mirror beside a software rasterizer.
    let baking = device.bake_engine(&draw);
    let engines = (&draw, &baking);
    let r = scale::scale(engines, (&sizes, material), &output, &|scene| {
        bake.apply(scene)
    })?;
    print_report(json, &r)?;
    Ok(())
}

/// `lobelight bench cluster`.
fn bench_cluster(args: BenchArgs) -> Result<()> {
    let BenchArgs {
        output,
        bake,
        device,
        json,
        cluster_splats,
        ..
    } = args;
    let engine = device.engine(EngineChoice::Auto)?;
    let r = cluster::cluster(&engine, cluster_splats, &output, &|scene| bake.apply(scene))?;
    print_report(json, &r)?;
    Ok(())
}

/// `lobelight bench sweep`.
fn bench_sweep(args: BenchArgs) -> Result<()> {
    let BenchArgs {
        scenes,
        output,
        bake,
        device,
        json,
        knobs,
        ..
    } = args;
    if scenes.is_empty() {
        return Err(Error::Invalid(
            "bench sweep needs at least one scene (e.g. scenes/bunny.toml scenes/dragon.toml)"
                .into(),
        ));
    }
    let mut loaded = Vec::new();
    for path in &scenes {
        let mut scene = load_scene(path)?;
        bake.apply(&mut scene)?;
        let name = path
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        loaded.push((name, scene));
    }
    let engine = device.engine(EngineChoice::Device)?;
    let mut plan = crate::cli::sweep::SweepPlan::default();
    if !knobs.is_empty() {
        plan = plan.only(&knobs)?;
    }
    let r = crate::cli::sweep::sweep(&loaded, &engine, &plan, &output)?;
    print_report(json, &r)?;
    Ok(())
}

/// `lobelight bench`.
fn bench_scenes(args: BenchArgs) -> Result<()> {
    let BenchArgs {
        what,
        scenes,
        bake,
        look,
        device,
        json,
        window,
        target_ms,
        orbit,
        ..
    } = args;
    if scenes.is_empty() {
        return Err(Error::Invalid(
            "bench needs at least one scene (e.g. scenes/bunny.toml)".into(),
        ));
    }
    if window && (scenes.len() > 1 || !matches!(what, BenchKind::Frame) || device.cpu) {
        return Err(Error::Invalid(
            "--window is for `bench frame` of one scene on a GPU (a process opens one window)"
                .into(),
        ));
    }
    if let Some(ms) = target_ms {
        checked_target_ms(ms)?;
    }
    // Moving frames run on the device, a software rasterizer included (faster there
    // than the mirror); photons, the fit and re-bakes where still images run.
    let engine = device.engine(match what {
        BenchKind::Frame => EngineChoice::Device,
        _ => EngineChoice::Auto,
    })?;
    let _gpu = engine.gpu();
    let mut reports = Vec::new();
    for path in &scenes {
        let mut scene = load_scene(path)?;
        bake.apply(&mut scene)?;
        let scene = std::sync::Arc::new(scene);
        let photons = PhotonConfig::from_scene(&scene);
        let (text, value) = match what {
            BenchKind::Photons => {
                let r = bench::photons(&scene, &engine, &photons)?;
                (r.to_string(), to_json(&r)?)
            }
            BenchKind::Frame => {
                let (frame, tone) = (look.frame(), look.tone());
                // The window first (a process opens one): the orbit's frames are then
                // drawn again offscreen, at the sizes the window drew them.
                let (mut still, mut moving) = (None, None);
                if window {
                    let (f, t, backend) = (frame.clone(), tone, device.backend);
                    let report = bench::window_frames(&scene, f, t, backend, target_ms)?;
                    match target_ms {
                        Some(_) => moving = Some(report),
                        None => still = Some(report),
                    }
                }
                let mut r = bench::frame(&scene, &engine, (&frame, &tone), orbit, moving)?;
                r.window = still;
                (r.to_string(), to_json(&r)?)
            }
            BenchKind::Rebake => {
                let r = crate::cli::rebake::rebake(&scene, &engine)?;
                (r.to_string(), to_json(&r)?)
            }
            BenchKind::Em => {
                let em = EmConfig::from_scene(&scene);
                let r = bench::em(&scene, &engine, &photons, &em)?;
                (r.to_string(), to_json(&r)?)
            }
            BenchKind::Convolution | BenchKind::Sweep | BenchKind::Scale | BenchKind::Cluster => {
                unreachable!("handled above")
            }
        };
        if !json {
            say(format_args!("{text}\n"));
        }
        reports.push(value);
    }
    if json {
        match reports.len() {
            1 => print_json(&reports[0])?,
            _ => print_json(&reports)?,
        }
    }
    Ok(())
}

/// The `lobelight` binary: parses the command line and runs it.
pub fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("error")).init();
    // A decoder's panic on a damaged file becomes an error naming the file
    // (`reading::guarded`): it is not printed as a crash of lobelight.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !scene::model::reading::in_decoder() {
            default_hook(info)
        }
    }));
    let cli = Cli::parse();
    // The viewer keeps the session's own environment (a window system may live there).
    if !matches!(cli.command, Command::View { .. }) {
        give_the_driver_a_runtime_dir();
    }
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("lobelight: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Mesa's Vulkan drivers print "XDG_RUNTIME_DIR is invalid or not set" on stderr at every
/// device open when the variable is unset (headless shells, services, CI): give the headless
/// commands a private directory so that their stderr holds only what lobelight says.
fn give_the_driver_a_runtime_dir() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some() {
        return;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        let uid = std::fs::metadata("/proc/self").map_or(0, |m| m.uid());
        let dir = std::env::temp_dir().join(format!("lobelight-runtime-{uid}"));
        let private = std::fs::Permissions::from_mode(0o700);
        let ready = std::fs::create_dir_all(&dir)
            .and_then(|()| std::fs::set_permissions(&dir, private))
            .is_ok();
        if ready {
            // SAFETY: called from `main` before any thread exists.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}
