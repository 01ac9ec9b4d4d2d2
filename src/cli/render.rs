//! `lobelight render`: bake (or load the bake) and draw a scene to an image, with per-stage
//! figures. Methods: `lobes`, the renderer; `photons`, the stored photons seen from the camera.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use serde::Serialize;

use crate::bake::{Progress, StageReport};
use crate::camera::View;
use crate::error::{Error, Result};
use crate::frame::FrameConfig;
use crate::renderer::Compiled;
use crate::renderer::{Engine, Renderer};
use crate::scene::Scene;
use crate::scene::file::CameraDesc;
use crate::shared::tone::srgb_byte;
use crate::timing::ms_since;
use crate::tone::ToneConfig;
use crate::video::VideoWriter;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The bake's lobes shaded on splats, with direct light by shadow rays (the renderer).
    #[default]
    Lobes,
    /// Stored photons drawn as points where the camera sees them (a view of the bake).
    Photons,
    /// The reference the lobes approximate (thesis §4.2): per pixel, the visible point by ray
    /// casting and the photons within R gathered there with the exact BRDF, plus the same
    /// direct light. No lobe fit, no cache.
    Reference,
    /// Ground truth of the same splat scene: an unbiased path tracer through the splat grid
    /// with the same Ward BRDF and path length, `--spp` samples per pixel. No bake, no cache.
    Path,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Lobes => "lobes",
            Method::Photons => "photons",
            Method::Reference => "reference",
            Method::Path => "path",
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct Options {
    pub method: Method,
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// Show a progress bar on stderr.
    pub progress: bool,
    pub frame: FrameConfig,
    pub tone: ToneConfig,
    /// Load the bake from this file when it matches the scene, else bake and save it there.
    pub cache: Option<PathBuf>,
    /// Refinement frames of the still image (`--spp`): each jittered within the pixel, with
    /// its share of shadow rays; 1 is one exact frame at the pixel centres; 0 is the frame a
    /// moving camera gets (direct light as `frame.direct` says).
    pub spp: u32,
    /// An image sequence from one bake (`--views`): these cameras instead of the scene's, each
    /// written to the output's name numbered (`scene::views::numbered`).
    pub views: Vec<CameraDesc>,
    /// Frames a second of a video of the views (`.mp4` output).
    pub fps: f32,
    /// Draw only the views whose index is K modulo N (`--shard K/N`), so that N machines
    /// sharing a bake cache split a sequence.
    pub shard: Option<(u32, u32)>,
}

/// The image's size: `--width`/`--height`, else the scene camera's resolution.
fn image_size(scene: &Scene, opts: &Options) -> (u32, u32) {
    let [w, h] = scene.camera.resolution;
    (opts.width.unwrap_or(w), opts.height.unwrap_or(h))
}

/// Writes the object-ID image of the render `opts` describes (`crate::objects`) to `path`,
/// with the surfaces' names beside it.
pub fn write_object_ids(scene: &Arc<Scene>, opts: &Options, path: &Path) -> Result<()> {
    let (width, height) = image_size(scene, opts);
    let view = View::new(&scene.camera, width, height);
    let renderer = Renderer::new(scene.clone(), &Engine::Mirror)?;
    let ids = renderer.object_ids(&view, &opts.frame)?;
    crate::cli::compare::write_object_ids(path, &ids, view.width, view.height, &scene.surfaces)
}

/// Refinement frames `render` averages unless told: enough for smooth edges, and with the
/// default 4² area samples, one shadow ray per pixel and frame.
pub const DEFAULT_SPP: u32 = 16;

#[derive(Clone, Debug, Serialize)]
pub struct Stages {
    pub grid: StageReport,
    pub photons: StageReport,
    pub binning: StageReport,
    pub em: StageReport,
    pub shade: StageReport,
    pub tonemap: StageReport,
}

