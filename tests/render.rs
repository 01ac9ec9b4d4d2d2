//! The splat passes: GPU against the CPU mirror on shared bakes (docs/design.md §8), direct light
//! against closed forms, and the bake cache's keys.

mod common;

use std::path::Path;

use lobelight::bake::{BakeDevice, Progress, bake};
use lobelight::camera::View;
use lobelight::cli::compare::difference;
use lobelight::cpu::frames::cpu_frame;
use lobelight::em::LobeMap;
use lobelight::frame::{Direct, FrameConfig, Show, Splatter, camera_uniform, shade_params};
use lobelight::gpu::Gpu;
use lobelight::gpu::renderer::FrameRenderer;
use lobelight::gpu::scene::GpuScene;
use lobelight::grid::SplatGrid;
use lobelight::scene::{self, Scene};

/// Parity tolerances of the issue: mean relative difference and pixels within 5 %.
const MEAN_RELATIVE: f64 = 0.01;
const WITHIN_5_PERCENT: f64 = 0.99;

fn cpu_bake(scene: &Scene, grid: &SplatGrid) -> LobeMap {
    bake(scene, BakeDevice::Cpu(grid), &Progress::new(false))
        .unwrap()
        .lobes
}

/// The scene of file `path` with `photons` photons, baked on the CPU.
fn baked_scene(path: &str, photons: u64) -> (Scene, SplatGrid, LobeMap) {
    let mut scene = scene::load(Path::new(path)).unwrap();
    scene.bake.photons = photons;
    let grid = common::host_grid(&scene);
    let lobes = cpu_bake(&scene, &grid);
    (scene, grid, lobes)
}

/// The default scene with 100 k photons, baked on the CPU.
fn glossy_cornell() -> (Scene, SplatGrid, LobeMap) {
    baked_scene("scenes/cornell.toml", 100_000)
}

fn views(scene: &Scene, size: u32) -> Vec<View> {
    let mut desc = scene.camera.clone();
    let front = View::new(&desc, size, size);
    // A second, oblique view from high on the left: grazing splats, other occlusions.
    desc.eye = [-0.8, 0.6, 2.2];
    desc.target = [0.1, -0.4, -0.2];
    vec![front, View::new(&desc, size, size * 3 / 4)]
}

fn gpu_frame(
    gpu: &Gpu,
    scene: &Scene,
    lobes: &LobeMap,
    view: &View,
    cfg: &FrameConfig,
) -> Vec<[f32; 4]> {
    let mut renderer = FrameRenderer::new(gpu, scene).unwrap();
    renderer.set_lobes(gpu, scene, lobes).unwrap();
    renderer.draw(gpu, scene, view, cfg).unwrap();
    renderer.read_hdr(gpu).unwrap()
}

fn cpu_hdr(
    scene: &Scene,
    grid: &SplatGrid,
    lobes: &LobeMap,
    view: &View,
    cfg: &FrameConfig,
) -> Vec<[f32; 4]> {
    let cam = camera_uniform(view, scene.bounds(), cfg);
    cpu_frame(
        scene,
        grid,
        (lobes, None),
        &cam,
        &shade_params(scene, lobes, cfg),
    )
    .unwrap()
}

/// The frame of `view` drawn on the device and on the mirror agrees within the parity
/// tolerances (`label` names it in the log); returns the mirror's.
fn frames_agree(
    gpu: &Gpu,
    (scene, grid, lobes): (&Scene, &SplatGrid, &LobeMap),
    view: &View,
    cfg: &FrameConfig,
    label: &str,
) -> Vec<[f32; 4]> {
    let a = gpu_frame(gpu, scene, lobes, view, cfg);
    let b = cpu_hdr(scene, grid, lobes, view, cfg);
    let d = difference(&a, &b).unwrap();
    eprintln!("{label} {}x{}: {d:?}", view.width, view.height);
    assert!(d.mean_relative <= MEAN_RELATIVE, "{label}: {d:?}");
    assert!(d.within_5_percent >= WITHIN_5_PERCENT, "{label}: {d:?}");
    b
}

/// Moving frames by the raster passes with merged disks of up to 2 pixels.
fn merged_raster() -> FrameConfig {
    FrameConfig {
        splatter: Splatter::Raster,
        lod: 2.0,
        ..FrameConfig::default()
    }
}

/// The level of detail of moving frames (`--lod`): the device merges the same splats as the
/// mirror (the frames agree within the parity tolerances), and at 96 pixels, where the box's
/// far splats are about half a pixel, it does merge them: a thousand or more splats are left
/// out in each view, the frame changes, and its light stays within 5 % of the full frame's.
#[test]
fn level_of_detail_matches_the_mirror_and_thins() {
    use lobelight::shared::splat::{lod_level, lod_radius};
    let gpu = common::gpu();
    let (scene, grid, lobes) = glossy_cornell();
    let (lods, _) = lobelight::lod::merge_tree(&scene.splats, false);
    let cfg = merged_raster();
    for view in views(&scene, 96) {
        let cam = camera_uniform(&view, scene.bounds(), &cfg);
        let left_out = (0..scene.splats.len())
            .filter(|&i| {
                let (s, lod) = (&scene.splats[i], &lods[i]);
                lod_radius(&cam, s, lod, lod_level(&cam, s, lod)) == 0.0
            })
            .count();
        assert!(left_out >= 1000, "{left_out} left out");
        let b = frames_agree(&gpu, (&scene, &grid, &lobes), &view, &cfg, "lod");
        let full = FrameConfig { lod: 0.0, ..cfg };
        let e = difference(&b, &cpu_hdr(&scene, &grid, &lobes, &view, &full)).unwrap();
        eprintln!("against every splat: {e:?}");
        assert!(e.within_5_percent < 1.0, "{e:?}");
        assert!(e.energy.abs() <= 0.05, "{e:?}");
    }
}

