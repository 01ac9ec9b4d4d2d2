//! `estimate_coverage`: the share of a splat's gather disk that its surface covers, and its photon
//! irradiance divided by it (docs/design.md section 6), on the device and the mirror.

mod common;

use std::path::Path;

use glam::Vec3;

use lobelight::cpu::CpuExecutor;
use lobelight::cpu::estimate_coverage::{COVERAGE_POINTS, surface_weight};
use lobelight::fit_groups::{COVER_CELL, CoverGroups};
use lobelight::gpu::exec::GpuExecutor;
use lobelight::gpu::scene::GpuScene;
use lobelight::scene::{self, Scene};
use lobelight::sequence::{CoverInput, Executor, cover_light};
use lobelight::types::{EmParams, SplatLight};

/// Every splat's light after `estimate_coverage` on `ex`, each splat starting with irradiance 1,
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

/// `covered` on the mirror, after checking that the device gives the same splat by splat.
fn covered_on_both(scene: &Scene, em: &EmParams) -> Vec<f32> {
    let gpu = common::gpu();
    let grid = common::host_grid(scene);
    let on_cpu = covered(&mut CpuExecutor::tracing(scene.geometry(&grid)), scene, em);
    let on_gpu = {
        let on_gpu = GpuScene::upload(&gpu, scene).unwrap();
        let mut encoder = gpu.encoder("coverage");
        let mut ex = GpuExecutor::new(&gpu, &mut encoder).tracing(on_gpu.geometry());
        covered(&mut ex, scene, em)
    };
    for (i, (a, b)) in on_gpu.iter().zip(&on_cpu).enumerate() {
        assert!((a - b).abs() <= 1e-6 * b, "splat {i}: {a} against {b}");
    }
    on_cpu
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
    lit_shape(&format!("shape = \"quad\"\n{object_lines}"), radius)
}