#[derive(Clone, Debug, Serialize)]
pub struct RenderReport {
    pub adapter: String,
    pub backend: String,
    pub splats: usize,
    pub method: Method,
    pub output: String,
    pub width: u32,
    pub height: u32,
    /// The bake came from the `--cache` file.
    pub cache_hit: bool,
    /// The log-average luminance the tone map keyed on (0 when it did not run).
    pub log_average: f32,
    pub stages: Stages,
    /// Model points skipped because they could not be read or were not finite, and the first
    /// of them (its file, place and fault).
    pub skipped_points: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_skipped: Option<String>,
    /// With `--views`: each image drawn (this shard's), with its time from the bake in memory.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub views: Vec<ShotReport>,
    /// With `.mp4` output: the video's frames and rate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub video: Option<VideoReport>,
    /// On a device: the compute pipelines it compiled, whose time the stages above include.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pipelines: Option<Compiled>,
}

impl std::fmt::Display for RenderReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "device   {} ({})", self.adapter, self.backend)?;
        writeln!(f, "splats   {}", self.splats)?;
        if let Some(first) = &self.first_skipped {
            let n = self.skipped_points;
            writeln!(f, "skipped  {n} model points (the first: {first})")?;
        }
        let s = &self.stages;
        let rows = [
            ("grid", &s.grid),
            ("photons", &s.photons),
            ("binning", &s.binning),
            ("em", &s.em),
            ("shade", &s.shade),
            ("tonemap", &s.tonemap),
        ];
        for (name, r) in rows {
            if let (Some(ms), Some(frames)) = (r.ms, r.frames) {
                writeln!(f, "{name:<8} {ms:>9.1} ms  ({frames} refinement frames)")?;
                continue;
            }
            match (r.ran, r.ms, &r.skipped_reason) {
                (true, Some(ms), Some(part)) => writeln!(f, "{name:<8} {ms:>9.1} ms  ({part})")?,
                (true, Some(ms), None) => writeln!(f, "{name:<8} {ms:>9.1} ms")?,
                (_, _, Some(why)) => writeln!(f, "{name:<8}   skipped: {why}")?,
                _ => writeln!(f, "{name:<8}   ran")?,
            }
        }
        if let Some(c) = &self.pipelines {
            writeln!(
                f,
                "compiled {:>9.1} ms  ({} compute pipelines, in the stages above)",
                c.ms, c.pipelines
            )?;
        }
        write!(
            f,
            "wrote    {} ({}×{})",
            self.output, self.width, self.height
        )
    }
}

/// The shade stage's report for a still image of `spp` refinement frames.
fn refined(ms: f64, spp: u32) -> StageReport {
    StageReport {
        frames: Some(spp),
        ..StageReport::ran(ms)
    }
}

/// What a video of the views holds (`RenderReport::video`).
#[derive(Clone, Debug, Serialize)]
pub struct VideoReport {
    pub frames: u64,
    pub fps: f32,
    /// Encoding the frames, from the tone-mapped pixels to the file.
    pub encode_ms: f64,
}

/// The image formats `render` writes, by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// Tone-mapped 8-bit sRGB.
    Png,
    /// Linear HDR radiance, 32-bit float RGBA.
    Exr,
    /// The views as one H.264 video, tone-mapped.
    Mp4,
}

impl ImageFormat {
    pub fn of(path: &Path) -> Result<ImageFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("exr") => Ok(ImageFormat::Exr),
            Some("mp4") => Ok(ImageFormat::Mp4),
            _ => Err(Error::Invalid(format!(
                "{}: the output must end in .png (tone-mapped), .exr (linear HDR) or .mp4 (a \
                 video of --views)",
                path.display()
            ))),
        }
    }
}

