//! `lobelight bench sweep` (thesis chapter 4 in one command): for each scene, the path
//! tracer's converged image as the reference (`--method path`, `reference_spp` samples a
//! pixel), the path tracer's own images at fewer samples (knob `path`), then one lobe render
//! per setting of one knob at a time from a base (photons emitted, EM iterations, search
//! radius, lobes per splat, splat count, lobe family, pruning), each with its bake time, its
//! frame time and its error against the reference, over the image and per object. Writes
//! `sweep.csv`, `sweep.md`, one chart per scene (`sweep_<scene>.png`: error against bake time
//! and against frame time; a path row's image costs its whole time, as bake and as frame) and
//! the references (`reference_<scene>.exr`).
//!
//! The lobe renders are the still image `render` writes: its refinement frames, jittered, with
//! shadow rays for direct light and glossy rays for the glossy surfaces' indirect light, so
//! that the lobes' knobs show in the diffuse light they carry (still images trace the glossy
//! part; moving frames draw the lobes).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use std::sync::Arc;

use serde::Serialize;

use crate::bake::Progress;
use crate::camera::View;
use crate::cli::compare::{Difference, ObjectDifference, Values, difference_of, per_object};
use crate::cli::measure::median;
use crate::cli::plot::{Chart, Series};
use crate::em::LobeFamily;
use crate::error::{Error, Result};
use crate::frame::{Direct, FrameConfig};
use crate::renderer::{Engine, Renderer};
use crate::scene::Scene;
use crate::shared::rng::{pcg_hash, unit_float};
use crate::timing::ms_since;

/// What a sweep varies, and around what.
#[derive(Clone, Debug, Serialize)]
pub struct SweepPlan {
    /// Square images of this many pixels a side.
    pub size: u32,
    /// Photons of the base setting (every knob but `photons` keeps it).
    pub base_photons: u64,
    /// Photons of the photon-gather image a sweep once used as its reference; the reference is
    /// now the path tracer (`reference_spp`). Kept in the plan for scripts that read it.
    pub reference_photons: u64,
    /// Samples per pixel of the reference: the path tracer's converged image of the scene.
    pub reference_spp: u32,
    /// The path tracer's own rows: its image at these samples per pixel, timed, against the
    /// reference (knob `path`), so one chart compares a bake plus views with rendering each.
    pub path_spp: Vec<u32>,
    pub photons: Vec<u64>,
    pub iterations: Vec<u32>,
    /// Search radii as multiples of the scene's.
    pub radius_scales: Vec<f32>,
    pub lobes: Vec<u32>,
    /// Fractions of the splats kept (the rest dropped at random, radii grown to keep the area).
    pub splat_fractions: Vec<f32>,
    pub families: Vec<LobeFamily>,
    /// Lobe pruning on and off.
    pub prune: Vec<bool>,
    /// Shared fits' cells, in search radii (0: each splat its own fit).
    pub shares: Vec<f32>,
    /// Smoothing's widest kernel, in search radii (0: each splat's own photon estimate).
    pub smooths: Vec<f32>,
    /// Timed frames per setting (after one untimed); the median is reported.
    pub frames: u32,
}

impl Default for SweepPlan {
    fn default() -> SweepPlan {
        SweepPlan {
            size: 256,
            base_photons: 1_000_000,
            reference_photons: 10_000_000,
            reference_spp: 1024,
            path_spp: vec![4, 16, 64, 256],
            photons: vec![300_000, 600_000, 1_000_000, 3_000_000, 10_000_000],
            iterations: vec![2, 5, 10, 20, 100],
            radius_scales: vec![0.5, 0.75, 1.0, 1.5, 2.0],
            lobes: vec![1, 2, 3, 5, 8],
            splat_fractions: vec![0.25, 0.5, 1.0],
            families: vec![LobeFamily::Ward, LobeFamily::Vmf],
            prune: vec![true, false],
            shares: vec![0.0, 0.5, 1.0, 2.0, 4.0],
            smooths: vec![0.0, 1.0, 2.0],
            frames: 3,
        }
    }
}