/// `lit_quad` of any shape: one object of these lines.
fn lit_shape(object_lines: &str, radius: f32) -> (Scene, EmParams) {
    let text = format!(
        "[camera]\neye = [0.0, 0.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\n\
         [materials.white]\ndiffuse = [0.5, 0.5, 0.5]\n\
         [[light]]\ntype = \"point\"\nposition = [0.0, 0.0, 1.0]\nintensity = [1.0, 1.0, 1.0]\n\
         [[object]]\nmaterial = \"white\"\n{object_lines}"
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
/// disks' rims past the edge included; one at a corner about a third. Device and mirror agree
/// splat by splat.
#[test]
fn coverage_of_a_quad_is_whole_inside_half_at_an_edge() {
    let (scene, em) = lit_quad("", 0.1);
    let on_cpu = covered_on_both(&scene, &em);
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
/// area) plus what the measure's 64 points can jump when an edge crosses them (18 of them, the
/// bound the square grid's rows of 9 points set, two edges at a corner); on average by under
/// 0.01. Device and mirror agree.
#[test]
fn a_dense_quad_shares_its_coverage_within_the_bound() {
    let gpu = common::gpu();
    let radius = 0.1f32;
    let (scene, em) = lit_quad("size = [0.4, 0.4]\nspacing = 0.003\n", radius);
    let n = scene.splats.len();
    let groups = CoverGroups::new(&scene.splats, radius, None).unwrap();
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
        let bound = 0.64 * moved / radius + 18.0 / COVERAGE_POINTS.len() as f32;
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

/// A sphere of radius 0.04 at spacing 0.006, gather radius 0.05: the photons' test keeps a cap
/// of each splat's surface, out to 40° (within the slab of two splat radii of its plane,
/// within R), whose photons are those its surface sends the splat's front. The splats' mean
/// share is the cap's integral of (1 + cos θ)/2 over πR² within 3 %, and each splat's share
/// what the same 64 points give on the exact sphere, weighed by `surface_weight`, within 2.5
/// points (the disks approximate the sphere); the share of the cap's shadow in the plane, which
/// the measure counted before, is 7 % less. Device and mirror agree splat by splat.
#[test]
fn coverage_of_a_sphere_counts_the_photons_its_surface_sends() {
    let (rho, radius) = (0.04f32, 0.05f32);
    let (scene, em) = lit_shape(
        "shape = \"sphere\"\nradius = 0.04\nspacing = 0.006\n",
        radius,
    );
    let on_cpu = covered_on_both(&scene, &em);
    let n = scene.splats.len() as f32;
    let mean_share = on_cpu.iter().map(|l| 1.0 / l).sum::<f32>() / n;
    let slab = em.slab * scene.splats.iter().map(|s| s.radius).sum::<f32>() / n;
    // The cap's half-angle: its height within the slab, its chord within R (both well
    // inside 60°). Its photons from the splat's front, (1 + cos θ)/2 of its surface's
    // (`surface_weight`), over πR², against the share of its shadow in the plane alone.
    let cap = (1.0 - slab / rho)
        .acos()
        .min(2.0 * (radius / (2.0 * rho)).asin());
    let c = cap.cos();
    let expected = rho * rho * ((1.0 - c) + 0.5 * (1.0 - c * c)) / (radius * radius);
    let shadow = (rho * cap.sin() / radius).powi(2);
    // Each splat's share from the same 64 points on the exact sphere: a splat's disks, flat,
    // turn a point or two at the cap's rim either way.
    let mut on_sphere = 0.0;
    for u in COVERAGE_POINTS {
        let lateral = glam::Vec2::from(u).length() * radius;
        let cos = (1.0 - (lateral / rho).powi(2)).max(0.0).sqrt();
        let height = rho * (1.0 - cos);
        if height <= slab && lateral * lateral + height * height <= radius * radius {
            on_sphere += surface_weight(cos);
        }
    }
    let points = COVERAGE_POINTS.len() as f32;
    on_sphere /= points;
    eprintln!(
        "a sphere's splats: mean share {mean_share}, expected {expected} ({on_sphere} at the \
         64 points), its shadow {shadow}"
    );
    assert!(
        (mean_share - expected).abs() <= 0.03 * expected,
        "mean share {mean_share}"
    );
    for (i, l) in on_cpu.iter().enumerate() {
        let share = 1.0 / l;
        assert!(
            (share - on_sphere).abs() <= 2.5 / points,
            "splat {i}: share {share}"
        );
    }
    // The shadow alone, what the measure counted before, is 7 % less.
    assert!(expected >= 1.05 * shadow, "the test tells the two apart");
}

/// The WGSL twin tests the same points: its `COVERAGE_POINTS` literals are the mirror's, and
/// these are the spiral (point k at radius √((k + ½)/N), the golden angle on from the last).
#[test]
fn the_coverage_points_are_one_spiral_in_both_twins() {
    let wgsl = std::fs::read_to_string("wgsl/estimate_coverage.wgsl").unwrap();
    let table = wgsl.split("const COVERAGE_POINTS").nth(1).unwrap();
    let table = &table[..table.find(");").unwrap()];
    let values: Vec<f32> = table
        .split("vec2<f32>(")
        .skip(1)
        .flat_map(|v| {
            v.split(')')
                .next()
                .unwrap()
                .split(',')
                .map(|x| x.trim().parse().unwrap())
        })
        .collect();
    let mirror: Vec<f32> = COVERAGE_POINTS.iter().flatten().copied().collect();
    assert_eq!(values, mirror);
    let n = COVERAGE_POINTS.len() as f64;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for (k, u) in COVERAGE_POINTS.iter().enumerate() {
        let r = ((k as f64 + 0.5) / n).sqrt();
        let a = k as f64 * golden;
        let (x, y) = (r * a.cos(), r * a.sin());
        assert!(
            (u[0] as f64 - x).abs() < 1e-6 && (u[1] as f64 - y).abs() < 1e-6,
            "point {k}"
        );
    }
}
