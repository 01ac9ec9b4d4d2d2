//! One renderer over either engine (`renderer::Renderer`): the same calls draw the same images
//! on the device and on the CPU mirror, still images and moving frames with temporal
//! anti-aliasing alike, within the splat passes' parity tolerances (`tests/render.rs`); and
//! what it refuses, it refuses with an error.

mod common;

use std::path::Path;
use std::sync::Arc;

use lobelight::bake::Progress;
use lobelight::camera::View;
use lobelight::cli::compare::difference;
use lobelight::frame::FrameConfig;
use lobelight::renderer::{BackendChoice, Engine, EngineChoice, Renderer};
use lobelight::scene::{self, Scene};

/// The splat passes' parity tolerances (`tests/render.rs`): a frame's pixels differ where a
/// disk's edge rounds to the other side of a pixel centre on the two rasterizers.
const MEAN_RELATIVE: f64 = 0.01;
const WITHIN_5_PERCENT: f64 = 0.99;

fn cornell(photons: u64) -> Arc<Scene> {
    let mut scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    scene.bake.photons = photons;
    Arc::new(scene)
}

/// A renderer on each engine with the mirror's bake.
fn both(scene: &Arc<Scene>) -> (Renderer, Renderer) {
    let mut mirror = Renderer::new(scene.clone(), &Engine::Mirror).unwrap();
    mirror.bake(&Progress::new(false)).unwrap();
    let device = Engine::Device(Arc::new(common::gpu()));
    let mut on_device = Renderer::new(scene.clone(), &device).unwrap();
    on_device.set_lobes(mirror.lobes().clone());
    (on_device, mirror)
}

fn agree(a: &Renderer, b: &Renderer, label: &str) {
    let d = difference(&a.read_hdr().unwrap(), &b.read_hdr().unwrap()).unwrap();
    eprintln!("{label}: {d:?}");
    assert!(d.mean_relative <= MEAN_RELATIVE, "{label}: {d:?}");
    assert!(d.within_5_percent >= WITHIN_5_PERCENT, "{label}: {d:?}");
}

#[test]
fn one_renderer_draws_alike_on_either_engine() {
    let scene = cornell(60_000);
    let (mut device, mut mirror) = both(&scene);
    let view = View::new(&scene.camera, 64, 64);
    let cfg = FrameConfig::default();
    for r in [&mut device, &mut mirror] {
        r.draw(&view, &cfg, 4, |_| {}).unwrap();
    }
    agree(&device, &mirror, "still, 4 refinement frames");
    // Three moving frames of a camera turning, each blended into the ones before.
    let moving = FrameConfig {
        temporal: true,
        ..FrameConfig::default()
    };
    let mut desc = scene.camera.clone();
    for k in 0..3 {
        desc.eye[0] += 0.01 * k as f32;
        let view = View::new(&desc, 64, 64);
        for r in [&mut device, &mut mirror] {
            r.draw_moving(&view, &moving).unwrap();
        }
        agree(&device, &mirror, &format!("moving frame {k}, temporal"));
    }
    // The history is what the frames are blended into: without it the last frame differs.
    let alone = FrameConfig::default();
    mirror
        .draw_moving(&View::new(&desc, 64, 64), &alone)
        .unwrap();
    let blended = device.read_hdr().unwrap();
    let d = difference(&mirror.read_hdr().unwrap(), &blended).unwrap();
    assert!(d.mean_relative > 0.0, "{d:?}");
}

#[test]
fn the_mirror_is_chosen_by_name_and_a_relight_keeps_the_splats() {
    let (engine, fallback) = Engine::open(EngineChoice::Mirror, BackendChoice::Auto).unwrap();
    assert!(engine.gpu().is_none() && fallback.is_none());
    assert_eq!(
        (engine.adapter().as_str(), engine.backend()),
        ("CPU mirror", "cpu")
    );
    let scene = cornell(20_000);
    let mut renderer = Renderer::new(scene.clone(), &engine).unwrap();
    // Another scene's splats are refused with a message, not drawn with the wrong grid.
    let mut other = (*scene).clone();
    other.splats.truncate(other.splats.len() / 2);
    let err = renderer.relight(Arc::new(other)).unwrap_err().to_string();
    assert!(err.contains("a renderer of its own"), "{err}");
    // A reference before its photons are binned is an error too.
    let view = View::new(&scene.camera, 16, 16);
    assert!(
        renderer
            .draw_reference(&view, &FrameConfig::default())
            .is_err()
    );
}

/// A renderer moves to another thread (a worker, or a Python object that releases the GIL).
#[test]
fn a_renderer_and_its_engine_are_send() {
    fn send<T: Send>() {}
    send::<Renderer>();
    send::<Engine>();
}