/// One knob at one value.
#[derive(Clone, Copy, Debug)]
enum Setting {
    Photons(u64),
    Iterations(u32),
    Radius(f32),
    Lobes(u32),
    Splats(f32),
    Family(LobeFamily),
    Prune(bool),
    Share(f32),
    Smooth(f32),
}

/// The knobs a sweep can turn, by name.
pub const KNOBS: [&str; 10] = [
    "path",
    "photons",
    "iterations",
    "radius",
    "lobes",
    "splats",
    "family",
    "prune",
    "share",
    "smooth",
];

impl Setting {
    fn knob(self) -> &'static str {
        match self {
            Setting::Photons(_) => "photons",
            Setting::Iterations(_) => "iterations",
            Setting::Radius(_) => "radius",
            Setting::Lobes(_) => "lobes",
            Setting::Splats(_) => "splats",
            Setting::Family(_) => "family",
            Setting::Prune(_) => "prune",
            Setting::Share(_) => "share",
            Setting::Smooth(_) => "smooth",
        }
    }

    fn value(self) -> String {
        match self {
            Setting::Photons(n) if n >= 1_000_000 => format!("{}M", n as f64 / 1e6),
            Setting::Photons(n) => format!("{}k", n as f64 / 1e3),
            Setting::Iterations(n) | Setting::Lobes(n) => n.to_string(),
            Setting::Radius(s) => format!("{s}R"),
            Setting::Splats(f) => format!("{}%", f * 100.0),
            Setting::Family(f) => format!("{f:?}").to_lowercase(),
            Setting::Prune(on) => if on { "on" } else { "off" }.into(),
            Setting::Share(r) | Setting::Smooth(r) => format!("{r}R"),
        }
    }
}

impl SweepPlan {
    fn settings(&self) -> Vec<Setting> {
        let mut out: Vec<Setting> = self.photons.iter().map(|&n| Setting::Photons(n)).collect();
        out.extend(self.iterations.iter().map(|&n| Setting::Iterations(n)));
        out.extend(self.radius_scales.iter().map(|&s| Setting::Radius(s)));
        out.extend(self.lobes.iter().map(|&n| Setting::Lobes(n)));
        out.extend(self.splat_fractions.iter().map(|&f| Setting::Splats(f)));
        out.extend(self.families.iter().map(|&f| Setting::Family(f)));
        out.extend(self.prune.iter().map(|&on| Setting::Prune(on)));
        out.extend(self.shares.iter().map(|&r| Setting::Share(r)));
        out.extend(self.smooths.iter().map(|&r| Setting::Smooth(r)));
        out
    }

    /// The plan with only the named knobs (of `KNOBS`) turned.
    pub fn only(mut self, knobs: &[String]) -> Result<SweepPlan> {
        if let Some(k) = knobs.iter().find(|k| !KNOBS.contains(&k.as_str())) {
            return Err(Error::Invalid(format!(
                "unknown sweep knob {k:?}; the knobs are {}",
                KNOBS.join(", ")
            )));
        }
        let turned = |k: &str| knobs.iter().any(|x| x == k);
        fn keep<T>(values: &mut Vec<T>, turned: bool) {
            if !turned {
                values.clear();
            }
        }
        keep(&mut self.photons, turned("photons"));
        keep(&mut self.iterations, turned("iterations"));
        keep(&mut self.radius_scales, turned("radius"));
        keep(&mut self.lobes, turned("lobes"));
        keep(&mut self.splat_fractions, turned("splats"));
        keep(&mut self.families, turned("family"));
        keep(&mut self.prune, turned("prune"));
        keep(&mut self.shares, turned("share"));
        keep(&mut self.smooths, turned("smooth"));
        keep(&mut self.path_spp, turned("path"));
        Ok(self)
    }
}