pub fn render(
    scene: &Arc<Scene>,
    engine: &Engine,
    opts: &Options,
    output: &Path,
) -> Result<RenderReport> {
    let (width, height) = image_size(scene, opts);
    crate::scene::check_resolution(width, height).map_err(Error::Invalid)?;
    engine.check_image(width, height)?;
    if !engine.is_device() {
        (scene.budget.check_image(width, height)).map_err(Error::Invalid)?;
    }
    let format = ImageFormat::of(output)?;
    opts.frame.validate()?;
    opts.tone.validate()?;
    let view = View::new(&scene.camera, width, height);
    if matches!(opts.method, Method::Reference | Method::Path) && opts.cache.is_some() {
        return Err(Error::Invalid(format!(
            "--cache holds fitted lobes; --method {} fits none and has none to load or save",
            opts.method.name()
        )));
    }
    if opts.method != Method::Lobes && !opts.views.is_empty() {
        return Err(Error::Invalid(format!(
            "--views draws a sequence from one bake: it is for --method lobes, not {}",
            opts.method.name()
        )));
    }
    if format == ImageFormat::Mp4 && opts.views.is_empty() {
        return Err(Error::Invalid(
            "a video is a sequence: give its cameras with --views FILE (a [path] of keyframes, \
             an [orbit], [[view]]s, or a camera-path .json)"
                .into(),
        ));
    }
    if format == ImageFormat::Mp4 && !(width.is_multiple_of(2) && height.is_multiple_of(2)) {
        return Err(Error::Invalid(format!(
            "{}: H.264 needs an even width and height, got {width}×{height}",
            output.display()
        )));
    }
    if format == ImageFormat::Mp4 && opts.shard.is_some() {
        return Err(Error::Invalid(
            "--shard draws part of a sequence: write a shard's frames as numbered .png".into(),
        ));
    }
    if opts.method == Method::Photons && format != ImageFormat::Png {
        return Err(Error::Invalid(
            "--method photons writes PNG only (it shows where photons landed, not radiance)".into(),
        ));
    }
    // Every check before the scene goes onto its engine: a bad option costs no grid.
    let numbered = match opts.method {
        Method::Lobes => shots(opts, &view, width, height, output)?,
        _ => Vec::new(),
    };
    let mut renderer = Renderer::new(scene.clone(), engine)?;
    let mut views = Vec::new();
    let mut video = None;
    let (stages, cache_hit, log_average) = match opts.method {
        Method::Lobes => {
            let shots: Vec<Shot> = numbered.iter().map(|(_, s)| s.clone()).collect();
            let (stages, hit, done) = render_lobes(&mut renderer, opts, &shots, (format, output))?;
            video = done.video.clone();
            if !opts.views.is_empty() {
                views = numbered
                    .iter()
                    .zip(&done.each)
                    .map(|((index, s), &ms)| ShotReport {
                        index: *index,
                        // A video's frames are in the video.
                        output: match format {
                            ImageFormat::Mp4 => output.display().to_string(),
                            _ => s.output.display().to_string(),
                        },
                        ms,
                    })
                    .collect();
            }
            (stages, hit, done.log_average)
        }
        Method::Photons => (
            render_photons(&mut renderer, opts, &view, output)?,
            false,
            0.0,
        ),
        Method::Reference => {
            let (stages, log_average) =
                render_reference(&mut renderer, opts, &view, format, output)?;
            (stages, false, log_average)
        }
        Method::Path => {
            let (stages, log_average) = render_path(&mut renderer, opts, &view, format, output)?;
            (stages, false, log_average)
        }
    };
    let (skipped_points, first_skipped) = scene.skipped_points();
    Ok(RenderReport {
        adapter: engine.adapter(),
        backend: engine.backend().to_string(),
        splats: scene.splats.len(),
        method: opts.method,
        output: output.display().to_string(),
        width,
        height,
        cache_hit,
        log_average,
        stages,
        skipped_points,
        first_skipped: first_skipped.map(str::to_string),
        views,
        video,
        pipelines: engine.compiled(),
    })
}

