//! Accuracy against the path tracer of the same splat scene (docs/measurements.md, "Every
//! object against the path tracer"): each object's mean, direct and indirect light apart, of
//! the still image the render command makes (bake, then refinement frames), on the CPU mirrors.
//!
//! The tolerance is per object: |mean / path tracer's − 1| ≤ `OBJECT_TOLERANCE`. The path
//! tracer's own noise on an object's indirect light is kept near a quarter of it by its sample
//! count (at 512 samples two seeds differ by up to 1.4 % on the diffuse box's objects, so 2,048
//! are taken). A bake path that skips a correction fails: without `estimate_coverage` on the
//! all-diffuse box its blocks' indirect light reads 4.5 % and 2.3 % dark.

mod common;

use common::scans::{self, Scan};
use glam::Vec3;

use std::path::Path;

use lobelight::bake::{BakeDevice, Progress, bake};
use lobelight::camera::View;
use lobelight::cli::compare::{ObjectDifference, per_object};
use lobelight::cpu::frames::{cpu_path, cpu_refined};
use lobelight::frame::{FrameConfig, Show, camera_uniform, shade_params};
use lobelight::objects::{SAMPLES, object_ids};
use lobelight::scene::{self, Scene};

/// Most an object's mean may differ from the path tracer's, in direct or in indirect light.
const OBJECT_TOLERANCE: f64 = 0.02;

/// An image's size and samples: refinement frames of the still image, and path-traced
/// samples of its direct light and of its (noisier) indirect light.
struct Budget {
    size: u32,
    still_spp: u32,
    direct_spp: u32,
    indirect_spp: u32,
}

/// The box at 64²: 64 refinement frames, not the default 16 (at 64² a block holds few pixels,
/// and 16 points a pixel integrate its inner edges, bright top and dim sides, with an error
/// that does not average out over them: the small block's direct light +2.2 % at 16, +0.9 % at
/// 64 and +0.3 % at 256 frames, against pixels that 64 points find on it alone); the path
/// tracer at 256 samples for direct light and 2,048 for indirect.
const AT_64: Budget = Budget {
    size: 64,
    still_spp: 64,
    direct_spp: 256,
    indirect_spp: 2048,
};

/// Each object's figures against the path tracer, for each of the light terms `shows`, of
/// one bake.
fn objects_against_path_tracer(
    scene: &Scene,
    shows: &[Show],
    b: &Budget,
) -> Vec<Vec<ObjectDifference>> {
    let grid = common::host_grid(scene);
    let baked = bake(scene, BakeDevice::Cpu(&grid), &Progress::new(false)).unwrap();
    let view = View::new(&scene.camera, b.size, b.size);
    let mut ids = None;
    shows
        .iter()
        .map(|&show| {
            let cfg = FrameConfig {
                show: show.terms(),
                ..FrameConfig::default()
            };
            let cam = camera_uniform(&view, scene.bounds(), &cfg);
            let params = shade_params(scene, &baked.lobes, &cfg);
            let still = cpu_refined(
                scene,
                &grid,
                (&baked.lobes, baked.direct.as_ref()),
                &cam,
                &params,
                b.still_spp,
            )
            .unwrap();
            let spp = match show {
                Show::Direct => b.direct_spp,
                _ => b.indirect_spp,
            };
            let path = cpu_path(scene, &grid, &cam, show.terms(), spp).unwrap();
            let ids = ids.get_or_insert_with(|| object_ids(scene, &grid, &cam, SAMPLES).unwrap());
            per_object(&still, &path, ids, &scene.surfaces).unwrap()
        })
        .collect()
}

/// Prints each object's bias and returns the ones past `tolerance`.
fn outside(what: &str, objects: &[ObjectDifference], tolerance: f64) -> Vec<String> {
    objects
        .iter()
        .inspect(|o| {
            eprintln!(
                "{what:>8} {:>14}: {:>6} px, bias {:+.2} %",
                o.name,
                o.pixels,
                100.0 * o.bias
            )
        })
        .filter(|o| o.bias.abs() > tolerance)
        .map(|o| format!("{what} {}: {:+.2} %", o.name, 100.0 * o.bias))
        .collect()
}

/// The all-diffuse box (`scenes/diffuse.toml`, what most scans are): every object within 2 % of
/// the path tracer in direct and in indirect light.
#[test]
fn every_object_of_the_diffuse_box_matches_the_path_tracer() {
    let scene = scene::load(Path::new("scenes/diffuse.toml")).unwrap();
    let shows = [Show::Direct, Show::Indirect];
    let mut failed = Vec::new();
    for (objects, what) in objects_against_path_tracer(&scene, &shows, &AT_64)
        .iter()
        .zip(["direct", "indirect"])
    {
        assert_eq!(objects.len(), 7, "the box's five walls, and its two blocks");
        failed.extend(outside(what, objects, OBJECT_TOLERANCE));
    }
    assert!(failed.is_empty(), "past {OBJECT_TOLERANCE}: {failed:?}");
}

