//! Photon emission and tracing: GPU against the CPU mirror (same random numbers, so the same
//! paths), energy bookkeeping in closed boxes, every light type, the growable store, and
//! determinism.

mod common;

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;
use lobelight::photons::{PhotonConfig, PhotonMap};
use lobelight::renderer::{Engine, Renderer};
use lobelight::scene::{self, Scene, file::StoreRange};
use lobelight::types::Photon;

fn parse(text: &str) -> Scene {
    scene::parse(Path::new("test.toml"), text).unwrap()
}

fn config(scene: &Scene, photons: u64, store: StoreRange) -> PhotonConfig {
    PhotonConfig {
        photons,
        store,
        ..PhotonConfig::from_scene(scene)
    }
}

fn on_cpu(scene: &Scene, cfg: &PhotonConfig) -> PhotonMap {
    traced_on(&Engine::Mirror, scene, cfg)
}

/// The photons `engine` traces, read back.
fn traced_on(engine: &Engine, scene: &Scene, cfg: &PhotonConfig) -> PhotonMap {
    let renderer = Renderer::new(std::sync::Arc::new(scene.clone()), engine).unwrap();
    renderer.trace_photons(cfg, &mut |_, _| {}).unwrap().map
}

/// Σ power of the photons of one bounce, per channel, in f64.
fn power_at(map: &PhotonMap, bounce: u32) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    for p in map.photons.iter().filter(|p| p.bounce == bounce) {
        for (s, &x) in sum.iter_mut().zip(&p.power) {
            *s += x as f64;
        }
    }
    sum
}

fn count_at(map: &PhotonMap, bounce: u32) -> usize {
    map.photons.iter().filter(|p| p.bounce == bounce).count()
}

fn assert_finite(map: &PhotonMap, what: &str) {
    for p in &map.photons {
        let all = p.position.iter().chain(&p.direction).chain(&p.power);
        assert!(
            all.clone().all(|v| v.is_finite()),
            "{what}: non-finite photon {p:?}"
        );
        assert!(
            p.power.iter().all(|&v| v >= 0.0),
            "{what}: negative power {p:?}"
        );
        let d = Vec3::from(p.direction).length();
        assert!((d - 1.0).abs() < 1e-4, "{what}: direction of length {d}");
    }
}

fn cornell() -> Scene {
    scene::load(Path::new("scenes/cornell.toml")).unwrap()
}

// ---------------------------------------------------------------------------------------
// Parity

/// The GPU and the CPU mirror draw the same random numbers, so each path is the same path:
/// direct and first-bounce photons agree one by one (matched by (path, bounce)) within the
/// rounding that differs between the two (FMA contraction, transcendental functions). The
/// splat index may differ where overlapping disks meet: a rounding-sized change of direction
/// picks the other of two disks at the same place.
#[test]
fn first_bounces_match_the_cpu_mirror_photon_by_photon() {
    let device = common::device();
    let scene = cornell();
    let cfg = config(&scene, 50_000, StoreRange::All);
    let a = traced_on(&device, &scene, &cfg);
    let b = on_cpu(&scene, &cfg);
    assert_finite(&a, "GPU");
    assert_finite(&b, "CPU");
    // First-hit power is the emitted power times the fraction of photons that hit (each of the
    // area light's photons carries P / N).
    for map in [&a, &b] {
        let hit = count_at(map, 0) as f64 / cfg.photons as f64;
        let p0 = power_at(map, 0);
        for c in 0..3 {
            let emitted = scene.lights[0].power[c] as f64;
            assert!(
                (p0[c] / (emitted * hit) - 1.0).abs() < 1e-5,
                "bounce 0 power {p0:?}"
            );
        }
    }
    let by_key: HashMap<(u32, u32), &Photon> = b.photons.iter().map(|p| (p.key(), p)).collect();
    for bounce in [0, 1] {
        let ours: Vec<&Photon> = a.photons.iter().filter(|p| p.bounce == bounce).collect();
        let close = |p: &Photon, q: &Photon| {
            let pos = (Vec3::from(p.position) - Vec3::from(q.position))
                .abs()
                .max_element();
            let dir = (Vec3::from(p.direction) - Vec3::from(q.direction))
                .abs()
                .max_element();
            let pw = (Vec3::from(p.power) - Vec3::from(q.power))
                .abs()
                .max_element()
                / Vec3::from(q.power).max_element().max(1e-30);
            pos <= 1e-4 && dir <= 1e-4 && pw <= 1e-4
        };
        let matched = ours
            .iter()
            .filter(|p| by_key.get(&p.key()).is_some_and(|q| close(p, q)))
            .count();
        let frac = matched as f64 / ours.len() as f64;
        eprintln!(
            "bounce {bounce}: {matched} of {} GPU photons match the CPU's",
            ours.len()
        );
        assert!(
            ours.len() > 10_000,
            "bounce {bounce}: too few photons to test"
        );
        assert!(
            frac >= 0.999,
            "bounce {bounce}: only {:.4} % match",
            100.0 * frac
        );
        let theirs = count_at(&b, bounce);
        assert!(
            ours.len().abs_diff(theirs) * 1000 <= theirs,
            "bounce {bounce}: {} vs {theirs}",
            ours.len()
        );
    }
}

