//! Photon deposits (design §6, "Deposits"): `deposit_add`, `deposit_list` and `deposit_share` on
//! the device against their mirrors, the deposits' sums against the photons', and the shared
//! irradiance against the photons' own estimate and the exact irradiance of a flat field.

mod common;

use std::path::Path;

use glam::Vec3;
use lobelight::bake::{self, Progress, on_device};
use lobelight::bins::DepositBins;
use lobelight::bins::bin_params;
use lobelight::cpu::{self, CpuExecutor};
use lobelight::em::{EmConfig, FitShape, deposit_params};
use lobelight::fit_groups::CoverGroups;
use lobelight::gpu::bins::GpuDeposits;
use lobelight::gpu::exec::GpuExecutor;
use lobelight::gpu::scene::GpuScene;
use lobelight::grid::{GridConfig, grid_params};
use lobelight::host::FitFrom;
use lobelight::photons::PhotonMap;
use lobelight::plan::BakePlan;
use lobelight::renderer::{Engine, Renderer};
use lobelight::sequence::{CoverInput, Executor, SharedDeposits, share_light};
use lobelight::shared::deposits::{DEPOSIT_POSITION_UNITS, disk_share};
use lobelight::types::{EmParams, Photon, Splat, SplatLight};

use common::Rng;

/// The default scene with `photons` traced on the mirror.
fn cornell(
    photons: u64,
) -> (
    lobelight::scene::Scene,
    lobelight::grid::SplatGrid,
    PhotonMap,
) {
    let mut scene = lobelight::scene::load(Path::new("scenes/cornell.toml")).unwrap();
    scene.bake.photons = photons;
    scene.bake.gather = 8;
    // The shared estimate as deposit_share and estimate_coverage give it (tests/estimate_smooth.rs
    // holds the smoothing after them to its own parity).
    scene.bake.smooth = 0.0;
    let cfg = lobelight::photons::PhotonConfig::from_scene(&scene);
    let (map, grid) = common::mirror_photons(&scene, &cfg);
    (scene, grid, map)
}

