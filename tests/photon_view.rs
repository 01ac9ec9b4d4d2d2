//! The photon view (`photon_view` + `photon_resolve`): the device against its CPU mirror on
//! the same photons, and the fixed-point sums' independence from photon order.

mod common;

use std::path::Path;

use lobelight::camera::View;
use lobelight::cpu;
use lobelight::cpu::photon_view::scene_scale;
use lobelight::frame::{FrameConfig, camera_uniform};
use lobelight::gpu::photon_view::photon_image;
use lobelight::gpu::photons::GpuPhotons;
use lobelight::gpu::scene::GpuScene;
use lobelight::photons::{PhotonConfig, PhotonMap};
use lobelight::scene::{self, Scene};
use lobelight::types::Camera;

/// Pixels whose sums may differ by more than `PIXEL_ULPS`: a photon on a pixel's edge, or a
/// visibility ray that grazes a disk's rim, can land apart on the two devices.
const CLOSE_PIXELS: f64 = 0.995;
/// How far a pixel's channels may lie apart, in units in the last place: the same photons'
/// powers summed in the same order, each weighed by f32 arithmetic that a device may round
/// apart (an H100 fuses multiply-adds: 10 % of pixels 1 ulp apart; lavapipe bit for bit).
const PIXEL_ULPS: f32 = 4.0;
/// And the image's total power.
const TOTAL_RELATIVE: f64 = 0.005;

fn setup() -> (Scene, PhotonMap, lobelight::grid::SplatGrid, Camera, f32) {
    let mut scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    scene.bake.photons = 40_000;
    let cfg = PhotonConfig::from_scene(&scene);
    let (map, grid) = common::mirror_photons(&scene, &cfg);
    let view = View::new(&scene.camera, 96, 96);
    let cam = camera_uniform(&view, scene.bounds(), &FrameConfig::default());
    let scale = scene_scale(&scene.lights, cfg.photons).unwrap();
    (scene, map, grid, cam, scale)
}

fn total(image: &[[f32; 4]]) -> f64 {
    image.iter().map(|c| (c[0] + c[1] + c[2]) as f64).sum()
}

#[test]
fn device_matches_the_cpu_mirror() {
    let gpu = common::gpu();
    let (scene, map, grid, cam, scale) = setup();
    let geo = scene.geometry(&grid);
    let ours = cpu::photon_image(&cam, &scene.materials, &map.photons, &geo, scale).unwrap();
    let on_gpu = GpuScene::upload(&gpu, &scene).unwrap();
    let photons = GpuPhotons::upload(&gpu, &map).unwrap();
    let mut encoder = gpu.encoder("photon view");
    let hdr = photon_image(&gpu, &mut encoder, &on_gpu, &photons, &cam, scale).unwrap();
    gpu.submit_and_wait(encoder).unwrap();
    let theirs: Vec<[f32; 4]> = gpu.read(&hdr, ours.len()).unwrap();
    let close_channel =
        |a: f32, b: f32| (a - b).abs() <= PIXEL_ULPS * f32::EPSILON * a.abs().max(b.abs());
    let close = ours
        .iter()
        .zip(&theirs)
        .filter(|(a, b)| a.iter().zip(b.iter()).all(|(x, y)| close_channel(*x, *y)))
        .count();
    let lit = ours.iter().filter(|c| c[0] > 0.0).count();
    assert!(lit > ours.len() / 2, "only {lit} pixels saw a photon");
    let share = close as f64 / ours.len() as f64;
    let (a, b): (&[f32], &[f32]) = (bytemuck::cast_slice(&theirs), bytemuck::cast_slice(&ours));
    assert!(
        share >= CLOSE_PIXELS,
        "{share:.4} of pixels within {PIXEL_ULPS} ulps ({})",
        common::apart(a, b)
    );
    let (a, b) = (total(&ours), total(&theirs));
    assert!(
        ((a - b) / a).abs() <= TOTAL_RELATIVE,
        "total power {a} on the CPU, {b} on the device"
    );
    assert!(theirs.iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn the_sums_do_not_depend_on_photon_order() {
    let (scene, mut map, grid, cam, scale) = setup();
    let geo = scene.geometry(&grid);
    let forward = cpu::photon_image(&cam, &scene.materials, &map.photons, &geo, scale).unwrap();
    map.photons.reverse();
    let backward = cpu::photon_image(&cam, &scene.materials, &map.photons, &geo, scale).unwrap();
    assert!(
        forward == backward,
        "reversing the photons changed the image"
    );
}