/// Over full multi-bounce runs with *different* seeds, the power stored per region of splats
/// agrees within its statistical error (compound-Poisson variance Σ power²).
#[test]
fn stored_power_per_region_agrees_statistically() {
    let device = common::device();
    let scene = cornell();
    let cfg = config(&scene, 100_000, StoreRange::Indirect);
    let a = traced_on(
        &device,
        &scene,
        &PhotonConfig {
            seed: 1,
            ..cfg.clone()
        },
    );
    let b = on_cpu(&scene, &PhotonConfig { seed: 2, ..cfg });
    // Regions: 48 blocks of consecutive splats (objects and walls are laid out in order, so a
    // block is a patch of one surface or two).
    const REGIONS: usize = 48;
    let region = |p: &Photon| p.splat as usize * REGIONS / scene.splats.len();
    let sums = |m: &PhotonMap| {
        let mut s = vec![(0.0f64, 0.0f64); REGIONS];
        for p in &m.photons {
            let w = p.power.iter().map(|&x| x as f64).sum::<f64>() / 3.0;
            s[region(p)].0 += w;
            s[region(p)].1 += w * w;
        }
        s
    };
    let (sa, sb) = (sums(&a), sums(&b));
    let mut chi2 = 0.0;
    for r in 0..REGIONS {
        let z = (sa[r].0 - sb[r].0) / (sa[r].1 + sb[r].1).sqrt();
        assert!(
            z.abs() < 5.0,
            "region {r}: {} vs {} (z = {z:.2})",
            sa[r].0,
            sb[r].0
        );
        chi2 += z * z;
    }
    // Chi-square with 48 degrees of freedom at p = 1e-4 is about 93.
    eprintln!("chi-square over {REGIONS} regions: {chi2:.1}");
    assert!(chi2 < 93.0, "chi-square {chi2:.1} over {REGIONS} regions");
}

// ---------------------------------------------------------------------------------------
// Energy

/// The five Cornell walls plus a front wall: a closed box with inward normals.
fn closed_box(material: &str, light: &str) -> String {
    format!(
        r#"
[materials.wall]
{material}

{light}

[[object]]
shape = "cornell_box"
material = "wall"
spacing = 0.05

[[object]]
shape = "quad"
material = "wall"
size = [2.0, 2.0]
rotate = [0.0, 180.0, 0.0]
translate = [0.0, 0.0, 1.0]
spacing = 0.05

[bake]
max_depth = 64
"#
    )
}

const POINT: &str = "[[light]]\ntype = \"point\"\nposition = [0.1, 0.2, -0.1]\npower = 10.0";