/// Keeps about `fraction` of the splats (a hash of each index decides, so the same ones every
/// time) and grows their radii by 1/√fraction so that the kept disks cover the same area.
pub fn thin(scene: &Scene, fraction: f32) -> Scene {
    let mut out = scene.clone();
    if fraction >= 1.0 {
        return out;
    }
    let grow = 1.0 / fraction.max(1e-6).sqrt();
    out.splats = scene
        .splats
        .iter()
        .enumerate()
        .filter(|(i, _)| unit_float(pcg_hash(*i as u32 ^ 0x5eed_5eed)) < fraction)
        .map(|(_, s)| {
            let mut s = *s;
            s.radius *= grow;
            s
        })
        .collect();
    out
}

/// The base scene with one knob turned; the search radius is pinned to the base's, so that
/// thinning (which grows the bounds a little) does not move it.
fn apply(base: &Scene, setting: Setting, radius: f32) -> Scene {
    let mut scene = match setting {
        Setting::Splats(f) => thin(base, f),
        _ => base.clone(),
    };
    scene.bake.radius = Some(radius);
    match setting {
        Setting::Photons(n) => scene.bake.photons = n,
        Setting::Iterations(n) => scene.bake.iterations = n,
        Setting::Radius(s) => scene.bake.radius = Some(radius * s),
        Setting::Lobes(n) => scene.bake.lobes = n,
        Setting::Family(f) => scene.bake.family = f,
        Setting::Prune(on) => scene.bake.prune = on,
        Setting::Share(r) => scene.bake.share = r,
        Setting::Smooth(r) => scene.bake.smooth = r,
        Setting::Splats(_) => {}
    }
    scene
}

#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    pub scene: String,
    pub knob: String,
    pub value: String,
    pub photons: u64,
    pub iterations: u32,
    pub radius: f32,
    pub lobes: u32,
    pub family: LobeFamily,
    pub splats: usize,
    pub photons_ms: f64,
    pub binning_ms: f64,
    pub em_ms: f64,
    /// Photons, binning and EM.
    pub bake_ms: f64,
    /// Median of the timed frames: the splat passes, without tone mapping.
    pub frame_ms: f64,
    /// Against the reference (`compare`'s definitions).
    pub rel_mse: f64,
    pub smape: f64,
    pub flip: Option<f64>,
    /// Lobe pruning, and the lobes the bake kept.
    pub prune: bool,
    pub lobes_kept: u64,
    /// The figures per object of the scene (`compare --objects`'s).
    pub objects: Vec<ObjectDifference>,
}

/// A setting that could not run on this device, with the reason (e.g. a software device's
/// loop limit at high photon counts): the sweep goes on without it.
#[derive(Clone, Debug, Serialize)]
pub struct SweepSkip {
    pub scene: String,
    pub knob: String,
    pub value: String,
    pub reason: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct SweepReference {
    pub scene: String,
    /// 0: the reference is the path tracer's, which traces no photon map.
    pub photons: u64,
    /// The path tracer's samples per pixel.
    pub spp: u32,
    pub splats: usize,
    /// Rendering it.
    pub ms: f64,
    pub image: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct SweepReport {
    pub adapter: String,
    pub backend: String,
    pub plan: SweepPlan,
    pub references: Vec<SweepReference>,
    pub rows: Vec<SweepRow>,
    pub skipped: Vec<SweepSkip>,
    /// The tables and charts written.
    pub files: Vec<String>,
    /// False when no font was found: the charts have no text.
    pub chart_text: bool,
    pub ms: f64,
}

/// What one lobe render measured.
struct LobeRun {
    hdr: Vec<[f32; 4]>,
    photons_ms: f64,
    binning_ms: f64,
    em_ms: f64,
    lobes_kept: u64,
    frame_ms: f64,
}

/// Where the sweep runs: one renderer, its device's passes compiled once, made for the first
/// scene it draws.
struct Runner<'a> {
    engine: &'a Engine,
    renderer: Option<Renderer>,
}

impl Runner<'_> {
    /// The renderer drawing `scene`, uploaded or gridded anew.
    fn on(&mut self, scene: &Arc<Scene>) -> Result<&mut Renderer> {
        let scene = scene.clone();
        Ok(match &mut self.renderer {
            Some(renderer) => {
                renderer.set_scene(scene)?;
                renderer
            }
            none => none.insert(Renderer::new(scene, self.engine)?),
        })
    }

