//! Baked direct light and refined still images (docs/design.md §8): the direct bake on the
//! device against its CPU mirror and against shadow rays per pixel, and the refinement frames
//! that turn a moving frame into the exact, anti-aliased still image.

mod common;

use std::path::Path;

use lobelight::bake::{BakeDevice, Progress, bake};
use lobelight::camera::View;
use lobelight::cli::compare::difference;
use lobelight::cpu::CpuExecutor;
use lobelight::cpu::frames::{cpu_direct, cpu_frame, cpu_refined};
use lobelight::direct::direct_params;
use lobelight::em::LobeMap;
use lobelight::frame::{Direct, FrameConfig, Show, camera_uniform, shade_params};
use lobelight::gpu::exec::GpuExecutor;
use lobelight::gpu::renderer::FrameRenderer;
use lobelight::gpu::scene::GpuScene;
use lobelight::grid::splat_order;
use lobelight::scene::{self, Scene};
use lobelight::sequence::{Executor, bake_direct};

fn cornell(photons: u64) -> Scene {
    let mut scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    scene.bake.photons = photons;
    scene
}

fn cpu_bake(scene: &Scene) -> LobeMap {
    let grid = common::host_grid(scene);
    bake(scene, BakeDevice::Cpu(&grid), &Progress::new(false))
        .unwrap()
        .lobes
}

/// Every splat drawn as it is (`lod: 0`), so that baked and ray-traced frames differ by the
/// direct light alone.
fn with(direct: Direct, show: Show) -> FrameConfig {
    FrameConfig {
        direct,
        show: show.terms(),
        lod: 0.0,
        ..FrameConfig::default()
    }
}

/// The direct bake on the device against its mirror, splat by splat. A shadow ray is all or
/// nothing, and one that grazes a disk's rim can go either way between two f32 paths, so the
/// tolerance counts splats: 99.5 % of them within 1e-3 in irradiance and visibility, and the
/// mean visibility within 1e-3. The box's blocks must cast shadows (some splats see none of
/// the light, some part of it), or the comparison would prove little.
#[test]
fn direct_bake_matches_the_cpu_mirror() {
    let gpu = common::gpu();
    let scene = cornell(1000);
    let grid = common::host_grid(&scene);
    let on_cpu = cpu_direct(&scene, &grid).unwrap();
    let mut renderer = FrameRenderer::new(&gpu, &scene).unwrap();
    let on_gpu = renderer.read_direct(&gpu, &scene).unwrap();
    assert_eq!(
        on_gpu.visibility.len(),
        scene.splats.len() * scene.lights.len()
    );
    let n = scene.splats.len() as f64;
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-3 * a.abs().max(b.abs()).max(1e-3);
    let irradiance_ok = on_gpu
        .direct
        .iter()
        .zip(&on_cpu.direct)
        .filter(|(a, b)| (0..3).all(|c| close(a[c], b[c])))
        .count();
    let visibility_ok = on_gpu
        .visibility
        .iter()
        .zip(&on_cpu.visibility)
        .filter(|(a, b)| (*a - *b).abs() <= 1e-3)
        .count();
    let mean = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
    let (mean_gpu, mean_cpu) = (mean(&on_gpu.visibility), mean(&on_cpu.visibility));
    eprintln!(
        "irradiance {irradiance_ok} / {n}, visibility {visibility_ok} / {n}, means \
         {mean_gpu:.5} {mean_cpu:.5}"
    );
    assert!(irradiance_ok as f64 >= 0.995 * n);
    assert!(visibility_ok as f64 >= 0.995 * n);
    assert!((mean_gpu - mean_cpu).abs() <= 1e-3);
    let dark = on_cpu.visibility.iter().filter(|&&v| v == 0.0).count();
    let partial = on_cpu
        .visibility
        .iter()
        .filter(|&&v| v > 0.0 && v < 1.0)
        .count();
    assert!(
        dark > 100 && partial > 100,
        "shadows: {dark} dark, {partial} partial"
    );
}