/// The device's deposits of the same photons are the mirror's: the same records in the same lists
/// (integer sums, so the order the photons arrive in changes nothing), the same power (to a
/// division's rounding) and spread (a photon's fixed-point offset a step apart where the device's
/// division rounds it across one); split over buffers by splat ranges (as on a device whose storage
/// bindings do not hold them all), they are the same records again, and the same spreads within
/// 1e-5. The irradiance `deposit_share` gives every splat (with `estimate_coverage`'s share) agrees
/// within 1e-5 on all but 1 % of the lit splats (measured: 125 of 34 k at 400 k photons; 643 at 100
/// k), and summed over them within 1e-5: a deposit's mean differs in its last bits (the device may
/// fuse a multiply and an add), and a deposit of one photon, a point, lying on the rim of a gather
/// disk counts on one side and not on the other.
#[test]
fn deposits_and_shared_light_on_the_device_equal_the_mirror() {
    let device = common::device();
    let gpu = device.gpu().unwrap();
    let (scene, grid, map) = cornell(400_000);
    let params = deposit_params(
        &scene.lights,
        scene.bake.photons,
        &scene.splats,
        scene.search_radius(),
    )
    .unwrap();
    let on = (&scene.splats[..], &grid.params);
    let on_cpu = Engine::Mirror
        .deposit_photons(&params, &[&map.photons], on)
        .unwrap();
    let on_gpu = device
        .deposit_photons(&params, &[&map.photons], on)
        .unwrap();
    // Deposits split over buffers of 8,738 splats each (512 KiB pages), 5 ranges.
    let paged = Engine::Device(std::sync::Arc::new(
        common::gpu().with_page_bytes(512 << 10),
    ));
    assert_eq!(paged.bake_limits().deposit_range, 8_738);
    let split = paged.deposit_photons(&params, &[&map.photons], on).unwrap();
    assert_eq!(
        split.params, on_gpu.params,
        "deposits split by splat ranges"
    );
    assert!(
        split.bins == on_gpu.bins,
        "split deposits: the records differ"
    );
    // The spreads are the same formula (a square root of a difference of means) compiled into
    // the split and the whole pipelines, which a device may round apart (an H100 measured
    // 5.6e-6 at worst; lavapipe bit for bit).
    let flat = |v: &[[f32; 2]]| v.iter().flatten().copied().collect::<Vec<f32>>();
    let (a, b) = (flat(&split.spread), flat(&on_gpu.spread));
    let spread_apart = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| (*x - *y).abs() > 1e-5 * y.abs().max(1e-3))
        .count();
    assert_eq!(
        spread_apart,
        0,
        "split deposits' spreads: {}",
        common::apart(&a, &b)
    );
    assert!(on_cpu.bins.len() > 10_000, "{} deposits", on_cpu.bins.len());
    assert_eq!(on_gpu.bins.cell_start, on_cpu.bins.cell_start);
    assert_eq!(on_gpu.bins.keys, on_cpu.bins.keys);
    // A photon's offset from its splat's centre is summed in fixed point (DEPOSIT_POSITION_UNITS
    // steps a radius), and a device whose division rounds apart from the mirror's can put an
    // offset on the other side of a step (an H100 did, for one photon of 400 k): such a
    // deposit's mean may move by a step in each axis, and its spread with it.
    let mut stepped = std::collections::HashSet::new();
    for k in 0..on_cpu.bins.len() {
        let (a, b) = (&on_cpu.bins, &on_gpu.bins);
        let (pa, pb) = (
            Vec3::from(a.geom[k].position),
            Vec3::from(b.geom[k].position),
        );
        let splat = a.keys[k][0];
        let step = scene.splats[splat as usize].radius / DEPOSIT_POSITION_UNITS;
        if (pa - pb).length() > 1e-6 {
            stepped.insert(splat);
        }
        assert!(
            (pa - pb).length() <= 1e-6 + 2.0 * step,
            "deposit {k}: {pa} vs {pb}"
        );
        // The same integer sum over the same scale: a device's division may round 2.5 ulps off
        // (Vulkan's bound; an H100's was 1 ulp off where lavapipe's is exact).
        let ulps = |x: f32, y: f32| (x - y).abs() <= 3.0 * f32::EPSILON * x.abs().max(y.abs());
        let (ea, eb) = (a.power[k], b.power[k]);
        assert!(
            ea.iter().zip(&eb).all(|(x, y)| ulps(*x, *y)),
            "deposit {k}: power {ea:?} vs {eb:?}"
        );
    }
    assert!(
        stepped.len() * 1000 <= on_cpu.bins.len(),
        "{} stepped",
        stepped.len()
    );
    for (j, (a, b)) in on_cpu.spread.iter().zip(&on_gpu.spread).enumerate() {
        // rho^2 = 2 r^2 (E|o|^2 - |mean|^2) from fixed-point sums (DEPOSIT_POSITION_UNITS steps
        // a radius, and a squared radius), and a device may round an offset or its square
        // across a step: E|o|^2 - |mean|^2 then moves by at most 5 steps (|mean| <= 2), rho^2
        // by 10 r^2 / units, and rho by the least of sqrt of that and that over 2 rho (an H100:
        // 4.8e-7 at rho 0.011, where that bound is 9.5e-6).
        let r = scene.splats[j].radius;
        let moved = 10.0 * r * r / DEPOSIT_POSITION_UNITS;
        let step = moved.sqrt().min(moved / (2.0 * a[0].max(1e-12)));
        let tolerance = 1e-5 * a[0].max(1e-3) + step;
        assert!(
            (a[0] - b[0]).abs() <= tolerance,
            "splat {j}: {a:?} vs {b:?}"
        );
        assert_eq!(a[1], b[1], "splat {j}: count");
    }

    let plan = BakePlan::new(&scene, gpu.bake_limits()).unwrap();
    let (cfg, setup) = (plan.em.clone(), plan.gather_setup(&scene));
    assert!(cfg.uses_deposits());
    let quiet = Progress::new(false);
    let on_gpu_scene = GpuScene::upload(gpu, &scene).unwrap();
    let deposits = GpuDeposits::upload(gpu, &on_gpu).unwrap();
    let lit_gpu = on_device(&scene, gpu, &on_gpu_scene, |ex, on| {
        let input = (&deposits.bins, Some(&deposits));
        bake::fit(ex, &scene, &plan, on, input, &quiet).map(|(lobes, _)| lobes)
    })
    .unwrap();
    let shape = plan.limits.fit_shape;
    let mirror = Renderer::new(std::sync::Arc::new(scene.clone()), &Engine::Mirror).unwrap();
    let lit_cpu = mirror
        .fit_lobes(&cfg, FitFrom::deposits(&on_cpu), shape, Some(&setup))
        .unwrap();
    let (mut lit, mut apart, mut sums) = (0, 0, [0.0f64; 2]);
    for i in 0..scene.splats.len() {
        let m = scene.materials[scene.splats[i].material as usize];
        if m.is_glossy() {
            continue;
        }
        let (a, b) = (&lit_cpu.light[i], &lit_gpu.light[i]);
        let (ea, eb) = (Vec3::from(a.irradiance), Vec3::from(b.irradiance));
        let rel = (ea - eb).abs().max_element() / ea.max_element().max(1e-6);
        apart += usize::from(rel > 1e-5);
        sums[0] += ea.x as f64;
        sums[1] += eb.x as f64;
        lit += usize::from(a.photons > 0);
    }
    assert!(lit > 30_000, "{lit} diffuse splats lit");
    eprintln!("{apart} of {lit} lit diffuse splats further apart than 1e-5");
    assert!(
        apart * 100 <= lit,
        "{apart} of {lit} splats further apart than 1e-5"
    );
    assert!((sums[0] / sums[1] - 1.0).abs() < 1e-5, "{sums:?}");
}

