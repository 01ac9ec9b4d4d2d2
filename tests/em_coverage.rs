//! `em_coverage`: the share of a splat's gather disk that its surface covers, and its photon
//! irradiance divided by it (docs/design.md section 6), on the device and the mirror.

mod common;

use std::path::Path;

use glam::Vec3;

use lobelight::cpu::CpuExecutor;
use lobelight::fit_groups::{COVER_CELL, CoverGroups};
use lobelight::gpu::exec::GpuExecutor;
use lobelight::gpu::scene::GpuScene;
use lobelight::scene::{self, Scene};
use lobelight::sequence::{CoverInput, Executor, cover_light};
use lobelight::types::{EmParams, SplatLight};

/// Every splat's light after `em_coverage` on `ex`, each splat starting with irradiance 1,
/// each measuring its own coverage.
fn covered<E: Executor>(ex: &mut E, scene: &Scene, em: &EmParams) -> Vec<f32> {
    covered_in(ex, scene, em, None)
}

/// `covered`, with the coverage measured once a group of `groups` where they are given.
fn covered_in<E: Executor>(
    ex: &mut E,
    scene: &Scene,
    em: &EmParams,
    groups: Option<&CoverGroups>,
) -> Vec<f32> {
    let n = scene.splats.len();
    let start = vec![
        SplatLight {
            irradiance: [1.0; 3],
            photons: 1,
            ..Default::default()
        };
        n
    ];
    let light = ex.upload("light", &start).unwrap();
    let words = groups.map(|g| ex.upload("groups", &g.words).unwrap());
    let cover = groups.zip(words.as_ref()).map(|(g, words)| CoverInput {
        words,
        groups: g.groups,
    });
    cover_light(ex, em, &light, cover.as_ref()).unwrap();
    let out: Vec<SplatLight> = ex.read(&light, n).unwrap();
    out.iter().map(|l| l.irradiance[0]).collect()
}

/// The splat nearest `p`.
fn nearest(scene: &Scene, p: Vec3) -> usize {
    (0..scene.splats.len())
        .min_by(|&a, &b| {
            let d = |i: usize| Vec3::from(scene.splats[i].center).distance(p);
            d(a).total_cmp(&d(b))
        })
        .unwrap()
}

/// A quad lit from above, of the given `size` and `spacing` lines (empty: the defaults), and
/// the coverage pass's parameters for gather radius `radius`.
fn lit_quad(object_lines: &str, radius: f32) -> (Scene, EmParams) {
    let text = format!(
        "[camera]\neye = [0.0, 0.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\n\
         [materials.white]\ndiffuse = [0.5, 0.5, 0.5]\n\
         [[light]]\ntype = \"point\"\nposition = [0.0, 0.0, 1.0]\nintensity = [1.0, 1.0, 1.0]\n\
         [[object]]\nshape = \"quad\"\nmaterial = \"white\"\n{object_lines}"
    );
    let scene = scene::parse(Path::new("quad.toml"), &text).unwrap();
    let em = EmParams {
        radius,
        radius2: radius * radius,
        slab: scene.bake.slab,
        splat_count: scene.splats.len() as u32,
        ..Default::default()
    };
    (scene, em)
}