    fn lobes(&mut self, scene: &Arc<Scene>, view: &View, frames: u32) -> Result<LobeRun> {
        let quiet = Progress::new(false);
        // The still image `render` writes (its default refinement frames, with shadow rays and
        // glossy rays), as the user gets it from the bake's knobs.
        let cfg = FrameConfig {
            direct: Direct::Rays,
            ..FrameConfig::default()
        };
        let spp = super::render::DEFAULT_SPP;
        let mut times = Vec::new();
        let renderer = self.on(scene)?;
        let baked = renderer.bake(&quiet)?;
        // The first frame compiles a device's passes: not timed.
        for i in 0..=frames {
            let t = Instant::now();
            renderer.draw(view, &cfg, spp, |_| {})?;
            if i > 0 {
                times.push(ms_since(t));
            }
        }
        Ok(LobeRun {
            hdr: renderer.read_hdr()?,
            photons_ms: baked.photons.ms.unwrap_or(0.0),
            binning_ms: baked.binning.ms.unwrap_or(0.0),
            em_ms: baked.em.ms.unwrap_or(0.0),
            lobes_kept: renderer.lobes().lobes.len() as u64,
            frame_ms: median(times),
        })
    }

    /// Which surface each pixel of `view` shows, of the scene drawn last.
    fn object_ids(&self, view: &View) -> Result<Vec<u16>> {
        let renderer = self.renderer.as_ref().ok_or_else(|| {
            Error::internal("the sweep asked for object IDs before drawing a scene")
        })?;
        renderer.object_ids(view, &FrameConfig::default())
    }

    /// The path tracer's image of `view` at `spp` samples per pixel.
    fn path(&mut self, scene: &Arc<Scene>, view: &View, spp: u32) -> Result<Vec<[f32; 4]>> {
        let renderer = self.on(scene)?;
        renderer.draw_path(view, &FrameConfig::default(), spp, |_| {})?;
        renderer.read_hdr()
    }
}