/// Each splat's light from the deposits, summed once a coverage group at its leader and copied
/// to the members (`deposit_share`'s two passes), in groups of 2 R (many splats each on the default
/// box, whose splats lie farther apart than the bake's R/16): on the mirror every member's
/// light is its leader's own sum, bit for bit, and the splats lit and not fitted are counted
/// member by member; the device's agrees within 1e-5 on all but 1 % of the lit splats, as the
/// ungrouped sums do (measured: 116 of 34 k at 400 k photons).
#[test]
fn shared_light_once_a_group_on_the_device_equals_the_mirror() {
    let gpu = common::gpu();
    let (scene, grid, map) = cornell(400_000);
    let r = scene.search_radius();
    let params = deposit_params(&scene.lights, scene.bake.photons, &scene.splats, r).unwrap();
    let on = (&scene.splats[..], &grid.params);
    let d = Engine::Mirror
        .deposit_photons(&params, &[&map.photons], on)
        .unwrap();
    let n = scene.splats.len() as u32;
    let em = EmConfig::from_scene(&scene).params(n, n, FitShape::default());
    let coarse = CoverGroups::new(&scene.splats, 32.0 * r, None).unwrap();
    assert!(coarse.groups * 4 < n, "{} groups", coarse.groups);
    fn run<E: Executor>(
        ex: &mut E,
        (scene, d, em): (&lobelight::scene::Scene, &DepositBins, &EmParams),
        cover: Option<&CoverGroups>,
    ) -> (Vec<SplatLight>, u32) {
        let deposit_params = ex.uniform("deposit params", &d.params).unwrap();
        let bin_params = ex.uniform("bin params", &d.bins.params).unwrap();
        let splats = ex.upload("splats", &scene.splats).unwrap();
        let materials = ex.upload("materials", &scene.materials).unwrap();
        let cell_start = ex.upload("cell start", &d.bins.cell_start).unwrap();
        let keys = ex.upload("keys", &d.bins.keys).unwrap();
        let geom = ex.upload("geom", &d.bins.geom).unwrap();
        let power = ex.upload("power", &d.bins.power).unwrap();
        let spread = ex.upload("spread", &d.spread).unwrap();
        let deposits = SharedDeposits {
            deposit_params: &deposit_params,
            bin_params: &bin_params,
            splats: &splats,
            materials: &materials,
            cell_start: &cell_start,
            keys: &keys,
            geom: &geom,
            power: &power,
            spread: &spread,
        };
        let light = ex.zeroed("light", scene.splats.len() as u64 * 32).unwrap();
        let counters = ex.zeroed("counters", 16).unwrap();
        let words = cover.map(|c| ex.upload("cover", &c.words).unwrap());
        let input = cover.zip(words.as_ref()).map(|(c, words)| CoverInput {
            words,
            groups: c.groups,
        });
        share_light(ex, em, &deposits, (&light, &counters), input.as_ref()).unwrap();
        let lit = ex.read::<u32>(&counters, 4).unwrap()[3];
        (ex.read(&light, scene.splats.len()).unwrap(), lit)
    }
    let input = (&scene, &d, &em);
    let (own, _) = run(&mut CpuExecutor::default(), input, None);
    let (grouped, lit) = run(&mut CpuExecutor::default(), input, Some(&coarse));
    let leaders = &coarse.words[n as usize..];
    for i in 0..n as usize {
        let leader = leaders[coarse.words[i] as usize] as usize;
        assert_eq!(grouped[i], own[leader], "splat {i}, led by {leader}");
    }
    let diffuse_lit = (0..n as usize)
        .filter(|&i| {
            let m = scene.materials[scene.splats[i].material as usize];
            grouped[i].photons > 0 && !m.is_glossy()
        })
        .count();
    assert_eq!(
        lit as usize, diffuse_lit,
        "the lit splats counted member by member"
    );
    let on_gpu = {
        let mut encoder = gpu.encoder("shared light");
        let mut ex = GpuExecutor::new(&gpu, &mut encoder);
        run(&mut ex, input, Some(&coarse))
    };
    assert_eq!(on_gpu.1, lit, "lit splats counted on the device");
    let apart = grouped
        .iter()
        .zip(&on_gpu.0)
        .filter(|(a, b)| {
            let (ea, eb) = (Vec3::from(a.irradiance), Vec3::from(b.irradiance));
            (ea - eb).abs().max_element() > 1e-5 * ea.max_element().max(1e-6)
        })
        .count();
    eprintln!("{apart} of {lit} lit splats further apart than 1e-5");
    assert!(apart * 100 <= lit as usize, "{apart} of {lit} splats apart");
}