/// The images to draw, with their places in the view list: the scene's camera to `output`,
/// or with `--views` this shard's views, each to its numbered file.
fn shots(
    opts: &Options,
    view: &View,
    width: u32,
    height: u32,
    output: &Path,
) -> Result<Vec<(usize, Shot)>> {
    if opts.views.is_empty() {
        if opts.shard.is_some() {
            return Err(Error::Invalid(
                "--shard splits a view list: give it with --views FILE".into(),
            ));
        }
        let shot = Shot {
            view: *view,
            output: output.to_path_buf(),
        };
        return Ok(vec![(0, shot)]);
    }
    let (k, n) = opts.shard.unwrap_or((0, 1));
    if n == 0 || k >= n {
        return Err(Error::Invalid(format!(
            "--shard {k}/{n}: K must be below N (shards 0/N to N-1/N)"
        )));
    }
    let count = opts.views.len();
    Ok(opts
        .views
        .iter()
        .enumerate()
        .filter(|(i, _)| *i as u32 % n == k)
        .map(|(i, cam)| {
            let shot = Shot {
                view: View::new(cam, width, height),
                output: crate::scene::views::numbered(output, i, count),
            };
            (i, shot)
        })
        .collect())
}

/// The pixels a frame ends in: tone-mapped for PNG, linear for EXR.
enum Pixels {
    Rgba8(Vec<u32>),
    Hdr(Vec<[f32; 4]>),
}

/// A drawn frame with the figures of its two stages.
struct Drawn {
    pixels: Pixels,
    shade: StageReport,
    tonemap: StageReport,
    /// (Σ log(ε + Y), count), when the tone map ran.
    log_sum: Option<[f32; 2]>,
}

fn tone_skipped() -> StageReport {
    StageReport::skipped("EXR output keeps linear radiance")
}

/// The renderer's last image, tone-mapped for PNG or read back linear for EXR.
fn drawn(
    renderer: &mut Renderer,
    format: ImageFormat,
    tone: &ToneConfig,
    shade: StageReport,
) -> Result<Drawn> {
    Ok(match format {
        ImageFormat::Png | ImageFormat::Mp4 => {
            let t = Instant::now();
            let toned = renderer.tone_map(tone)?;
            Drawn {
                pixels: Pixels::Rgba8(toned.rgba),
                shade,
                tonemap: StageReport::ran(ms_since(t)),
                log_sum: Some(toned.log_sum),
            }
        }
        ImageFormat::Exr => Drawn {
            pixels: Pixels::Hdr(renderer.read_hdr()?),
            shade,
            tonemap: tone_skipped(),
            log_sum: None,
        },
    })
}

fn write_drawn(drawn: &Drawn, progress: &Progress, view: &View, output: &Path) -> Result<()> {
    progress.done("shade", drawn.shade.ms.unwrap_or(0.0), "");
    match &drawn.pixels {
        Pixels::Rgba8(rgba) => write_rgba8(output, rgba, view.width, view.height),
        Pixels::Hdr(hdr) => write_exr(output, hdr, view.width, view.height),
    }
}

/// One image of a render: its view and its file.
#[derive(Clone)]
pub struct Shot {
    pub view: View,
    pub output: PathBuf,
}

/// What one image of a view sequence took (`RenderReport::views`).
#[derive(Clone, Debug, Serialize)]
pub struct ShotReport {
    /// Its place in the view list (shards keep the list's numbers).
    pub index: usize,
    pub output: String,
    /// Drawing, tone mapping and writing it, from the bake in memory.
    pub ms: f64,
}

/// What drawing the shots gave: the last one's stages and log-average, and each one's time.
struct Shots {
    shade: StageReport,
    tonemap: StageReport,
    log_average: f32,
    each: Vec<f64>,
    /// The video the shots went into, where they went into one.
    video: Option<VideoReport>,
}