fn check_closed(map: &PhotonMap, what: &str) {
    let s = &map.stats;
    assert_eq!(s.escaped, 0, "{what}: photons left a closed box");
    assert_eq!(s.aborted, 0, "{what}: paths ran out of budget");
    assert_eq!(
        s.escaped + s.absorbed + s.depth_capped,
        s.emitted,
        "{what}: path ends"
    );
    assert_finite(map, what);
    for p in &map.photons {
        let inside = Vec3::from(p.position).abs().max_element() <= 1.0 + 1e-4;
        assert!(inside, "{what}: photon outside the box at {:?}", p.position);
    }
}

#[test]
fn white_box_loses_exactly_the_albedo_per_bounce() {
    let device = common::device();
    let albedo = [0.9, 0.6, 0.3];
    let scene = parse(&closed_box("diffuse = [0.9, 0.6, 0.3]", POINT));
    let cfg = config(&scene, 40_000, StoreRange::All);
    for (what, map) in [
        ("GPU", traced_on(&device, &scene, &cfg)),
        ("CPU", on_cpu(&scene, &cfg)),
    ] {
        check_closed(&map, what);
        // Every emitted photon hits: first-bounce power is the emitted power, to rounding.
        let p0 = power_at(&map, 0);
        for c in 0..3 {
            assert!(
                (p0[c] / 10.0 - 1.0).abs() < 1e-5,
                "{what}: bounce 0 power {p0:?}"
            );
        }
        assert_eq!(count_at(&map, 0) as u64, map.stats.emitted);
        // Each bounce keeps ρ of the power: roulette survives with P_d = mean ρ and scales
        // the survivors by ρ / P_d. Binomial error of the survivor count.
        let pd: f64 = albedo.iter().sum::<f64>() / 3.0;
        for k in 0..5 {
            let (a, b) = (power_at(&map, k), power_at(&map, k + 1));
            let n = count_at(&map, k) as f64;
            for c in 0..3 {
                let ratio = b[c] / a[c];
                let sigma = albedo[c] / pd * (pd * (1.0 - pd) / n).sqrt();
                assert!(
                    (ratio - albedo[c]).abs() < 4.0 * sigma,
                    "{what}: bounce {k}→{}, channel {c}: ratio {ratio:.4}, albedo {} ± {sigma:.4}",
                    k + 1,
                    albedo[c]
                );
            }
        }
    }
}