/// A deposit keeps every photon that landed on its splat: the counts and the power summed over
/// the deposits are the photons' (the power within the fixed point's rounding, 1e-6).
#[test]
fn deposits_keep_every_photon() {
    let (scene, grid, map) = cornell(40_000);
    let params =
        deposit_params(&scene.lights, 40_000, &scene.splats, scene.search_radius()).unwrap();
    let on = (&scene.splats[..], &grid.params);
    let d = Engine::Mirror
        .deposit_photons(&params, &[&map.photons], on)
        .unwrap();
    let count: f64 = d.spread.iter().map(|s| s[1] as f64).sum();
    assert_eq!(count as usize, map.photons.len());
    let sum = |p: &mut dyn Iterator<Item = [f32; 3]>| {
        p.fold([0.0f64; 3], |a, b| {
            [a[0] + b[0] as f64, a[1] + b[1] as f64, a[2] + b[2] as f64]
        })
    };
    let deposited = sum(&mut d.bins.power.iter().map(|p| [p[0], p[1], p[2]]));
    let photons = sum(&mut map.photons.iter().map(|p| p.power));
    for c in 0..3 {
        assert!(
            (deposited[c] / photons[c] - 1.0).abs() < 1e-6,
            "channel {c}: {} against {}",
            deposited[c],
            photons[c]
        );
    }
}

/// `disk_share` is the share of a uniform disk inside a circle: against 400 k points drawn in
/// the disk, within 0.005 at every tested distance and radius (inside, across the rim, a disk
/// larger than the circle, a point).
#[test]
fn disk_share_is_the_share_of_a_uniform_disk() {
    let mut rng = Rng(7);
    let r = 2.0;
    for (l, rho) in [
        (0.5, 0.7),
        (1.6, 0.7),
        (2.0, 0.7),
        (2.5, 0.7),
        (0.3, 3.0),
        (1.0, 2.5),
        (1.9, 0.0),
    ] {
        let n = 400_000;
        let mut inside = 0;
        for _ in 0..n {
            let (a, b) = (rng.f32(), rng.f32());
            let q = rho * a.sqrt();
            let phi = std::f32::consts::TAU * b;
            let (x, y) = (l + q * phi.cos(), q * phi.sin());
            inside += usize::from(x * x + y * y <= r * r);
        }
        let expected = inside as f32 / n as f32;
        let share = disk_share(l, r, rho);
        assert!(
            (share - expected).abs() < 0.005,
            "l {l}, rho {rho}: {share} against {expected}"
        );
    }
}