/// The renderer: bake (or load) once, then for each shot the splat passes, tone map, write.
fn render_lobes(
    renderer: &mut Renderer,
    opts: &Options,
    shots: &[Shot],
    (format, output): (ImageFormat, &Path),
) -> Result<(Stages, bool, Shots)> {
    let progress = Progress::new(opts.progress);
    let mut done = Shots {
        shade: StageReport::skipped("no view to draw"),
        tonemap: StageReport::skipped("no view to draw"),
        log_average: 0.0,
        each: Vec::with_capacity(shots.len()),
        video: None,
    };
    let mut video = match (format, shots.first()) {
        (ImageFormat::Mp4, Some(first)) => {
            let (w, h) = (first.view.width, first.view.height);
            Some(VideoWriter::create(output, w, h, opts.fps)?)
        }
        _ => None,
    };
    let mut encode_ms = 0.0;
    let (baked, hit) = renderer.bake_cached(opts.cache.as_deref(), &progress)?;
    // A sequence shows one bar over its frames; a still, one over its refinement frames.
    let frames = (shots.len() > 1).then(|| progress.bar_of(shots.len() as u64, "frames"));
    for (k, shot) in shots.iter().enumerate() {
        let (t, view) = (Instant::now(), &shot.view);
        let bar = (opts.spp > 0 && frames.is_none()).then(|| progress.bar(opts.spp as u64));
        let each = |k: u32| bar.iter().for_each(|b| b.set_position(k as u64 + 1));
        let drawn_now = renderer.draw(view, &opts.frame, opts.spp, each);
        bar.iter().for_each(|b| b.finish_and_clear());
        drawn_now?;
        let shade = refined(ms_since(t), opts.spp);
        let drawn = drawn(renderer, format, &opts.tone, shade)?;
        match (&mut video, &drawn.pixels) {
            (Some(v), Pixels::Rgba8(rgba)) => {
                let e = Instant::now();
                v.push(rgba)?;
                encode_ms += ms_since(e);
            }
            _ if frames.is_some() => {
                write_drawn(&drawn, &Progress::new(false), view, &shot.output)?
            }
            _ => write_drawn(&drawn, &progress, view, &shot.output)?,
        }
        frames.iter().for_each(|b| b.set_position(k as u64 + 1));
        done.each.push(ms_since(t));
        done.log_average = drawn.log_sum.map_or(0.0, crate::tone::log_average);
        (done.shade, done.tonemap) = (drawn.shade, drawn.tonemap);
    }
    frames.iter().for_each(|b| b.finish_and_clear());
    if let Some(v) = video {
        let e = Instant::now();
        let frames = v.finish()?;
        encode_ms += ms_since(e);
        done.video = Some(VideoReport {
            frames,
            fps: opts.fps,
            encode_ms,
        });
    }
    let stages = Stages {
        grid: StageReport::ran(renderer.grid_ms()),
        photons: baked.photons,
        binning: baked.binning,
        em: baked.em,
        shade: done.shade.clone(),
        tonemap: done.tonemap.clone(),
    };
    Ok((stages, hit, done))
}

/// `--method reference`: photons traced and binned (no fit), gathered per pixel at the
/// visible point with the exact BRDF, direct light by the frame's own shade pass.
fn render_reference(
    renderer: &mut Renderer,
    opts: &Options,
    view: &View,
    format: ImageFormat,
    output: &Path,
) -> Result<(Stages, f32)> {
    let progress = Progress::new(opts.progress);
    let [photons, binning] = renderer.bin_photons(&progress)?;
    let t = Instant::now();
    renderer.draw_reference(view, &opts.frame)?;
    let shade = StageReport::ran(ms_since(t));
    let drawn = drawn(renderer, format, &opts.tone, shade)?;
    write_drawn(&drawn, &progress, view, output)?;
    let stages = Stages {
        grid: StageReport::ran(renderer.grid_ms()),
        photons,
        binning,
        em: StageReport::skipped("the reference gathers photons; it fits no lobes"),
        shade: drawn.shade,
        tonemap: drawn.tonemap,
    };
    Ok((stages, drawn.log_sum.map_or(0.0, crate::tone::log_average)))
}

/// `--method path`: `--spp` path-traced samples per pixel, on the device or the CPU mirror.
fn render_path(
    renderer: &mut Renderer,
    opts: &Options,
    view: &View,
    format: ImageFormat,
    output: &Path,
) -> Result<(Stages, f32)> {
    let progress = Progress::new(opts.progress);
    let spp = opts.spp.max(1);
    let bar = progress.bar(spp as u64);
    let each = |k: u32| bar.set_position(k as u64 + 1);
    let t = Instant::now();
    let traced = renderer.draw_path(view, &opts.frame, spp, each);
    bar.finish_and_clear();
    traced?;
    let drawn = drawn(renderer, format, &opts.tone, refined(ms_since(t), spp))?;
    write_drawn(&drawn, &progress, view, output)?;
    let why = "the path tracer needs no bake";
    let stages = Stages {
        grid: StageReport::ran(renderer.grid_ms()),
        photons: StageReport::skipped(why),
        binning: StageReport::skipped(why),
        em: StageReport::skipped(why),
        shade: drawn.shade,
        tonemap: drawn.tonemap,
    };
    Ok((stages, drawn.log_sum.map_or(0.0, crate::tone::log_average)))
}

