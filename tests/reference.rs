//! The reference renderer (thesis §4.2): the GPU gather against its CPU mirror on the same
//! binned photons, and against the lobe renderer where both estimate the same thing.

mod common;

use std::path::Path;

use lobelight::bake::{Binned, Progress, bins_cpu};
use lobelight::bins::PhotonBins;
use lobelight::camera::View;
use lobelight::cli::compare::difference;
use lobelight::cpu::frames::{cpu_frame, cpu_reference};
use lobelight::frame::{Direct, FrameConfig, camera_uniform, shade_params};
use lobelight::gpu::Gpu;
use lobelight::gpu::bins::GpuBins;
use lobelight::gpu::renderer::FrameRenderer;
use lobelight::grid::SplatGrid;
use lobelight::scene::{self, Scene};

/// The splat passes' parity tolerances (tests/render.rs).
const MEAN_RELATIVE: f64 = 0.01;
const WITHIN_5_PERCENT: f64 = 0.99;

fn load(path: &str, photons: u64) -> (Scene, SplatGrid) {
    let mut scene = scene::load(Path::new(path)).unwrap();
    scene.bake.photons = photons;
    let grid = common::host_grid(&scene);
    (scene, grid)
}

fn gpu_reference(
    gpu: &Gpu,
    scene: &Scene,
    binned: &Binned<PhotonBins>,
    view: &View,
) -> Vec<[f32; 4]> {
    let cfg = FrameConfig::default();
    let mut renderer = FrameRenderer::new(gpu, scene).unwrap();
    // The CPU's bins on the device: both paths gather the very same photons.
    let on_device = Binned {
        bins: GpuBins::upload(gpu, &binned.bins).unwrap(),
        em: binned.em,
        photons: binned.photons.clone(),
        binning: binned.binning.clone(),
    };
    renderer
        .draw_reference(gpu, scene, (&on_device.bins, &on_device.em), view, &cfg)
        .unwrap();
    renderer.read_hdr(gpu).unwrap()
}

/// The glossy Cornell box from the front and from high on the left, on photons binned once.
#[test]
fn reference_matches_the_cpu_mirror() {
    let gpu = common::gpu();
    let (scene, grid) = load("scenes/cornell.toml", 100_000);
    let binned = bins_cpu(&scene, &grid, &Progress::new(false)).unwrap();
    let cfg = FrameConfig::default();
    let mut desc = scene.camera.clone();
    let front = View::new(&desc, 96, 96);
    desc.eye = [-0.8, 0.6, 2.2];
    desc.target = [0.1, -0.4, -0.2];
    for view in [front, View::new(&desc, 96, 72)] {
        let a = gpu_reference(&gpu, &scene, &binned, &view);
        let cam = camera_uniform(&view, scene.bounds(), &cfg);
        let b = cpu_reference(&scene, &grid, &binned.bins, &binned.em, &cam, &cfg);
        let d = difference(&a, &b).unwrap();
        eprintln!("{}x{}: {d:?}", view.width, view.height);
        assert!(d.mean_relative <= MEAN_RELATIVE, "{d:?}");
        assert!(d.within_5_percent >= WITHIN_5_PERCENT, "{d:?}");
        let lit = b.iter().filter(|p| p[0] + p[1] + p[2] > 0.0).count();
        assert!(lit > b.len() / 2, "most of the image shows the box");
    }
}

/// Where nothing is glossy the lobes carry only each splat's irradiance (a box kernel at its
/// centre), and the reference gathers the same photons at each visible point (Epanechnikov):
/// two estimates of the same radiance, so the image's energy agrees within 1 % and the
/// per-value difference is photon noise (SMAPE, in [0, 1]). A kernel that lost its
/// normalisation, or photons read from the wrong cells, fails the energy test.
#[test]
fn reference_and_lobes_agree_where_nothing_is_glossy() {
    let (scene, grid) = load("scenes/diffuse.toml", 300_000);
    let progress = Progress::new(false);
    let binned = bins_cpu(&scene, &grid, &progress).unwrap();
    // The photon fit: the reference gathers the same photons.
    let em = lobelight::em::EmConfig {
        gather: 0,
        ..lobelight::em::EmConfig::from_scene(&scene)
    };
    let of = (&scene.splats[..], &scene.materials[..]);
    let from = lobelight::host::FitFrom::photons(&binned.bins);
    let lobes = lobelight::renderer::Engine::Mirror
        .fit_lobes(&em, from, of, Default::default())
        .unwrap();
    assert_eq!(lobes.stats.fitted, 0, "nothing glossy, no lobes");
    // The same direct light in both (shadow rays): the comparison is of the indirect light.
    let cfg = FrameConfig {
        direct: Direct::Rays,
        ..FrameConfig::default()
    };
    let view = View::new(&scene.camera, 64, 64);
    let cam = camera_uniform(&view, scene.bounds(), &cfg);
    let a = cpu_frame(
        &scene,
        &grid,
        (&lobes, None),
        &cam,
        &shade_params(&scene, &lobes, &cfg),
    )
    .unwrap();
    let b = cpu_reference(&scene, &grid, &binned.bins, &binned.em, &cam, &cfg);
    let d = difference(&a, &b).unwrap();
    eprintln!("{d:?}");
    assert!(d.energy.abs() <= 0.01, "{d:?}");
    assert!(d.smape <= 0.05, "{d:?}");
}