#[test]
fn glossy_box_never_gains_energy() {
    let device = common::device();
    let scene = parse(&closed_box(
        "diffuse = 0.0\nspecular = 0.8\nroughness = 0.2",
        POINT,
    ));
    let cfg = config(&scene, 40_000, StoreRange::All);
    for (what, map) in [
        ("GPU", traced_on(&device, &scene, &cfg)),
        ("CPU", on_cpu(&scene, &cfg)),
    ] {
        check_closed(&map, what);
        for k in 0..4 {
            let (a, b) = (power_at(&map, k)[0], power_at(&map, k + 1)[0]);
            let n = count_at(&map, k) as f64;
            // Weights are at most 2 / P_s, so the error is at most that over √n.
            let sigma = 2.0 * (0.8 / n).sqrt();
            let ratio = b / a;
            assert!(
                ratio < 0.8 + 4.0 * sigma,
                "{what}: bounce {k}: ratio {ratio:.4} > ρs = 0.8"
            );
            assert!(
                ratio > 0.4,
                "{what}: bounce {k}: ratio {ratio:.4}: glossy light lost"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Lights

/// Point, spot (smooth falloff, weighted photons) and area lights inside a closed box: all
/// their power arrives at the first hit.
#[test]
fn every_light_delivers_its_power() {
    let device = common::device();
    let lights = [
        ("point", POINT.to_string(), false),
        (
            "spot",
            "[[light]]\ntype = \"spot\"\nposition = [0.0, 0.5, 0.0]\ndirection = [0.2, -1.0, 0.1]\n\
             power = [10.0, 5.0, 2.0]\nangle = 40.0\ninner_angle = 15.0"
                .to_string(),
            true,
        ),
        (
            "area",
            "[[light]]\ntype = \"area\"\ncenter = [0.0, 0.9, 0.0]\nsize = [0.5, 0.3]\n\
             normal = [0.0, -1.0, 0.0]\npower = [10.0, 5.0, 2.0]"
                .to_string(),
            false,
        ),
        (
            "two lights",
            format!("{POINT}\n[[light]]\ntype = \"point\"\nposition = [-0.5, 0.0, 0.3]\npower = [0.0, 3.0, 1.0]"),
            false,
        ),
    ];
    for (name, light, weighted) in lights {
        let scene = parse(&closed_box("diffuse = 0.5", &light));
        let total: [f64; 3] =
            [0, 1, 2].map(|c| scene.lights.iter().map(|l| l.power[c] as f64).sum());
        let cfg = config(&scene, 30_000, StoreRange::All);
        for (what, map) in [
            ("GPU", traced_on(&device, &scene, &cfg)),
            ("CPU", on_cpu(&scene, &cfg)),
        ] {
            check_closed(&map, &format!("{name} {what}"));
            let got = power_at(&map, 0);
            for c in 0..3 {
                // Photons of a spot carry falloff-weighted power: the total is right on
                // average, to about 1/√N; the others carry exactly P / N.
                let tol = if weighted {
                    4.0 / (30_000f64).sqrt()
                } else {
                    1e-5
                };
                assert!(
                    (got[c] - total[c]).abs() <= tol * total[c],
                    "{name} {what}, channel {c}: {} arrived of {}",
                    got[c],
                    total[c]
                );
            }
        }
    }
}

/// An area light is an opaque emitter, as the path tracer sees it: a photon that meets its face
/// ends there (absorbed) instead of passing on to the ceiling behind it. In a closed box with
/// the light a millimetre under the ceiling, no photon lands on the ceiling behind the light's
/// middle (more than 0.1 in from its edges), while the rest of the ceiling receives many, on the
/// device and the mirror.
#[test]
fn photons_end_at_the_light_they_meet() {
    let device = common::device();
    let light = "[[light]]\ntype = \"area\"\ncenter = [0.0, 0.999, 0.0]\nsize = [0.6, 0.6]\n\
                 normal = [0.0, -1.0, 0.0]\npower = 10.0";
    let scene = parse(&closed_box("diffuse = 0.8", light));
    let cfg = config(&scene, 40_000, StoreRange::All);
    for (what, map) in [
        ("GPU", traced_on(&device, &scene, &cfg)),
        ("CPU", on_cpu(&scene, &cfg)),
    ] {
        check_closed(&map, what);
        let on_ceiling = |p: &&Photon| p.position[1] > 0.99;
        let behind = |p: &&&Photon| p.position[0].abs() < 0.2 && p.position[2].abs() < 0.2;
        let ceiling: Vec<&Photon> = map.photons.iter().filter(on_ceiling).collect();
        let hidden = ceiling.iter().filter(behind).count();
        assert_eq!(hidden, 0, "{what}: photons behind the light");
        assert!(
            ceiling.len() > 1000,
            "{what}: {} on the ceiling",
            ceiling.len()
        );
    }
}

/// A light that carries a material reflects as Mitsuba's lights do: a photon that meets its
/// face lands on the light's own surface just behind it (stored, and bounced by its material)
/// rather than ending there, and still none reaches the ceiling behind it; on the device and
/// the mirror alike (the light a millimetre under the ceiling, as in
/// `photons_end_at_the_light_they_meet`). The light's surface is the scene's last object
/// ("light 1").
#[test]
fn photons_land_on_a_light_that_reflects() {
    let device = common::device();
    let light = "[[light]]\ntype = \"area\"\ncenter = [0.0, 0.999, 0.0]\nsize = [0.6, 0.6]\n\
                 normal = [0.0, -1.0, 0.0]\npower = 10.0\nmaterial = \"wall\"\nspacing = 0.05";
    let scene = parse(&closed_box("diffuse = 0.8", light));
    let body = scene.surfaces.iter().position(|s| s == "light 1").unwrap() as u32;
    let body_splats: Vec<u32> = (0..scene.splats.len() as u32)
        .filter(|&i| scene.splats[i as usize].object == body)
        .collect();
    assert_eq!(body_splats.len(), 144, "a 0.6 square at spacing 0.05");
    assert!(body_splats.iter().all(|&i| {
        let s = &scene.splats[i as usize];
        s.normal == [0.0, -1.0, 0.0] && s.center[1] > 0.999 && s.center[1] < 0.9996
    }));
    let cfg = config(&scene, 40_000, StoreRange::All);
    for (what, map) in [
        ("GPU", traced_on(&device, &scene, &cfg)),
        ("CPU", on_cpu(&scene, &cfg)),
    ] {
        check_closed(&map, what);
        let on_body = map
            .photons
            .iter()
            .filter(|p| scene.splats[p.splat as usize].object == body)
            .count();
        let behind = map
            .photons
            .iter()
            .filter(|p| p.position[1] > 0.9998)
            .filter(|p| p.position[0].abs() < 0.2 && p.position[2].abs() < 0.2)
            .count();
        assert!(
            on_body > 100,
            "{what}: {on_body} photons on the light's surface"
        );
        assert_eq!(behind, 0, "{what}: photons behind the light");
    }
}

/// Replaces the scene's splats by one disk at the origin facing up, its light's target: its
/// area is exact where a quad of splats overhangs its edges by about a splat radius. Its radius.
fn one_disk(scene: &mut Scene) -> f32 {
    let radius = 0.9f32;
    scene.splats = vec![lobelight::types::Splat {
        center: [0.0; 3],
        radius,
        normal: [0.0, 1.0, 0.0],
        ..scene.splats[0]
    }];
    radius
}

/// A directional light emits from a disk covering the scene: a target of area A receives
/// E·A, up to the binomial error of how many photons hit it. The target is one disk, whose
/// area is exact (a quad of splats overhangs its edges by about a splat radius).
#[test]
fn directional_light_delivers_irradiance_times_area() {
    let device = common::device();
    let mut scene = parse(
        r#"
[[light]]
type = "directional"
direction = [0.0, -1.0, 0.0]
irradiance = 2.0

[[object]]
shape = "quad"
size = [2.0, 2.0]
rotate = [-90.0, 0.0, 0.0]
spacing = 0.5
"#,
    );
    // The light's disk covers the quad's bounds, so also this disk inside them.
    let radius = one_disk(&mut scene);
    let n = 30_000u64;
    let cfg = config(&scene, n, StoreRange::All);
    let disk_area = scene.lights[0].area as f64;
    let target = std::f64::consts::PI * (radius as f64).powi(2);
    let hit_fraction = target / disk_area;
    for (what, map) in [
        ("GPU", traced_on(&device, &scene, &cfg)),
        ("CPU", on_cpu(&scene, &cfg)),
    ] {
        assert_finite(&map, what);
        let got = power_at(&map, 0)[0];
        let expected = 2.0 * target;
        let sigma = 2.0 * disk_area * (hit_fraction * (1.0 - hit_fraction) / n as f64).sqrt();
        assert!(
            (got - expected).abs() < 4.0 * sigma,
            "{what}: {got} arrived, E·A = {expected} ± {sigma:.3}"
        );
        assert!(
            map.stats.escaped > 0,
            "{what}: the light's disk should overhang the target"
        );
    }
}

/// A constant sky of radiance L over an open disk facing up: the photons that land on it
/// carry E·A with E = π L, the irradiance of the upper hemisphere (the disk is one-sided, so
/// the lower one's photons pass it). Their powers vary (radiance over the map's pdf), so the
/// bound is 4 σ of the sample itself.
#[test]
fn a_constant_sky_delivers_pi_l_on_an_open_disk() {
    let device = common::device();
    let radiance = 0.8f64;
    let mut scene = parse(&format!(
        r#"
[[light]]
type = "environment"
radiance = {radiance}

[[object]]
shape = "quad"
size = [2.0, 2.0]
rotate = [-90.0, 0.0, 0.0]
spacing = 0.5
"#
    ));
    let radius = one_disk(&mut scene);
    let n = 40_000u64;
    let cfg = config(&scene, n, StoreRange::All);
    let target = std::f64::consts::PI * (radius as f64).powi(2);
    let expected = std::f64::consts::PI * radiance * target;
    for (what, map) in [
        ("GPU", traced_on(&device, &scene, &cfg)),
        ("CPU", on_cpu(&scene, &cfg)),
    ] {
        assert_finite(&map, what);
        let landed: Vec<f64> = map
            .photons
            .iter()
            .filter(|p| p.bounce == 0)
            .map(|p| p.power[1] as f64)
            .collect();
        let got: f64 = landed.iter().sum();
        // The sum over n emitted photons, each landing or not: σ² = n E[x²] − (Σ x)² / n.
        let square: f64 = landed.iter().map(|x| x * x).sum();
        let sigma = (square - got * got / n as f64).max(0.0).sqrt();
        eprintln!("{what}: {got:.4} arrived, π L A = {expected:.4} ± {sigma:.4}");
        assert!(
            landed.len() > 1000,
            "{what}: {} photons landed",
            landed.len()
        );
        assert!(
            (got - expected).abs() < 4.0 * sigma,
            "{what}: {got} arrived, π L A = {expected} ± {sigma:.4}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Store

/// A store far too small to start with, small batches and pages capped at 5,000 photons: the
/// batches rerun after growing, new pages start, batches halve, and the photons are exactly
/// those of a run with room to spare.
#[test]
fn overflow_grows_the_store_and_loses_nothing() {
    let device = common::device();
    let scene = cornell();
    let roomy = config(&scene, 20_000, StoreRange::All);
    let tight = PhotonConfig {
        initial_capacity: 64,
        batch: 4096,
        page_limit: 5000,
        ..roomy.clone()
    };
    let reference = traced_on(&device, &scene, &roomy);
    let squeezed = traced_on(&device, &scene, &tight);
    let s = &squeezed.stats;
    eprintln!(
        "tight store: {} batches, {} reruns, {} pages",
        s.batches, s.reruns, s.pages
    );
    assert!(
        s.reruns > 0 && s.pages > 1,
        "the tight store should have overflowed: {s:?}"
    );
    assert!(s.batches > 5, "batches should have halved: {s:?}");
    assert_eq!(
        squeezed.photons, reference.photons,
        "GPU: photons differ after growth"
    );
    assert_eq!(squeezed.stats.stored, reference.stats.stored);
    let cpu_ref = on_cpu(&scene, &roomy);
    let cpu_tight = on_cpu(
        &scene,
        &PhotonConfig {
            page_limit: 0,
            ..tight
        },
    );
    assert!(cpu_tight.stats.reruns > 0);
    assert_eq!(
        cpu_tight.photons, cpu_ref.photons,
        "CPU: photons differ after growth"
    );
}

#[test]
fn same_seed_same_photons() {
    let device = common::device();
    let scene = cornell();
    let cfg = config(&scene, 30_000, StoreRange::Indirect);
    let a = traced_on(&device, &scene, &cfg);
    let b = traced_on(&device, &scene, &cfg);
    assert_eq!(a.photons, b.photons, "two GPU runs differ");
    let c = on_cpu(&scene, &cfg);
    let d = on_cpu(&scene, &cfg);
    assert_eq!(c.photons, d.photons, "two CPU runs differ");
    let other = on_cpu(&scene, &PhotonConfig { seed: 9, ..cfg });
    assert_ne!(c.photons, other.photons, "the seed should matter");
}