/// `--method photons`: the stored photons seen from the camera (thesis Fig. 3.1), drawn by
/// the `photon_view` stage on the device or its CPU mirror, to a PNG (`render` checked).
fn render_photons(
    renderer: &mut Renderer,
    opts: &Options,
    view: &View,
    output: &Path,
) -> Result<Stages> {
    let total = crate::photons::PhotonConfig::from_scene(renderer.scene()).photons;
    let bar = Progress::new(opts.progress).bar(total);
    let mut on_batch = |done: u64, _total: u64| bar.set_position(done);
    let seen = renderer.photon_view(view, &opts.frame, &mut on_batch);
    bar.finish_and_clear();
    let seen = seen?;
    let image: Vec<[f32; 3]> = seen.hdr.iter().map(|c| [c[0], c[1], c[2]]).collect();
    write_png(output, &image, view.width, view.height)?;
    let not_built = "not part of --method photons";
    let stats = seen.stats;
    Ok(Stages {
        grid: StageReport::ran(renderer.grid_ms()),
        photons: StageReport {
            emitted: Some(stats.emitted),
            stored: Some(stats.stored),
            ..StageReport::ran(stats.trace_ms)
        },
        binning: StageReport::skipped(not_built),
        em: StageReport::skipped(not_built),
        // Drawing the photons.
        shade: StageReport::ran(seen.draw_ms),
        tonemap: StageReport::skipped("photon view is scaled by its 99.5th percentile"),
    })
}

/// Writes an HDR image as PNG, scaled so that the 99.5th percentile of the lit pixels' largest
/// channel maps to white, then sRGB-encoded.
pub fn write_png(path: &Path, image: &[[f32; 3]], width: u32, height: u32) -> Result<()> {
    let mut peaks: Vec<f32> = image
        .iter()
        .map(|c| c[0].max(c[1]).max(c[2]))
        .filter(|&m| m > 0.0 && m.is_finite())
        .collect();
    peaks.sort_by(f32::total_cmp);
    let white = peaks
        .get((peaks.len() as f64 * 0.995) as usize)
        .or(peaks.last())
        .copied()
        .unwrap_or(1.0);
    let bytes: Vec<u8> = image
        .iter()
        .flat_map(|c| c.map(|v| srgb_byte(v / white) as u8))
        .collect();
    let img = image::RgbImage::from_raw(width, height, bytes)
        .ok_or_else(|| Error::Invalid("image buffer has the wrong size".into()))?;
    img.save(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot write image: {e}", path.display())))
}

/// Writes packed RGBA8 pixels (red in the low byte, as `pack_srgb` packs them) as PNG.
pub fn write_rgba8(path: &Path, rgba: &[u32], width: u32, height: u32) -> Result<()> {
    let bytes: Vec<u8> = rgba.iter().flat_map(|p| p.to_le_bytes()).collect();
    let img = image::RgbaImage::from_raw(width, height, bytes)
        .ok_or_else(|| Error::Invalid("image buffer has the wrong size".into()))?;
    img.save(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot write image: {e}", path.display())))
}

/// Writes linear HDR pixels as 32-bit float OpenEXR.
pub fn write_exr(path: &Path, hdr: &[[f32; 4]], width: u32, height: u32) -> Result<()> {
    let floats: Vec<f32> = hdr.iter().flatten().copied().collect();
    let img = image::Rgba32FImage::from_raw(width, height, floats)
        .ok_or_else(|| Error::Invalid("image buffer has the wrong size".into()))?;
    img.save(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot write image: {e}", path.display())))
}