/// Most a curved model's mean may differ from the path tracer's in indirect light: its gather
/// disks leave the surface wherever it curves, so the covered share's correction carries more
/// of its light than on the box's flat faces.
const MODEL_TOLERANCE: f64 = 0.03;

/// The diffuse box's camera, materials, light and walls, without its blocks, and the model in
/// `model`'s file standing on its floor, `fit` high, turned 30° about the vertical.
fn model_in_the_box(dir: &Path, model: &Path, fit: f32) -> Scene {
    let box_scene = std::fs::read_to_string("scenes/diffuse.toml").unwrap();
    let walls = box_scene
        .split("[[object]]                     # small block")
        .next()
        .unwrap();
    let text = format!(
        "{walls}\n[materials.model]\ndiffuse = [0.45, 0.4, 0.35]\n\n\
         [[object]]\nshape = \"model\"\npath = {model:?}\nmaterial = \"model\"\nfit = {fit}\n\
         anchor = \"bottom\"\ntranslate = [0.0, -1.0, 0.0]\nrotate = [0.0, 30.0, 0.0]\n"
    );
    scene::parse(&dir.join("scene.toml"), &text).unwrap()
}

/// A curved diffuse model (what a scan is) standing in the diffuse box: its indirect light
/// within 3 % of the path tracer, the box's within 2 %. The covered share must count the
/// photons a curved surface sends its splats, not the surface's shadow in the gather disk's
/// plane: counting the shadow read +5.4 % on this ball (+4.1 % on the bunny made diffuse), and
/// counting the surface without the share of it whose light arrives from the splat's front
/// −3.3 % (−2.9 %); both fail; now +2.6 % (+0.3 %). 64², 64 refinement frames, the path
/// tracer at 2,048 samples.
#[test]
fn a_curved_diffuse_model_matches_the_path_tracer() {
    let dir = std::env::temp_dir().join(format!("lobelight-accuracy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("bumpy_ball.obj");
    std::fs::write(&model, scans::obj_text(&scans::bumpy_ball(0.3, 130))).unwrap();
    let scene = model_in_the_box(&dir, &model, 0.8);
    let objects = objects_against_path_tracer(&scene, &[Show::Indirect], &AT_64).remove(0);
    let (model, walls): (Vec<_>, Vec<_>) =
        objects.into_iter().partition(|o| o.name.contains("model"));
    assert_eq!(model.len(), 1, "one model");
    let mut failed = outside("indirect", &model, MODEL_TOLERANCE);
    failed.extend(outside("indirect", &walls, OBJECT_TOLERANCE));
    assert!(failed.is_empty(), "{failed:?}");
}

/// A single-view scan of the bumpy ball standing in the diffuse box: every object within 2 %
/// of the path tracer in direct light, the walls within 2 % and the scan within 3 % in indirect
/// light (`MODEL_TOLERANCE`, as for the closed ball), the floor under the scan and the wall
/// behind it included. With one-sided disks (`sides = "one"`: light passes the sheet from
/// behind, and only from behind) the floor read +5.7 to +6.0 %, the back wall −5.4 to −5.6 %,
/// the side walls ±5.1 to 5.7 %, the scan +4.1 to +5.8 % in indirect light, and all three
/// failed; with its back sides (a thin closed shell, as the scanned object is) the walls are
/// within 1.0 % and the scan +2.4 % (sheet), +1.2 % (holes), +0.8 % (noisy). 64², 64 refinement
/// frames, the path tracer at 256 and 2,048 samples.
fn a_single_view_scan_matches_the_path_tracer(kind: Scan) {
    let dir = std::env::temp_dir().join(format!(
        "lobelight-accuracy-{kind:?}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("scan.obj");
    let scan =
        scans::single_view_scan(&scans::bumpy_ball(0.3, 130), Vec3::new(0.3, 0.2, 1.0), kind);
    std::fs::write(&model, scans::obj_text(&scan)).unwrap();
    let scene = model_in_the_box(&dir, &model, 0.8);
    assert!(
        scene.objects[1].back_sides > 0,
        "an open sheet gets back sides"
    );
    let shows = [Show::Direct, Show::Indirect];
    let mut figures = objects_against_path_tracer(&scene, &shows, &AT_64);
    let mut failed = outside("direct", &figures[0], OBJECT_TOLERANCE);
    let (model, walls): (Vec<_>, Vec<_>) =
        (figures.remove(1).into_iter()).partition(|o| o.name.contains("model"));
    failed.extend(outside("indirect", &model, MODEL_TOLERANCE));
    failed.extend(outside("indirect", &walls, OBJECT_TOLERANCE));
    assert!(failed.is_empty(), "{kind:?}: {failed:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_single_view_sheet_matches_the_path_tracer() {
    a_single_view_scan_matches_the_path_tracer(Scan::Sheet);
}

#[test]
fn a_sheet_with_holes_matches_the_path_tracer() {
    a_single_view_scan_matches_the_path_tracer(Scan::Holes);
}

#[test]
fn a_noisy_sheet_matches_the_path_tracer() {
    a_single_view_scan_matches_the_path_tracer(Scan::Noisy);
}