/// The direct bake takes its splats in `grid::splat_order` (a permutation of them), and the
/// order only schedules the invocations: in reverse order it writes the same bytes, on the
/// mirror and on the device.
#[test]
fn the_direct_bake_is_the_same_in_any_order() {
    let scene = cornell(1000);
    let order = splat_order(&scene.splats);
    let mut seen = vec![false; scene.splats.len()];
    for &i in &order {
        assert!(
            !std::mem::replace(&mut seen[i as usize], true),
            "splat {i} twice"
        );
    }
    assert!(seen.iter().all(|&s| s), "not every splat in the order");
    assert_ne!(order, (0..order.len() as u32).collect::<Vec<_>>());
    let reversed: Vec<u32> = (0..scene.splats.len() as u32).rev().collect();
    let grid = common::host_grid(&scene);
    let params = direct_params(&scene);
    let bake_in = |order: &[u32]| {
        let mut ex = CpuExecutor::tracing(scene.geometry(&grid));
        let lights = ex.upload("lights", &scene.lights).unwrap();
        let order = ex.upload("order", order).unwrap();
        let baked = bake_direct(&mut ex, &lights, &order, &params).unwrap();
        baked.read_back(&mut ex, &params).unwrap()
    };
    let on_cpu = cpu_direct(&scene, &grid).unwrap();
    assert_eq!(bake_in(&reversed), on_cpu);
    let gpu = common::gpu();
    let on_gpu = GpuScene::upload(&gpu, &scene).unwrap();
    let bake_on_device = |order: &[u32]| {
        let mut encoder = gpu.encoder("direct bake");
        let mut ex = GpuExecutor::new(&gpu, &mut encoder).tracing(on_gpu.geometry());
        let lights = ex.upload("lights", &scene.lights).unwrap();
        let order = ex.upload("order", order).unwrap();
        let baked = bake_direct(&mut ex, &lights, &order, &params).unwrap();
        baked.read_back(&mut ex, &params).unwrap()
    };
    assert_eq!(bake_on_device(&reversed), bake_on_device(&order));
}

/// The baked direct light against shadow rays per pixel, on the CPU mirror of the Cornell
/// box's direct light: the same energy within 1 % (the bake moves no light), and a SMAPE under
/// 0.03 (measured 0.013: the rays' own noise in the penumbrae, which the bake draws smooth at
/// splat resolution; relMSE, at 0.03, is all dark penumbra pixels and says less).
#[test]
fn baked_direct_light_agrees_with_shadow_rays() {
    let scene = cornell(20_000);
    let grid = common::host_grid(&scene);
    let lobes = cpu_bake(&scene);
    let view = View::new(&scene.camera, 64, 64);
    let frame = |direct| {
        let cfg = with(direct, Show::Direct);
        let cam = camera_uniform(&view, scene.bounds(), &cfg);
        cpu_frame(
            &scene,
            &grid,
            (&lobes, None),
            &cam,
            &shade_params(&scene, &lobes, &cfg),
        )
        .unwrap()
    };
    let d = difference(&frame(Direct::Baked), &frame(Direct::Rays)).unwrap();
    eprintln!("{d:?}");
    assert!(d.energy.abs() <= 0.01, "{d:?}");
    assert!(d.smape <= 0.03, "{d:?}");
}

/// One refinement frame of one sample is today's exact frame, bit for bit: no jitter, every
/// area-light stratum, shadow rays.
#[test]
fn a_one_sample_still_is_the_exact_frame() {
    let gpu = common::gpu();
    let scene = cornell(20_000);
    let lobes = cpu_bake(&scene);
    let view = View::new(&scene.camera, 48, 48);
    let cfg = with(Direct::Rays, Show::Full);
    let mut renderer = FrameRenderer::new(&gpu, &scene).unwrap();
    renderer.set_lobes(&gpu, &scene, &lobes).unwrap();
    renderer.draw(&gpu, &scene, &view, &cfg).unwrap();
    let exact = renderer.read_hdr(&gpu).unwrap();
    renderer
        .draw_refined(&gpu, &scene, &view, &cfg, 1, |_| {})
        .unwrap();
    assert_eq!(renderer.read_hdr(&gpu).unwrap(), exact);
}