/// Merged disks of curved glossy surfaces (the spheres' box), shaded with their lobes widened
/// by the spread of their normals (`lod::merge_tree`): the device and the mirror agree within
/// the parity tolerances, in views where hundreds of glossy splats are drawn merged with a
/// spread above nothing.
#[test]
fn merged_glossy_disks_match_the_mirror() {
    use lobelight::shared::splat::{lod_level, lod_radius, lod_roughness, lod_word};
    let gpu = common::gpu();
    let (scene, grid, lobes) = baked_scene("scenes/cornell_spheres.toml", 50_000);
    let (lods, spreads) = lobelight::lod::merge_tree(&scene.splats, true);
    let cfg = merged_raster();
    for view in views(&scene, 96) {
        let cam = camera_uniform(&view, scene.bounds(), &cfg);
        let widened = (0..scene.splats.len())
            .filter(|&i| {
                let (s, lod) = (&scene.splats[i], &lods[i]);
                let level = lod_level(&cam, s, lod);
                scene.materials[s.material as usize].is_glossy()
                    && lod_radius(&cam, s, lod, level) > 0.0
                    && lod_roughness(0.0, lod_word(&spreads[i], level)) > 0.0
            })
            .count();
        assert!(widened >= 200, "{widened} widened");
        let label = format!("{widened} widened,");
        frames_agree(&gpu, (&scene, &grid, &lobes), &view, &cfg, &label);
    }
}

/// A scene with nothing glossy carries no merged normals (a stand-in of one record, not 20
/// bytes a splat, and `drawn_normals` of one word on the device), where the glossy box carries
/// one record a splat; and its merged frames agree with the mirror's within the parity
/// tolerances, `splat_select` writing no word.
#[test]
fn a_diffuse_scene_merges_without_normals() {
    let gpu = common::gpu();
    let (scene, grid, lobes) = baked_scene("scenes/diffuse.toml", 50_000);
    let tree = scene.lod_tree(true);
    assert!(
        !tree.normals && tree.spreads.len() == 1,
        "{}",
        tree.spreads.len()
    );
    let glossy = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    let tree = glossy.lod_tree(true);
    assert!(tree.normals && tree.spreads.len() == glossy.splats.len());
    let cfg = merged_raster();
    for view in views(&scene, 96) {
        frames_agree(
            &gpu,
            (&scene, &grid, &lobes),
            &view,
            &cfg,
            "diffuse, merged,",
        );
    }
}

/// The level of detail's merged disks leave no hole: in both views of the box, from 24 to 96
/// pixels and with merged disks of up to 1 to 4 pixels, every pixel that the full set of splats
/// covers is covered by the splats drawn with the level of detail (the visibility pass's
/// mirror), while a third or more of the splats are left out.
#[test]
fn level_of_detail_leaves_no_hole() {
    use lobelight::cpu::splat_select::{drawn_splats, selection};
    use lobelight::cpu::splat_visibility::{bin_tiles, splat_visibility};
    let scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    let tree = scene.lod_tree(true);
    let covered = |cam: &lobelight::types::Camera, splats: &[lobelight::types::Splat]| {
        let visible = splat_visibility(cam, splats, &scene.clips, &bin_tiles(cam, splats));
        visible.iter().map(|v| v.depth > 0.0).collect::<Vec<bool>>()
    };
    for size in [24, 48, 96] {
        for lod in [1.0, 2.0, 4.0] {
            let cfg = FrameConfig {
                lod,
                ..FrameConfig::default()
            };
            for view in views(&scene, size) {
                let cam = camera_uniform(&view, scene.bounds(), &cfg);
                let chosen = selection(&cam, &scene.splats, &tree);
                let full = covered(&cam, &scene.splats);
                let merged = covered(&cam, &drawn_splats(&scene.splats, &chosen.drawn));
                let holes = full
                    .iter()
                    .zip(&merged)
                    .filter(|(f, m)| **f && !**m)
                    .count();
                let drawn = chosen.selected.len();
                eprintln!("{size} px, lod {lod}: {drawn} splats drawn, {holes} holes");
                assert_eq!(holes, 0, "{size} px, lod {lod}");
                if size == 24 {
                    assert!(3 * drawn <= 2 * scene.splats.len(), "{drawn} drawn");
                }
            }
        }
    }
}

/// The glossy Cornell box, baked once on the CPU and drawn from two views by both paths, with
/// baked and ray-traced direct light, by the raster passes and by the compute splatter (whose
/// mirror is the raster passes' own: the same fragments summed per pixel in the same order).
#[test]
fn splat_passes_match_the_cpu_mirror() {
    let gpu = common::gpu();
    let (scene, grid, lobes) = glossy_cornell();
    assert!(lobes.stats.fitted > 500, "the glossy block has lobes");
    let modes =
        [Direct::Baked, Direct::Rays].map(|d| [(d, Splatter::Raster), (d, Splatter::Compute)]);
    for (direct, splatter) in modes.into_iter().flatten() {
        // The compute splatter draws every splat as it is, whatever the level of detail
        // (`frame_camera`); its mirror, the raster passes', then does too.
        let lod = match splatter {
            Splatter::Compute => 0.0,
            _ => FrameConfig::default().lod,
        };
        let cfg = FrameConfig {
            direct,
            splatter,
            lod,
            ..FrameConfig::default()
        };
        for view in views(&scene, 96) {
            let label = format!("{direct:?} {splatter:?}");
            let b = frames_agree(&gpu, (&scene, &grid, &lobes), &view, &cfg, &label);
            let lit = b.iter().filter(|p| p[0] + p[1] + p[2] > 0.0).count();
            assert!(lit > b.len() / 2, "most of the image shows the box");
        }
    }
}