/// Runs the plan on each `(name, scene)`, writing tables, charts and references to `out_dir`.
pub fn sweep(
    scenes: &[(String, Scene)],
    engine: &Engine,
    plan: &SweepPlan,
    out_dir: &Path,
) -> Result<SweepReport> {
    let start = Instant::now();
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
    let mut runner = Runner {
        engine,
        renderer: None,
    };
    let (adapter, backend) = (engine.adapter(), engine.backend().to_string());
    let mut references = Vec::new();
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    let mut files = Vec::new();
    let mut chart_text = true;
    for (name, scene) in scenes {
        let view = View::new(&scene.camera, plan.size, plan.size);
        let radius = scene.search_radius();
        let mut base = scene.clone();
        base.bake.photons = plan.base_photons;
        eprintln!(
            "sweep {name}: reference, the path tracer at {} samples a pixel",
            plan.reference_spp
        );
        // One copy of the scene for the renderer, whichever image draws it.
        let shared = Arc::new(scene.clone());
        let t = Instant::now();
        let reference = runner.path(&shared, &view, plan.reference_spp)?;
        let image = out_dir.join(format!("reference_{name}.exr"));
        crate::cli::render::write_exr(&image, &reference, plan.size, plan.size)?;
        references.push(SweepReference {
            scene: name.clone(),
            photons: 0,
            spp: plan.reference_spp,
            splats: scene.splats.len(),
            ms: ms_since(t),
            image: image.display().to_string(),
        });
        // Which surface each pixel shows, for the per-object figures.
        let ids = runner.object_ids(&view)?;
        let against = |hdr: &[[f32; 4]]| -> Result<(Difference, Vec<ObjectDifference>)> {
            let d = difference_of(hdr, &reference, plan.size, plan.size, Values::Radiance)?;
            Ok((d, per_object(hdr, &reference, &ids, &scene.surfaces)?))
        };
        // The path tracer's own rows: each image costs its whole time, every view again.
        for &spp in &plan.path_spp {
            let t = Instant::now();
            let hdr = runner.path(&shared, &view, spp)?;
            let ms = ms_since(t);
            let (d, objects) = against(&hdr)?;
            let row = SweepRow {
                scene: name.clone(),
                knob: "path".into(),
                value: format!("{spp} spp"),
                photons: 0,
                iterations: 0,
                radius: 0.0,
                lobes: 0,
                family: scene.bake.family,
                splats: scene.splats.len(),
                photons_ms: 0.0,
                binning_ms: 0.0,
                em_ms: 0.0,
                bake_ms: ms,
                frame_ms: ms,
                rel_mse: d.rel_mse,
                smape: d.smape,
                flip: d.flip,
                prune: false,
                lobes_kept: 0,
                objects,
            };
            eprintln!(
                "sweep {name}: path       {:>6}  image {:>8.0} ms  relMSE {:.4}  SMAPE {:.4}",
                row.value, row.frame_ms, row.rel_mse, row.smape
            );
            rows.push(row);
        }
        for setting in plan.settings() {
            let s = Arc::new(apply(&base, setting, radius));
            let run = match runner.lobes(&s, &view, plan.frames) {
                Ok(run) => run,
                Err(e) => {
                    eprintln!(
                        "sweep {name}: {} {} skipped: {e}",
                        setting.knob(),
                        setting.value()
                    );
                    skipped.push(SweepSkip {
                        scene: name.clone(),
                        knob: setting.knob().into(),
                        value: setting.value(),
                        reason: e.to_string(),
                    });
                    continue;
                }
            };
            let (d, objects) = against(&run.hdr)?;
            let row = SweepRow {
                scene: name.clone(),
                knob: setting.knob().into(),
                value: setting.value(),
                photons: s.bake.photons,
                iterations: s.bake.iterations,
                radius: s.search_radius(),
                lobes: s.bake.lobes,
                family: s.bake.family,
                splats: s.splats.len(),
                photons_ms: run.photons_ms,
                binning_ms: run.binning_ms,
                em_ms: run.em_ms,
                bake_ms: run.photons_ms + run.binning_ms + run.em_ms,
                frame_ms: run.frame_ms,
                rel_mse: d.rel_mse,
                smape: d.smape,
                flip: d.flip,
                prune: s.bake.prune,
                lobes_kept: run.lobes_kept,
                objects,
            };
            eprintln!(
                "sweep {name}: {:<10} {:>6}  bake {:>8.0} ms  frame {:>6.1} ms  relMSE {:.4}  SMAPE {:.4}",
                row.knob, row.value, row.bake_ms, row.frame_ms, row.rel_mse, row.smape
            );
            rows.push(row);
        }
        let chart = out_dir.join(format!("sweep_{name}.png"));
        chart_text &= crate::cli::plot::draw(&charts(name, &rows), &chart)?;
        files.push(chart.display().to_string());
    }
    let mut md = markdown(&rows);
    for skip in &skipped {
        let _ = writeln!(
            md,
            "Skipped: {} {} = {}: {}",
            skip.scene, skip.knob, skip.value, skip.reason
        );
    }
    for (file, text) in [("sweep.csv", csv(&rows)), ("sweep.md", md)] {
        let path = out_dir.join(file);
        std::fs::write(&path, text).map_err(|e| Error::io(&path, e))?;
        files.push(path.display().to_string());
    }
    Ok(SweepReport {
        adapter,
        backend,
        plan: plan.clone(),
        references,
        rows,
        skipped,
        files,
        chart_text,
        ms: ms_since(start),
    })
}