/// The refinement frames' points within the pixel: their mean is the pixel's centre for every
/// count (every pixel takes the same point in a frame, so an offset mean shifts every edge of
/// the image alike: the Halton points of before were 0.043 pixel off in y at 16 frames), and a
/// power of two of them puts one point in each column and each row of that many. The moving
/// frames' cycle starts at the centre, so a frame without history is the one drawn alone.
#[test]
fn the_refinement_points_are_centred_and_stratified() {
    use lobelight::frame::{TEMPORAL_JITTERS, jitter, temporal_jitter};
    assert_eq!(jitter(0, 1), [0.0; 2]);
    assert_eq!(temporal_jitter(0), [0.0; 2]);
    for n in [2, 3, 5, 12, 16, 24, 64, 256] {
        let points: Vec<[f32; 2]> = (0..n).map(|k| jitter(k, n)).collect();
        for axis in 0..2 {
            let mean = points.iter().map(|p| p[axis] as f64).sum::<f64>() / n as f64;
            // Counts between powers of two take a prefix of the larger set, whose mean is off
            // by at most 1.41 / n pixel for every count up to 300 (computed on the side).
            let bound = if n.is_power_of_two() {
                1e-6
            } else {
                1.5 / n as f64
            };
            assert!(mean.abs() <= bound, "n = {n}, axis {axis}: mean {mean}");
            assert!(
                points.iter().all(|p| p[axis].abs() < 0.5),
                "n = {n}: {points:?}"
            );
            if n.is_power_of_two() {
                let mut strata: Vec<u32> = points
                    .iter()
                    .map(|p| ((p[axis] + 0.5) * n as f32) as u32)
                    .collect();
                strata.sort();
                assert_eq!(strata, (0..n).collect::<Vec<_>>(), "n = {n}, axis {axis}");
            }
        }
    }
    let cycle: Vec<[f32; 2]> = (0..TEMPORAL_JITTERS).map(temporal_jitter).collect();
    assert_eq!(temporal_jitter(TEMPORAL_JITTERS), cycle[0]);
    for axis in 0..2 {
        let mut strata: Vec<u32> = cycle
            .iter()
            .map(|p| ((p[axis] + 0.5) * 16.0) as u32)
            .collect();
        strata.sort();
        assert_eq!(strata, (0..16).collect::<Vec<_>>(), "axis {axis}");
    }
}

/// A still image of 8 jittered frames, on the device and on the mirror: the same image within
/// the splat passes' parity tolerances. Also the glossy direct light alone of the box of
/// spheres, where the near-mirror sphere's lobe is narrower than the light, so that its
/// direct light also takes a sample of the lobe (multiple importance sampling), and its
/// glossy indirect light alone, which the glossy rays trace (the default).
#[test]
fn refined_still_matches_the_cpu_mirror() {
    let gpu = common::gpu();
    let cornell = cornell(20_000);
    refined_parity(&gpu, &cornell, &FrameConfig::default(), "cornell");
    let mut spheres = scene::load(Path::new("scenes/cornell_spheres.toml")).unwrap();
    spheres.bake.photons = 20_000;
    let specular = FrameConfig {
        show: lobelight::frame::Terms::DIRECT_SPECULAR,
        ..Default::default()
    };
    refined_parity(&gpu, &spheres, &specular, "spheres, glossy direct light");
    let traced = FrameConfig {
        show: lobelight::frame::Terms::INDIRECT_SPECULAR,
        ..Default::default()
    };
    refined_parity(&gpu, &spheres, &traced, "spheres, glossy rays");
}