/// A 1 × 1 quad of splats 0.025 apart, gather radius 0.1. A splat inside covers all its disk
/// (its irradiance unchanged); one on the middle of an edge a little more than half of it, the
/// disks' rims past the edge included (measured 0.565, 39 of the 69 points); one at a corner
/// about a third (0.319). Device and mirror agree splat by splat.
#[test]
fn coverage_of_a_quad_is_whole_inside_half_at_an_edge() {
    let gpu = common::gpu();
    let (scene, em) = lit_quad("", 0.1);
    let grid = common::host_grid(&scene);
    let geometry = scene.geometry(&grid);
    let on_cpu = covered(&mut CpuExecutor::tracing(geometry), &scene, &em);
    let on_gpu = {
        let on_gpu = GpuScene::upload(&gpu, &scene).unwrap();
        let mut encoder = gpu.encoder("coverage");
        let mut ex = GpuExecutor::new(&gpu, &mut encoder).tracing(on_gpu.geometry());
        covered(&mut ex, &scene, &em)
    };
    for (i, (a, b)) in on_gpu.iter().zip(&on_cpu).enumerate() {
        assert!((a - b).abs() <= 1e-6 * b, "splat {i}: {a} against {b}");
    }
    let share = |p: Vec3| 1.0 / on_cpu[nearest(&scene, p)];
    let (inside, edge, corner) = (
        share(Vec3::ZERO),
        share(Vec3::new(0.5, 0.0, 0.0)),
        share(Vec3::new(0.5, 0.5, 0.0)),
    );
    eprintln!("shares: inside {inside}, edge {edge}, corner {corner}");
    assert_eq!(inside, 1.0);
    assert!((0.55..=0.75).contains(&edge), "edge {edge}");
    assert!((0.25..=0.5).contains(&corner), "corner {corner}");
}

/// A dense quad (0.4 × 0.4 at spacing 0.003, 17,689 splats, gather radius 0.1): its splats
/// measure their coverage in groups (cells of R/16), at a quarter of the splats or fewer, and
/// each splat's share differs from its own measure by no more than the share can move between
/// it and its group's leader (0.64 per R the centre moves: the disk's widest chord over its
/// area) plus what the measure's grid of 69 points can jump when an edge crosses it (a row of
/// 9 points an edge; two at a corner); on average by under 0.01. Device and mirror agree.
#[test]
fn a_dense_quad_shares_its_coverage_within_the_bound() {
    let gpu = common::gpu();
    let radius = 0.1f32;
    let (scene, em) = lit_quad("size = [0.4, 0.4]\nspacing = 0.003\n", radius);
    let n = scene.splats.len();
    let groups = CoverGroups::new(&scene.splats, radius).unwrap();
    assert!(
        groups.groups as usize * 4 <= n,
        "{} groups of {n} splats",
        groups.groups
    );
    let grid = common::host_grid(&scene);
    let geometry = scene.geometry(&grid);
    let own = covered(&mut CpuExecutor::tracing(geometry), &scene, &em);
    let shared = covered_in(
        &mut CpuExecutor::tracing(geometry),
        &scene,
        &em,
        Some(&groups),
    );
    let on_gpu = {
        let on_gpu = GpuScene::upload(&gpu, &scene).unwrap();
        let mut encoder = gpu.encoder("coverage");
        let mut ex = GpuExecutor::new(&gpu, &mut encoder).tracing(on_gpu.geometry());
        covered_in(&mut ex, &scene, &em, Some(&groups))
    };
    for (i, (a, b)) in on_gpu.iter().zip(&shared).enumerate() {
        assert!((a - b).abs() <= 1e-6 * b, "splat {i}: {a} against {b}");
    }
    let leaders = &groups.words[n..];
    let (mut sum, mut most) = (0.0, 0.0f32);
    for i in 0..n {
        let leader = leaders[groups.words[i] as usize] as usize;
        let moved = Vec3::from(scene.splats[i].center).distance(scene.splats[leader].center.into());
        assert!(moved <= 3f32.sqrt() * COVER_CELL * radius);
        let (a, b) = (1.0 / shared[i], 1.0 / own[i]);
        let bound = 0.64 * moved / radius + 18.0 / 69.0;
        assert!(
            (a - b).abs() <= bound,
            "splat {i}: share {a} against its own {b}"
        );
        sum += (a - b).abs();
        most = most.max((a - b).abs());
    }
    let mean = sum / n as f32;
    eprintln!(
        "{} groups of {n} splats; share difference: mean {mean}, most {most}",
        groups.groups
    );
    assert!(mean < 0.01, "mean share difference {mean}");
}