/// A flat field: photons of equal power fall uniformly on a plane of splats (each on the first
/// splat whose disk holds it, as a ray's tie between coplanar disks goes). Away from the edges, the
/// irradiance `deposit_share` gives the splats is the photons' own estimate (`estimate_gather`)
/// within 0.5 % on the mean (measured +0.21 %: a splat's photons cover what its disk captures,
/// which is no disk where disks overlap) and the field's exact irradiance within 1 % (+0.32 %), and
/// no splat is further than 10 % from the photons' estimate. Counting a deposit whole where its
/// mean lies within R instead puts splats 14 % off (the lattice points within a circle).
#[test]
fn shared_light_of_a_flat_field_is_the_photons_estimate() {
    let side = 48usize;
    let spacing = 1.0f32;
    let radius = spacing * std::f32::consts::FRAC_1_SQRT_2 * 1.01;
    let mut splats = Vec::new();
    for y in 0..side {
        for x in 0..side {
            splats.push(Splat {
                center: [x as f32 * spacing, y as f32 * spacing, 0.0],
                radius,
                normal: [0.0, 0.0, 1.0],
                material: 0,
                diffuse: [0.5; 3],
                object: 0,
            });
        }
    }
    let extent = (side - 1) as f32 * spacing;
    let count = 300_000u32;
    let mut rng = Rng(3);
    let mut photons = Vec::with_capacity(count as usize);
    for path in 0..count {
        let p = Vec3::new(rng.range(0.0, extent), rng.range(0.0, extent), 0.0);
        let near = |c: [f32; 3]| (Vec3::from(c) - p).length() <= radius;
        let Some(splat) = splats.iter().position(|s| near(s.center)) else {
            continue;
        };
        photons.push(Photon {
            position: p.into(),
            bounce: 1,
            direction: [0.0, 0.0, 1.0],
            splat: splat as u32,
            power: [1.0; 3],
            path,
        });
    }
    let field = photons.len() as f32 / (extent * extent);
    let r = 2.02 * spacing;
    let em = EmConfig {
        radius: r,
        ..test_config()
    };
    let n = splats.len() as u32;
    let params = em.params(n, n, FitShape::default());
    let grid = grid_params(&splats, &GridConfig::default()).unwrap();
    let deposit = lobelight::types::DepositParams {
        power_scale: lobelight::em::DEPOSIT_POWER_UNITS,
        photon_count: 0,
        splat_count: n,
        reach: r + lobelight::em::DEPOSIT_REACH * radius,
        spread_max: lobelight::em::DEPOSIT_REACH * radius,
        ..Default::default()
    };
    let d: DepositBins = Engine::Mirror
        .deposit_photons(&deposit, &[&photons], (&splats, &grid))
        .unwrap();
    let mut shared = vec![SplatLight::default(); splats.len()];
    let binned = cpu::deposit_share::BinnedDeposits {
        cell_start: &d.bins.cell_start,
        keys: &d.bins.keys,
        geom: &d.bins.geom,
        power: &d.bins.power,
        spread: &d.spread,
    };
    let groups = n.div_ceil(cpu::deposit_share::WG);
    let mut counters = [0; 4];
    let matte = [lobelight::types::Material::default()];
    // Each splat its own group and leader: the sum, then the copy that counts.
    let cover: Vec<u32> = (0..n).chain(0..n).collect();
    let on = (&mut shared[..], &cover[..]);
    cpu::deposit_share::deposit_share(
        &params,
        &d.params,
        &d.bins.params,
        &splats,
        &binned,
        on,
        groups,
    );
    let on = (&mut shared[..], &cover[..]);
    cpu::deposit_share::copy(&params, (&splats, &matte), on, &mut counters, groups);
    assert_eq!(counters[3], n, "every splat of the field is lit");

    let bins = Engine::Mirror
        .bin_photons(
            &bin_params(&grid, r, photons.len() as u64).unwrap(),
            &[&photons],
            &splats,
        )
        .unwrap();
    let margin = r + 2.0 * spacing;
    let interior: Vec<u32> = (0..n)
        .filter(|&i| {
            let c = splats[i as usize].center;
            [c[0], c[1]]
                .iter()
                .all(|&v| v >= margin && v <= extent - margin)
        })
        .collect();
    let mut gathered = vec![SplatLight::default(); splats.len()];
    let gather_params = em.params(n, interior.len() as u32, FitShape::default());
    cpu::estimate_gather::estimate_gather(
        &gather_params,
        &bins.params,
        &splats,
        &interior,
        &bins.cell_start,
        &bins.geom,
        &bins.power,
        &mut gathered,
        (interior.len() as u32).div_ceil(cpu::estimate_gather::WG),
    );
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for &i in &interior {
        let (s, g) = (
            shared[i as usize].irradiance[0],
            gathered[i as usize].irradiance[0],
        );
        assert!(
            (s / g - 1.0).abs() < 0.1,
            "splat {i}: shared {s}, photons' {g}"
        );
        a += s as f64;
        b += g as f64;
    }
    let k = interior.len() as f64;
    let (shared_mean, photons_mean) = (a / k, b / k);
    eprintln!(
        "{} interior splats: shared {shared_mean:.4}, photons' {photons_mean:.4}, field {field:.4}",
        interior.len()
    );
    assert!(interior.len() > 1000);
    assert!((shared_mean / photons_mean - 1.0).abs() < 0.005);
    assert!((shared_mean / field as f64 - 1.0).abs() < 0.01);
}

fn test_config() -> EmConfig {
    EmConfig {
        lobes: 1,
        iterations: 1,
        family: lobelight::em::LobeFamily::Vmf,
        sparse: false,
        priors: true,
        fit_all: false,
        prune: false,
        radius: 1.0,
        slab: 2.0,
        fit_candidates: 0,
        gather: 8,
        estimate: lobelight::em::Estimate::Deposits,
        share: 0.0,
        smooth: 0.0,
    }
}