fn refined_parity(gpu: &lobelight::gpu::Gpu, scene: &Scene, cfg: &FrameConfig, what: &str) {
    let grid = common::host_grid(scene);
    let lobes = cpu_bake(scene);
    let view = View::new(&scene.camera, 64, 64);
    let mut renderer = FrameRenderer::new(gpu, scene).unwrap();
    renderer.set_lobes(gpu, scene, &lobes).unwrap();
    let mut frames = 0;
    renderer
        .draw_refined(gpu, scene, &view, cfg, 8, |_| frames += 1)
        .unwrap();
    assert_eq!(frames, 8);
    let still = renderer.read_hdr(gpu).unwrap();
    let cam = camera_uniform(&view, scene.bounds(), cfg);
    let params = shade_params(scene, &lobes, cfg);
    let mirror = cpu_refined(scene, &grid, (&lobes, None), &cam, &params, 8).unwrap();
    let d = difference(&still, &mirror).unwrap();
    eprintln!("{what}: device against mirror: {d:?}");
    assert!(d.mean_relative <= 0.01, "{what}: {d:?}");
    assert!(d.within_5_percent >= 0.99, "{what}: {d:?}");
}

/// The still image against the exact one-frame render (256², on the device): the same light,
/// moved only within pixels. Energy within 1 % and SMAPE under 0.035 (measured −0.6 %, most of
/// it the light's own edge, and 0.030; 0.025 while the pixel's centre was one of the 16 points,
/// which drew the still image towards the centre's sample); most pixels within 5 %, but not
/// all, or the jitter would not bite (measured 74 % at this bake's 20 k photons: edges, and the
/// lobes' splat-sized patches, which a pixel centre samples and a jittered pixel averages).
#[test]
fn refined_still_differs_from_the_exact_frame_by_anti_aliasing() {
    let gpu = common::gpu();
    let scene = cornell(20_000);
    let lobes = cpu_bake(&scene);
    let view = View::new(&scene.camera, 256, 256);
    let mut renderer = FrameRenderer::new(&gpu, &scene).unwrap();
    renderer.set_lobes(&gpu, &scene, &lobes).unwrap();
    let cfg = FrameConfig::default();
    renderer
        .draw_refined(&gpu, &scene, &view, &cfg, 16, |_| {})
        .unwrap();
    let still = renderer.read_hdr(&gpu).unwrap();
    renderer
        .draw(&gpu, &scene, &view, &with(Direct::Rays, Show::Full))
        .unwrap();
    let exact = renderer.read_hdr(&gpu).unwrap();
    let d = difference(&still, &exact).unwrap();
    eprintln!("still against exact: {d:?}");
    assert!(d.energy.abs() <= 0.01, "{d:?}");
    assert!(d.smape <= 0.035, "{d:?}");
    assert!(
        d.within_5_percent >= 0.7 && d.within_5_percent < 0.99,
        "{d:?}"
    );
}

/// The direct bake final gathering makes is the frames' own (same lights, samples, seed and
/// shadow bias), so a render hands it to the frames: on the mirror it equals `cpu_direct`
/// exactly, and a scene with nothing glossy, which gathers nothing, hands none.
#[test]
fn the_bake_hands_its_direct_light_to_the_frames() {
    let scene = cornell(20_000);
    let grid = common::host_grid(&scene);
    let baked = bake(&scene, BakeDevice::Cpu(&grid), &Progress::new(false)).unwrap();
    let made = baked.direct.expect("final gathering's direct bake");
    assert_eq!(made, cpu_direct(&scene, &grid).unwrap());
    let mut diffuse = scene::load(Path::new("scenes/diffuse.toml")).unwrap();
    diffuse.bake.photons = 20_000;
    let grid = common::host_grid(&diffuse);
    let baked = bake(&diffuse, BakeDevice::Cpu(&grid), &Progress::new(false)).unwrap();
    assert!(baked.direct.is_none());
}