fn plane_scene(light: &str) -> Scene {
    let text = format!(
        r#"
[camera]
eye = [0.0, 2.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov = 60.0
resolution = [33, 33]

[bake]
photons = 1000

[materials.grey]
diffuse = 0.5

{light}

[[object]]
shape = "quad"
material = "grey"
size = [4.0, 4.0]
rotate = [-90.0, 0.0, 0.0]
spacing = 0.05
"#
    );
    scene::parse(Path::new("plane.toml"), &text).unwrap()
}

/// A lone diffuse plane has no indirect light: the centre pixel is ρ/π × the irradiance of
/// the light in closed form, on both paths, for each light kind, from shadow rays at the pixel
/// (within 2e-3: f32 rounding) and from the direct bake (within 5e-3: the pixel blends splat
/// centres up to a radius, 0.04, off the axis, where a light 1 above gives (h / d)^3 or
/// (h / d)^4 of the irradiance, 1 − 2 r² ≈ 0.997 at the rim).
#[test]
fn direct_light_matches_closed_forms() {
    let gpu = common::gpu();
    let pi = std::f32::consts::PI;
    let cases = [
        // intensity 2 W/sr at 1 m: E = 2.
        (
            "[[light]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 2.0",
            2.0,
        ),
        // 3 W/m² arriving at 60° from the normal: E = 1.5.
        (
            "[[light]]\ntype = \"directional\"\ndirection = [0.0, -0.5, -0.8660254]\nirradiance = 3.0",
            1.5,
        ),
        // A spot of power P over a 30° cone without falloff: I = P / (2π (1 − cos 30°)).
        (
            "[[light]]\ntype = \"spot\"\nposition = [0.0, 2.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\npower = 10.0\nangle = 30.0",
            10.0 / (2.0 * pi * (1.0 - 30f32.to_radians().cos())) / 4.0,
        ),
        // A small square of radiance L at height h straight above: E ≈ L A / h².
        (
            "[[light]]\ntype = \"area\"\ncenter = [0.0, 1.0, 0.0]\nsize = [0.02, 0.02]\nnormal = [0.0, -1.0, 0.0]\nradiance = 5000.0",
            5000.0 * 0.0004,
        ),
    ];
    for ((light, irradiance), direct) in cases
        .into_iter()
        .flat_map(|c| [(c, Direct::Rays), (c, Direct::Baked)])
    {
        let cfg = FrameConfig {
            direct,
            ..FrameConfig::default()
        };
        let scene = plane_scene(light);
        let grid = common::host_grid(&scene);
        let lobes = cpu_bake(&scene, &grid);
        let view = View::new(&scene.camera, 33, 33);
        let expect = 0.5 / pi * irradiance;
        let centre = (16 * 33 + 16) as usize;
        for (name, hdr) in [
            ("cpu", cpu_hdr(&scene, &grid, &lobes, &view, &cfg)),
            ("gpu", gpu_frame(&gpu, &scene, &lobes, &view, &cfg)),
        ] {
            let got = hdr[centre];
            let tolerance = match direct {
                Direct::Rays => 2e-3,
                Direct::Baked => 5e-3,
            };
            for c in 0..3 {
                let rel = (got[c] - expect).abs() / expect;
                assert!(
                    rel < tolerance,
                    "{name} {direct:?}, {light}: {got:?} vs {expect}"
                );
            }
        }
    }
}

/// Light kinds a scene does not have cost nothing: the shading loops over the scene's own
/// lights, so the area lights' sample grid (N² shadow rays a pixel) touches no frame without
/// one: 1 and 8 samples a side give bit-identical frames under point, directional and spot
/// lights, and different ones under an area light (the test's check that the knob bites).
#[test]
fn light_kinds_not_in_the_scene_cost_nothing() {
    let gpu = common::gpu();
    let lights = [
        (
            "point",
            "[[light]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = 2.0",
        ),
        (
            "directional",
            "[[light]]\ntype = \"directional\"\ndirection = [0.0, -0.5, -0.8660254]\nirradiance = 3.0",
        ),
        (
            "spot",
            "[[light]]\ntype = \"spot\"\nposition = [0.0, 2.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\npower = 10.0\nangle = 30.0",
        ),
        (
            "area",
            "[[light]]\ntype = \"area\"\ncenter = [0.0, 1.0, 0.0]\nsize = [0.5, 0.5]\nnormal = [0.0, -1.0, 0.0]\nradiance = 50.0",
        ),
    ];
    for (kind, light) in lights {
        let scene = plane_scene(light);
        let grid = common::host_grid(&scene);
        let lobes = cpu_bake(&scene, &grid);
        let view = View::new(&scene.camera, 33, 33);
        let [one, many] = [1, 8].map(|area_samples| {
            let cfg = FrameConfig {
                area_samples,
                direct: Direct::Rays,
                ..FrameConfig::default()
            };
            gpu_frame(&gpu, &scene, &lobes, &view, &cfg)
        });
        let same = one == many;
        assert_eq!(
            same,
            kind != "area",
            "{kind} light: frames the same: {same}"
        );
    }
}

/// An area light seen directly shows its radiance, in front of what lies behind it.
#[test]
fn area_light_is_seen_directly() {
    let scene = plane_scene(
        "[[light]]\ntype = \"area\"\ncenter = [0.0, 1.0, 0.0]\nsize = [0.5, 0.5]\nnormal = [0.0, 1.0, 0.0]\nradiance = [1.0, 2.0, 3.0]",
    );
    let grid = common::host_grid(&scene);
    let lobes = cpu_bake(&scene, &grid);
    let view = View::new(&scene.camera, 33, 33);
    let hdr = cpu_hdr(&scene, &grid, &lobes, &view, &FrameConfig::default());
    let centre = hdr[16 * 33 + 16];
    let rel = |a: f32, b: f32| ((a - b) / b).abs();
    assert!(
        rel(centre[0], 1.0) < 1e-4 && rel(centre[1], 2.0) < 1e-4 && rel(centre[2], 3.0) < 1e-4,
        "{centre:?}"
    );
    // It faces up, away from the plane: the plane gets no light from it.
    assert_eq!(hdr[0][..3], [0.0; 3]);
}

/// An area light with a material shows its radiance added to what its own surface reflects:
/// here a point light above it lights that surface to ρ/π × E = 1 at the centre, so the centre
/// pixel reads the light's radiance plus one in every channel (within 1 %), where without a
/// material it reads the radiance alone.
#[test]
fn a_light_that_reflects_shows_its_surface_too() {
    let point = "[[light]]\ntype = \"point\"\nposition = [0.0, 1.5, 0.0]\npower = 19.7392088";
    let area = "[[light]]\ntype = \"area\"\ncenter = [0.0, 1.0, 0.0]\nsize = [0.5, 0.5]\n\
                normal = [0.0, 1.0, 0.0]\nradiance = [1.0, 2.0, 3.0]";
    let centre = |reflects: bool| {
        let material = if reflects {
            "\nmaterial = \"grey\"\nspacing = 0.05"
        } else {
            ""
        };
        let scene = plane_scene(&format!("{point}\n\n{area}{material}"));
        let grid = common::host_grid(&scene);
        let lobes = cpu_bake(&scene, &grid);
        let view = View::new(&scene.camera, 33, 33);
        cpu_hdr(&scene, &grid, &lobes, &view, &FrameConfig::default())[16 * 33 + 16]
    };
    let rel = |a: f32, b: f32| ((a - b) / b).abs();
    let (plain, reflecting) = (centre(false), centre(true));
    for (c, want) in [(0, 1.0), (1, 2.0), (2, 3.0)] {
        assert!(rel(plain[c], want) < 1e-4, "{plain:?}");
        assert!(rel(reflecting[c], want + 1.0) < 1e-2, "{reflecting:?}");
    }
}

#[test]
fn cache_key_follows_the_bake_not_the_view() {
    use lobelight::cache::{Miss, bake_key, load, save};
    let mut scene =
        plane_scene("[[light]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\npower = 1.0");
    let key = bake_key(&scene);
    let grid = common::host_grid(&scene);
    let lobes = cpu_bake(&scene, &grid);
    let path =
        std::env::temp_dir().join(format!("lobelight-cache-test-{}.bin", std::process::id()));
    save(&path, key, &lobes).unwrap();
    scene.camera.eye = [1.0, 2.0, 0.5];
    scene.camera.resolution = [64, 48];
    assert_eq!(bake_key(&scene), key, "the camera is not part of the bake");
    let back = load(&path, key, scene.splats.len()).unwrap().unwrap();
    assert_eq!(back.lobes, lobes.lobes);
    assert_eq!(back.light, lobes.light);
    scene.bake.iterations += 1;
    let changed = bake_key(&scene);
    assert_ne!(changed, key);
    assert_eq!(
        load(&path, changed, scene.splats.len()).unwrap().err(),
        Some(Miss::Stale)
    );
    std::fs::write(&path, b"not a cache").unwrap();
    assert!(
        load(&path, key, scene.splats.len()).is_err(),
        "a foreign file is an error"
    );
    std::fs::remove_file(&path).unwrap();
}

/// The same scene and seed give bit-identical lobes and HDR pixels on the same device: the
/// bake's atomics are integer, its reductions run in a fixed order, and the frame's blending
/// adds fragments in draw order.
#[test]
fn gpu_bake_and_frame_are_deterministic() {
    let gpu = common::gpu();
    let mut scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    scene.bake.photons = 50_000;
    let on_gpu = GpuScene::upload(&gpu, &scene).unwrap();
    let cfg = FrameConfig::default();
    let view = View::new(&scene.camera, 48, 48);
    let run = || {
        let lobes = bake(
            &scene,
            BakeDevice::Gpu(&gpu, &on_gpu),
            &Progress::new(false),
        )
        .unwrap()
        .lobes;
        let hdr = gpu_frame(&gpu, &scene, &lobes, &view, &cfg);
        (lobes, hdr)
    };
    let (a, b) = (run(), run());
    assert!(a.0.stats.fitted > 0, "the glossy block has lobes");
    assert!(
        a.1.iter().any(|p| p[0] > 0.0),
        "the frame shows the lit box"
    );
    let bits = |l: &LobeMap| -> Vec<u32> {
        let lobes = bytemuck::cast_slice::<_, u32>(&l.lobes);
        let light = bytemuck::cast_slice::<_, u32>(&l.light);
        lobes.iter().chain(light).copied().collect()
    };
    assert!(
        bits(&a.0) == bits(&b.0),
        "the lobes differ between two bakes"
    );
    let pixels = |p: &[[f32; 4]]| -> Vec<u32> { p.iter().flatten().map(|v| v.to_bits()).collect() };
    let differing = pixels(&a.1)
        .iter()
        .zip(pixels(&b.1))
        .filter(|(x, y)| **x != *y)
        .count();
    assert_eq!(differing, 0, "pixels differ between two frames");
}

/// The light terms a frame can show add up to the full frame, on the GPU and on the CPU
/// mirror: direct + indirect, and diffuse + specular. The parts are the same sums taken apart,
/// so they agree to f32 rounding (measured: mean relative 4e-9, worst pixel 2e-7; asserted
/// 1e-6 and 1e-5). The light seen directly counts with the direct diffuse term.
#[test]
fn shown_light_terms_add_up_to_the_full_frame() {
    use lobelight::frame::Terms;
    let gpu = common::gpu();
    let (scene, grid, lobes) = baked_scene("scenes/cornell.toml", 60_000);
    let view = View::new(&scene.camera, 64, 64);
    let with = |show: Terms, direct: Direct| FrameConfig {
        show,
        direct,
        ..FrameConfig::default()
    };
    let add = |a: Vec<[f32; 4]>, b: Vec<[f32; 4]>| -> Vec<[f32; 4]> {
        a.iter()
            .zip(&b)
            .map(|(p, q)| [p[0] + q[0], p[1] + q[1], p[2] + q[2], 1.0])
            .collect()
    };
    let specular = Terms::DIRECT_SPECULAR | Terms::INDIRECT_SPECULAR;
    let runs = [true, false].map(|g| [(g, Direct::Baked), (g, Direct::Rays)]);
    for (on_gpu, direct) in runs.into_iter().flatten() {
        let frame = |show: Terms| {
            if on_gpu {
                gpu_frame(&gpu, &scene, &lobes, &view, &with(show, direct))
            } else {
                cpu_hdr(&scene, &grid, &lobes, &view, &with(show, direct))
            }
        };
        let full = frame(Show::Full.terms());
        let splits = [
            (Show::Direct.terms(), Show::Indirect.terms()),
            (Show::Diffuse.terms(), specular),
        ];
        for (a, b) in splits {
            let d = difference(&add(frame(a), frame(b)), &full).unwrap();
            eprintln!("gpu {on_gpu}, {direct:?}, {a:?} + {b:?}: {d:?}");
            assert!(d.mean_relative <= 1e-6, "{d:?}");
            assert!(d.max_relative <= 1e-5, "{d:?}");
        }
        // A part alone is not the whole: the split is real.
        let direct = difference(&frame(Show::Direct.terms()), &full).unwrap();
        assert!(direct.energy < -0.05, "{direct:?}");
    }
}

/// The compute splatter's tile lists: the device's (atomics, then `grid_rank`) equal the
/// mirror's, list for list; and they are conservative: every splat whose disk covers a pixel
/// centre is in that pixel's tile's list (checked by brute force over every pixel and splat,
/// from a jittered camera).
#[test]
fn splat_tile_lists_match_the_mirror_and_miss_no_fragment() {
    use glam::{Vec2, Vec3};
    use lobelight::cpu::CpuExecutor;
    use lobelight::gpu::exec::GpuExecutor;
    use lobelight::sequence::{Executor, TILE, bin_splat_tiles};
    use lobelight::shared::splat::{covers, faces_camera, pixel_ray, splat_hit};

    let gpu = common::gpu();
    let scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    let views = views(&scene, 72);
    for (n, view) in views.iter().enumerate() {
        let mut cam = camera_uniform(view, scene.bounds(), &FrameConfig::default());
        cam.jitter = [0.3, -0.2];
        let count = scene.splats.len() as u32;
        let on_gpu = {
            let mut encoder = gpu.encoder("tiles");
            let mut ex = GpuExecutor::new(&gpu, &mut encoder);
            let cam_buf = ex.uniform("camera", &cam).unwrap();
            let splats = ex.upload("splats", &scene.splats).unwrap();
            let t = bin_splat_tiles(&mut ex, &cam, &cam_buf, &splats, count).unwrap();
            let tiles = (t.params.tiles_x * t.params.tiles_y) as usize;
            let start = ex.read::<u32>(&t.start, tiles + 1).unwrap();
            let entries = ex
                .read::<u32>(&t.splats, t.params.entry_count as usize)
                .unwrap();
            (start, entries)
        };
        let mut ex = CpuExecutor::default();
        let cam_buf = ex.uniform("camera", &cam).unwrap();
        let splats = ex.upload("splats", &scene.splats).unwrap();
        let t = bin_splat_tiles(&mut ex, &cam, &cam_buf, &splats, count).unwrap();
        let tiles_x = t.params.tiles_x;
        let tiles = (tiles_x * t.params.tiles_y) as usize;
        let start = ex.read::<u32>(&t.start, tiles + 1).unwrap();
        let entries = ex
            .read::<u32>(&t.splats, t.params.entry_count as usize)
            .unwrap();
        assert_eq!(on_gpu, (start.clone(), entries.clone()), "view {n}");
        assert!(
            entries.len() > scene.splats.len() / 4,
            "view {n}: most splats binned"
        );
        let eye = Vec3::from(cam.eye);
        let mut fragments = 0;
        for y in 0..view.height {
            for x in 0..view.width {
                let d = pixel_ray(&cam, Vec2::new(x as f32, y as f32) + 0.5);
                let tile = ((y / TILE) * tiles_x + x / TILE) as usize;
                let list = &entries[start[tile] as usize..start[tile + 1] as usize];
                for (i, s) in scene.splats.iter().enumerate() {
                    if faces_camera(s, eye) && covers(&cam, splat_hit(s, eye, d), d) {
                        fragments += 1;
                        assert!(
                            list.binary_search(&(i as u32)).is_ok(),
                            "view {n}: splat {i} at ({x}, {y})"
                        );
                    }
                }
            }
        }
        assert!(
            fragments > (view.width * view.height) as usize,
            "view {n}: {fragments}"
        );
    }
}

/// `splat_select` lists for shading only splats `in_view` says may cover a pixel: over a
/// plane seen from above and at a grazing angle, with the jitter at each corner of the pixel,
/// no splat it culls covers any pixel centre, and it culls some (the test's check that it bites).
#[test]
fn culled_splats_cover_no_pixel() {
    use glam::{Vec2, Vec3};
    use lobelight::shared::splat::{covers, faces_camera, in_view, pixel_ray, splat_hit};
    let mut scene =
        plane_scene("[[light]]\ntype = \"point\"\nposition = [0.0, 2.0, 0.0]\npower = 10.0");
    let (w, h) = (40, 30);
    let mut culled = 0;
    for (eye, target, up) in [
        (Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, [0.0, 0.0, -1.0]),
        (
            Vec3::new(1.8, 0.3, 1.5),
            Vec3::new(-0.5, 0.0, -0.2),
            [0.0, 1.0, 0.0],
        ),
    ] {
        scene.camera.eye = eye.to_array();
        scene.camera.target = target.to_array();
        scene.camera.up = up;
        let view = View::new(&scene.camera, w, h);
        for jitter in [[-0.5, -0.5], [0.5, -0.5], [-0.5, 0.5], [0.5, 0.5]] {
            let cam = lobelight::types::Camera {
                jitter,
                ..camera_uniform(&view, scene.bounds(), &FrameConfig::default())
            };
            for s in &scene.splats {
                if !faces_camera(s, Vec3::from(cam.eye)) || in_view(&cam, s) {
                    continue;
                }
                culled += 1;
                for y in 0..h {
                    for x in 0..w {
                        let d = pixel_ray(&cam, Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                        let hit = splat_hit(s, Vec3::from(cam.eye), d);
                        assert!(!covers(&cam, hit, d), "culled {s:?} covers ({x}, {y})");
                    }
                }
            }
        }
    }
    assert!(culled > 1000, "only {culled} splats culled");
}

/// A box's drawn edges are where the box ends (`wgsl/shared/drawn_clip.wgsl`), as traced rays
/// see them, in still images (moving frames draw disks as they are): looking square at a face, no pixel whose ray passes more than half a pixel outside
/// the box is drawn, by the raster passes, the compute splatter or the mirror, while every
/// pixel as far inside is. Without the clips the face's disks, overhanging its edges by 6 mm
/// (two pixels), would draw a rim around it.
#[test]
fn a_drawn_box_ends_at_its_edges() {
    use glam::{Vec2, Vec3};
    use lobelight::shared::splat::pixel_ray;
    let camera = "[camera]\neye = [3.0, 0.0, 0.0125]\ntarget = [0.0, 0.0, 0.0125]\nfov = 15.0";
    let mut scene = common::lit_box(camera, [2.0, 0.1, 0.2], 20.0);
    scene.bake.photons = 2_000;
    let grid = common::host_grid(&scene);
    let lobes = cpu_bake(&scene, &grid);
    let view = View::new(&scene.camera, 256, 256);
    let cam = camera_uniform(&view, scene.bounds(), &FrameConfig::default());
    // Where each pixel's ray meets the plane of the face x = 0.3, and a pixel there.
    let eye = Vec3::from(cam.eye);
    let pixel = 2.0 * (eye.x - 0.3) * (7.5f32).to_radians().tan() / 256.0;
    let (mut inside, mut outside) = (Vec::new(), Vec::new());
    for i in 0..256 * 256 {
        let d = pixel_ray(
            &cam,
            Vec2::new((i % 256) as f32 + 0.5, (i / 256) as f32 + 0.5),
        );
        let p = eye + (0.3 - eye.x) / d.x * d;
        let past = p.y.abs().max(p.z.abs()) - 0.3;
        if past > 0.5 * pixel {
            outside.push(i);
        } else if past < -0.5 * pixel {
            inside.push(i);
        }
    }
    let drawn = |image: &[[f32; 4]], i: usize| image[i][..3].iter().any(|&c| c > 0.0);
    let check = |what: &str, image: &[[f32; 4]]| {
        let rim = outside.iter().filter(|&&i| drawn(image, i)).count();
        let holes = inside.iter().filter(|&&i| !drawn(image, i)).count();
        assert_eq!(
            (rim, holes),
            (0, 0),
            "{what}: pixels drawn outside, undrawn inside"
        );
    };
    // Still images (direct light by shadow rays); moving frames draw disks as they are.
    let still = FrameConfig {
        direct: Direct::Rays,
        ..FrameConfig::default()
    };
    let gpu = common::gpu();
    for splatter in [Splatter::Raster, Splatter::Compute] {
        let cfg = FrameConfig { splatter, ..still };
        check(
            splatter.name(),
            &gpu_frame(&gpu, &scene, &lobes, &view, &cfg),
        );
    }
    let cfg = still.clone();
    check("mirror", &cpu_hdr(&scene, &grid, &lobes, &view, &cfg));
    scene.clips.clear();
    let unclipped = cpu_hdr(&scene, &grid, &lobes, &view, &cfg);
    let rim = outside.iter().filter(|&&i| drawn(&unclipped, i)).count();
    assert!(rim > 500, "unclipped, {rim} pixels drawn outside the box");
}

/// A frame of baked direct light selects what it draws chunk by chunk of the level of detail's
/// tree (`chunk_visits`) and draws exactly the splats, at the radii, that the per-splat rule
/// (`drawn_radius`) draws over every splat, with the level of detail off and on: on the mirror
/// the same set, on the device the mirror's list in its order. The chunks bite: a close view
/// of a corner visits under half of the splats, and with the level of detail at 4 pixels the
/// front view visits fewer than it would without it.
#[test]
fn selection_by_chunks_draws_what_every_splat_would() {
    use lobelight::cpu::splat_nodes::walk;
    use lobelight::cpu::splat_select::{selection, splat_select};
    use lobelight::frame::{Splatting, frame_camera};
    use lobelight::lod::visited;
    use lobelight::shared::splat::{drawn_radius, lod_level};
    let gpu = common::gpu();
    let (scene, _, lobes) = glossy_cornell();
    let (tree, flat) = (scene.lod_tree(true), scene.lod_tree(false));
    let mut renderer = FrameRenderer::new(&gpu, &scene).unwrap();
    renderer.set_lobes(&gpu, &scene, &lobes).unwrap();
    let mut views = views(&scene, 96);
    let mut corner = scene.camera.clone();
    corner.eye = [0.3, -0.3, 0.3];
    corner.target = [1.0, -1.0, -1.0];
    views.push(View::new(&corner, 96, 96));
    let n = scene.splats.len();
    let exact = common::rounds_like_the_mirror(&gpu);
    for (v, view) in views.iter().enumerate() {
        let mut visits_at = Vec::new();
        for lod in [0.0, 1.5, 4.0] {
            let cfg = FrameConfig {
                splatter: Splatter::Raster,
                lod,
                ..FrameConfig::default()
            };
            let params = shade_params(&scene, &lobes, &cfg);
            let cam = frame_camera(
                &camera_uniform(view, scene.bounds(), &cfg),
                &params,
                Splatting::Raster,
            );
            let t = if lod > 0.0 { &tree } else { &flat };
            let want: Vec<(u32, f32)> = (0..n)
                .filter_map(|i| {
                    let (s, lod) = (&scene.splats[i], t.lod(i as u32));
                    let r = drawn_radius(&cam, s, lod, lod_level(&cam, s, lod));
                    (r > 0.0).then_some((i as u32, r))
                })
                .collect();
            let chosen = selection(&cam, &scene.splats, t);
            let mut got: Vec<(u32, f32)> = chosen
                .selected
                .iter()
                .map(|&i| (i, chosen.drawn[i as usize]))
                .collect();
            got.sort_by_key(|&(i, _)| i);
            assert!(
                got == want,
                "view {v}, lod {lod}: {} against {}",
                got.len(),
                want.len()
            );
            let walked = walk(&cam, t);
            let selected = splat_select(&cam, &scene.splats, t, &walked[0]);
            let visited: usize = t
                .chunks
                .iter()
                .zip(&selected.visits)
                .map(|(ch, &m)| visited(ch, m).count())
                .sum();
            eprintln!(
                "view {v}, lod {lod}: {} drawn, {visited} of {n} visited",
                got.len()
            );
            visits_at.push(visited);

            renderer.draw(&gpu, &scene, view, &cfg).unwrap();
            let (list, radii) = renderer.read_selection(&gpu).unwrap();
            let listed: Vec<f32> = list.iter().map(|&i| chosen.drawn[i as usize]).collect();
            if exact {
                if list != chosen.selected {
                    let k = list.iter().zip(&chosen.selected).position(|(a, b)| a != b);
                    panic!(
                        "view {v}, lod {lod}: {} listed against {}, first apart at {k:?}: {:?} {:?}",
                        list.len(),
                        chosen.selected.len(),
                        k.map(|k| &list[k.saturating_sub(2)..(k + 3).min(list.len())]),
                        k.map(|k| &chosen.selected
                            [k.saturating_sub(2)..(k + 3).min(chosen.selected.len())])
                    );
                }
                assert_eq!(radii, listed, "view {v}, lod {lod}");
            } else {
                // Elsewhere a splat at the view's edge may round to the other side.
                let mine: std::collections::HashSet<u32> =
                    chosen.selected.iter().copied().collect();
                let theirs: std::collections::HashSet<u32> = list.iter().copied().collect();
                let apart = mine.symmetric_difference(&theirs).count();
                assert!(
                    apart * 1000 <= mine.len(),
                    "view {v}, lod {lod}: {apart} apart"
                );
            }
        }
        if v == 2 {
            assert!(
                2 * visits_at[0] < n,
                "the corner visits {} of {n}",
                visits_at[0]
            );
        }
        if v == 0 {
            assert!(visits_at[2] < visits_at[0], "lod 4 visits {visits_at:?}");
        }
    }
}

/// A frame walks the chunks' nodes from the top and culls whole subtrees: of two patches of
/// splats far apart, the one outside the view costs the walk one node, whose children read a
/// word each and no record, and no chunk of it is read. The patch in view is selected as the
/// per-splat rule selects it.
#[test]
fn the_walk_skips_a_patch_outside_the_view() {
    use lobelight::cpu::splat_nodes::walk;
    use lobelight::cpu::splat_select::selection;
    use lobelight::frame::{Splatting, frame_camera};
    use lobelight::lod::{CHUNK, LodTree, NODE_FANOUT};
    use lobelight::shared::splat::{drawn_radius, lod_level};
    use lobelight::types::Splat;
    // Two 256 × 256 grids of disks facing +z, one round the origin and one 100 units along x:
    // 256 chunks each, 16 nodes each above them.
    let side = 256;
    let splats: Vec<Splat> = (0..2 * side * side)
        .map(|k| {
            let (patch, i) = (k / (side * side), k % (side * side));
            let step = 2.0 / side as f32;
            Splat {
                center: [
                    -1.0 + (i % side) as f32 * step + 100.0 * patch as f32,
                    -1.0 + (i / side) as f32 * step,
                    0.0,
                ],
                radius: step,
                normal: [0.0, 0.0, 1.0],
                ..Splat::default()
            }
        })
        .collect();
    let far = |i: u32| splats[i as usize].center[0] > 50.0;
    let tree = LodTree::build(&splats, false);
    assert_eq!(tree.chunks.len(), 2 * side * side / CHUNK);
    let (scene, _, lobes) = glossy_cornell();
    let mut camera = scene.camera.clone();
    camera.eye = [0.0, 0.0, 3.0];
    camera.target = [0.0, 0.0, 0.0];
    let view = View::new(&camera, 128, 128);
    let bounds = lobelight::grid::splat_bounds(&splats).unwrap();
    for lod in [0.0, 1.5] {
        let cfg = FrameConfig {
            lod,
            ..FrameConfig::default()
        };
        let params = shade_params(&scene, &lobes, &cfg);
        let cam = frame_camera(
            &camera_uniform(&view, bounds, &cfg),
            &params,
            Splatting::Raster,
        );
        let t = if lod > 0.0 {
            &tree
        } else {
            &LodTree::flat(&splats)
        };
        let walked = walk(&cam, t);
        // Per level, from the chunks up: the records read (a parent that visits something).
        let mut read = Vec::new();
        for (level, visits) in walked.iter().enumerate() {
            let below = match level {
                0 => t.chunks.len(),
                _ => t.nodes[level - 1].len(),
            };
            read.push((0..below).filter(|j| visits[j / NODE_FANOUT] != 0).count());
        }
        read.push(walked.last().map_or(0, |v| v.len()));
        eprintln!("lod {lod}: records read per level, chunks first: {read:?}");
        // The far patch's chunks: none read.
        let far_chunks: Vec<usize> = (0..t.chunks.len())
            .filter(|&c| far(t.order[c * CHUNK]))
            .collect();
        assert_eq!(far_chunks.len(), t.chunks.len() / 2);
        assert!(
            far_chunks.iter().all(|&c| walked[0][c / NODE_FANOUT] == 0),
            "lod {lod}: a chunk of the far patch was read"
        );
        // Above the chunks, the far patch's 16 nodes read a word each: their parent, one
        // node for the whole patch, visits nothing.
        assert_eq!(read[0], t.chunks.len() / 2, "lod {lod}: {read:?}");
        assert_eq!(read[1], t.nodes[0].len() / 2, "lod {lod}: {read:?}");
        let want: Vec<u32> = (0..splats.len() as u32)
            .filter(|&i| {
                let (s, l) = (&splats[i as usize], t.lod(i));
                drawn_radius(&cam, s, l, lod_level(&cam, s, l)) > 0.0
            })
            .collect();
        let mut got = selection(&cam, &splats, t).selected;
        got.sort_unstable();
        assert!(!want.is_empty() && !want.iter().any(|&i| far(i)));
        assert_eq!(got, want, "lod {lod}");
    }
}

/// A ground seen from just above it, looking 18° down, as outdoor views look: nearly half its
/// splats lie behind the eye and many of the rest outside the view. The mirror's rasterizer gives
/// none of those a pixel (each of them used to cost every pixel of every frame: a 96² still of
/// a 40,000-splat ground took minutes), lists only a handful of splats on the whole image
/// (those across the near plane, within the view), and covers every pixel as testing every
/// splat at every pixel does.
#[test]
fn a_ground_seen_from_just_above_lists_only_what_the_view_holds() {
    use lobelight::cpu::splat_visibility::{Rect, Tiles, bin_tiles, splat_visibility};
    let text = "[camera]\neye = [0.0, 1.0, 0.0]\ntarget = [0.0, 0.675, -1.0]\nfov = 60\n\n\
                [[light]]\ntype = \"directional\"\ndirection = [-0.3, -1.0, -0.2]\n\
                irradiance = [2.0, 2.0, 2.0]\n\n[[object]]\nshape = \"quad\"\n\
                size = [10.0, 10.0]\nspacing = 0.2\nrotate = [-90.0, 0.0, 0.0]\n";
    let scene = scene::parse(Path::new("ground.toml"), text).unwrap();
    let view = View::new(&scene.camera, 48, 48);
    let cam = camera_uniform(&view, scene.bounds(), &FrameConfig::default());
    let tiles = bin_tiles(&cam, &scene.splats);
    let eye = glam::Vec3::from(cam.eye);
    let forward = glam::Vec3::from(cam.forward);
    let behind = (scene.splats.iter())
        .filter(|s| (glam::Vec3::from(s.center) - eye).dot(forward) < -2.0 * s.radius)
        .count();
    let listed = tiles.bounds.iter().filter(|b| b.is_some()).count();
    let whole = (tiles.bounds.iter().flatten())
        .filter(|r| (r.x1 - r.x0, r.y1 - r.y0) == (48, 48))
        .count();
    eprintln!(
        "{} splats, {behind} behind the eye, {listed} listed, {whole} on the whole image",
        scene.splats.len()
    );
    assert!(5 * behind >= 2 * scene.splats.len(), "{behind} behind");
    assert!(listed + behind <= scene.splats.len());
    assert!(whole <= 10, "{whole} splats on the whole image");
    // Every splat at every pixel: what the culled bounds must not change.
    let all = (0..scene.splats.len() as u32).collect::<Vec<u32>>();
    let everything = Tiles {
        lists: vec![all; tiles.lists.len()],
        bounds: vec![
            Some(Rect {
                x0: 0,
                y0: 0,
                x1: 48,
                y1: 48
            });
            scene.splats.len()
        ],
        ..tiles
    };
    let culled = splat_visibility(
        &cam,
        &scene.splats,
        &scene.clips,
        &bin_tiles(&cam, &scene.splats),
    );
    let brute = splat_visibility(&cam, &scene.splats, &scene.clips, &everything);
    assert!(culled.iter().filter(|v| v.depth > 0.0).count() > 48 * 20);
    assert_eq!(culled, brute);
}