/// Error against bake time and against frame time, one series per knob.
fn charts(scene: &str, rows: &[SweepRow]) -> [Chart; 2] {
    let series = |x: fn(&SweepRow) -> f64| -> Vec<Series> {
        let mut knobs: Vec<&str> = rows
            .iter()
            .filter(|r| r.scene == scene)
            .map(|r| r.knob.as_str())
            .collect();
        knobs.dedup();
        knobs
            .into_iter()
            .map(|k| {
                let mine: Vec<&SweepRow> = rows
                    .iter()
                    .filter(|r| r.scene == scene && r.knob == k)
                    .collect();
                Series {
                    name: k.to_string(),
                    points: mine.iter().map(|r| (x(r), r.rel_mse)).collect(),
                    labels: mine.iter().map(|r| r.value.clone()).collect(),
                }
            })
            .collect()
    };
    [
        Chart {
            title: format!("{scene}: error against bake time"),
            x_label: "bake time (s): photons + binning + EM".into(),
            y_label: "relMSE".into(),
            log_x: true,
            log_y: true,
            series: series(|r| r.bake_ms / 1e3),
        },
        Chart {
            title: format!("{scene}: error against frame time"),
            x_label: "frame time (ms)".into(),
            y_label: "relMSE".into(),
            log_x: false,
            log_y: true,
            series: series(|r| r.frame_ms),
        },
    ]
}

const CSV_HEADER: &str = "scene,knob,value,photons,iterations,radius,lobes,family,splats,\
photons_ms,binning_ms,em_ms,bake_ms,frame_ms,rel_mse,smape,flip,prune,lobes_kept";

pub fn csv(rows: &[SweepRow]) -> String {
    let mut out = format!("{CSV_HEADER}\n");
    for r in rows {
        let flip = r.flip.map_or(String::new(), |f| format!("{f:.6}"));
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{:?},{},{:.1},{:.1},{:.1},{:.1},{:.2},{:.6},{:.6},{flip},{},{}",
            r.scene,
            r.knob,
            r.value,
            r.photons,
            r.iterations,
            r.radius,
            r.lobes,
            r.family,
            r.splats,
            r.photons_ms,
            r.binning_ms,
            r.em_ms,
            r.bake_ms,
            r.frame_ms,
            r.rel_mse,
            r.smape,
            r.prune,
            r.lobes_kept
        );
    }
    out
}

pub fn markdown(rows: &[SweepRow]) -> String {
    let mut out = String::new();
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let _ = writeln!(out, "### {scene}\n");
        out.push_str(
            "| knob | value | photons | splats | lobes kept | bake (s) | frame (ms) | relMSE | SMAPE \
             | FLIP |\n",
        );
        out.push_str("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
        for r in rows.iter().filter(|r| r.scene == scene) {
            let flip = r.flip.map_or("—".to_string(), |f| format!("{f:.4}"));
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} | {:.2} | {:.1} | {:.4} | {:.4} | {flip} |",
                r.knob,
                r.value,
                r.photons,
                r.splats,
                r.lobes_kept,
                r.bake_ms / 1e3,
                r.frame_ms,
                r.rel_mse,
                r.smape
            );
        }
        out.push('\n');
    }
    out
}

impl std::fmt::Display for SweepReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "device   {} ({})", self.adapter, self.backend)?;
        for r in &self.references {
            writeln!(
                f,
                "reference {}: {} photons, {:.1} s",
                r.scene,
                r.photons,
                r.ms / 1e3
            )?;
        }
        write!(f, "{}", markdown(&self.rows))?;
        for skip in &self.skipped {
            writeln!(
                f,
                "skipped  {} {} = {}: {}",
                skip.scene, skip.knob, skip.value, skip.reason
            )?;
        }
        write!(f, "wrote    {}", self.files.join(", "))
    }
}
