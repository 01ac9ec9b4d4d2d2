//! Work a scene does not need is skipped: with nothing glossy no EM runs and no lobes are
//! kept, splats without photons get no fit, and the images are the same as without skipping.

mod common;

use std::path::Path;

use lobelight::bake::{BakeDevice, Progress, bake};
use lobelight::em::LobeMap;
use lobelight::gpu::scene::GpuScene;
use lobelight::scene::{self, Scene};
use lobelight::types::SplatLight;

fn load(path: &str) -> Scene {
    let mut scene = scene::load(Path::new(path)).unwrap();
    scene.bake.photons = 30_000;
    scene
}

fn both(scene: &Scene) -> [(&'static str, LobeMap, Option<String>); 2] {
    let gpu = common::gpu();
    let quiet = Progress::new(false);
    let on_gpu = GpuScene::upload(&gpu, scene).unwrap();
    let g = bake(scene, BakeDevice::Gpu(&gpu, &on_gpu), &quiet).unwrap();
    let grid = common::host_grid(scene);
    let c = bake(scene, BakeDevice::Cpu(&grid), &quiet).unwrap();
    [
        ("GPU", g.lobes, g.em.skipped_reason),
        ("CPU", c.lobes, c.em.skipped_reason),
    ]
}

#[test]
fn nothing_glossy_runs_no_em_and_keeps_no_lobes() {
    let scene = load("scenes/diffuse.toml");
    assert!(scene.materials.iter().all(|m| m.specular == [0.0; 3]));
    for (side, map, why) in both(&scene) {
        assert_eq!(map.stats.fitted, 0, "{side}");
        assert_eq!(map.lobes_per_splat, 0, "{side}");
        assert!(map.lobes.is_empty(), "{side}");
        assert!(map.light.iter().all(|l| l.lobes == 0), "{side}");
        // The irradiance is still there: the diffuse scene's indirect light.
        assert!(map.stats.listed > 0, "{side}");
        assert!(map.light.iter().any(|l| l.irradiance[0] > 0.0), "{side}");
        let why = why.unwrap_or_default();
        assert!(why.contains("no EM and no lobes kept"), "{side}: {why}");
    }
}

#[test]
fn only_glossy_splats_with_photons_are_fitted() {
    let mut scene = load("scenes/cornell.toml");
    // Each glossy splat its own fit (shared fits serve most of them from another's: their own
    // test is tests/fit_groups.rs).
    scene.bake.share = 0.0;
    let glossy = |i: usize| {
        let s = &scene.splats[i];
        scene.materials[s.material as usize].specular != [0.0; 3]
    };
    for (side, map, why) in both(&scene) {
        let n = scene.splats.len();
        let with_lobes: Vec<usize> = (0..n).filter(|&i| map.light[i].lobes > 0).collect();
        // Fitted: glossy and listed; a listed splat may still accept no photon (all behind it
        // or outside its slab) and then writes no lobe.
        assert!(with_lobes.len() as u32 <= map.stats.fitted, "{side}");
        assert!(
            with_lobes.len() as u32 > map.stats.fitted * 9 / 10,
            "{side}"
        );
        assert!(
            with_lobes.iter().all(|&i| glossy(i)),
            "{side}: a diffuse splat has lobes"
        );
        assert!(
            (0..n).all(|i| map.light[i].photons == 0 || !glossy(i) || map.light[i].lobes > 0),
            "{side}: a lit glossy splat has no lobes"
        );
        // Splats the selection did not list got no fit: their light is untouched.
        let untouched = map.light.iter().filter(|l| **l == SplatLight::default());
        assert!(
            untouched.count() >= n - map.stats.listed as usize,
            "{side}: more splats written than listed"
        );
        assert!(
            (map.stats.listed as usize) < n,
            "{side}: the box has dark splats"
        );
        // Only the lobes written are kept, packed: no slot for diffuse or dark splats.
        let written: usize = map.light.iter().map(|l| l.lobes as usize).sum();
        assert_eq!(map.lobes.len(), written, "{side}");
        assert!(written <= map.stats.fitted as usize * map.lobes_per_splat as usize);
        assert!(map.check_packed().is_ok(), "{side}");
        let why = why.unwrap_or_default();
        assert!(
            why.contains("EM on") && why.contains("without photons skipped"),
            "{why}"
        );
    }
}
