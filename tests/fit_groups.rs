//! Shared fits (`fit_groups`): which splats share a fit, the device's shared fit against the
//! mirror's, and the light the shared fits give against each splat's own.

mod common;

use std::path::Path;

use glam::Vec3;

use lobelight::bake::{self, BakeDevice, Progress, bake, on_device, on_mirror};
use lobelight::em::LobeMap;
use lobelight::fit_groups::{CoverGroups, FOLLOWER_BIT, FitGroups, GROUP_COS_MIN};
use lobelight::gpu::bins::GpuBins;
use lobelight::gpu::scene::GpuScene;
use lobelight::plan::BakePlan;
use lobelight::scene::{self, Scene};
use lobelight::types::{Material, Splat};

fn cornell(photons: u64) -> Scene {
    let mut scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    scene.bake.photons = photons;
    scene
}

fn glossy(scene: &Scene, i: usize) -> bool {
    let m = &scene.materials[scene.splats[i].material as usize];
    m.is_glossy()
}

/// The grey irradiance of a splat's lobes.
fn lobe_light(map: &LobeMap, i: usize) -> f32 {
    map.splat_lobes(i)
        .iter()
        .map(|l| (l.irradiance[0] + l.irradiance[1] + l.irradiance[2]) / 3.0)
        .sum()
}

/// The default scene's groups: every glossy splat in exactly one group, led by the first in
/// its members' list, all in the leader's cell and facing within `GROUP_COS_MIN` of it; no
/// diffuse splat in any. The cell of one search radius puts about four of the block's
/// splats (spacing half a radius) in a group.
#[test]
fn groups_hold_near_splats_that_face_alike() {
    let scene = cornell(1000);
    let plan = BakePlan::new(&scene, lobelight::plan::BakeLimits::host()).unwrap();
    let cell = plan.em.share * plan.em.radius;
    let g = plan.groups.as_ref().expect("shared fits by default");
    let n = scene.splats.len();
    let glossy_count = (0..n).filter(|&i| glossy(&scene, i)).count();
    assert_eq!(g.groups as usize + g.followers as usize, glossy_count);
    assert!(
        g.groups as usize * 3 < glossy_count,
        "{} groups of {glossy_count} glossy splats",
        g.groups
    );
    let starts = &g.words[g.starts_at() as usize..g.members_at() as usize];
    let members = &g.words[g.members_at() as usize..];
    assert_eq!(members.len(), glossy_count);
    let cell_of = |i: usize| (Vec3::from(scene.splats[i].center) / cell).floor();
    let mut seen = vec![false; n];
    for k in 0..g.groups as usize {
        let group = &members[starts[k] as usize..starts[k + 1] as usize];
        let leader = group[0] as usize;
        assert_eq!(g.words[leader], k as u32, "group {k}'s leader");
        for &m in group {
            let m = m as usize;
            assert!(glossy(&scene, m) && !seen[m], "splat {m} twice, or diffuse");
            seen[m] = true;
            assert_eq!(
                cell_of(m),
                cell_of(leader),
                "splat {m} outside its leader's cell"
            );
            let (a, b) = (scene.splats[m].normal, scene.splats[leader].normal);
            assert!(Vec3::from(a).dot(Vec3::from(b)) >= GROUP_COS_MIN);
            if m != leader {
                assert_eq!(g.words[m], FOLLOWER_BIT | leader as u32);
                assert_eq!(g.leader(m), Some(leader));
            }
        }
    }
    assert!((0..n).all(|i| seen[i] == glossy(&scene, i)));
}

/// With shared fits, the coverage groups (`deposit_share`, `estimate_coverage` and
/// `estimate_smooth` sum, measure and choose once one) are made of the splats no fit serves, and
/// each follower joins its fit leader's: no group is led by a follower, so the measures follow the
/// fits and the diffuse splats, not every glossy splat.
#[test]
fn followers_join_their_leaders_coverage_group() {
    let scene = cornell(1000);
    let plan = BakePlan::new(&scene, lobelight::plan::BakeLimits::host()).unwrap();
    let fits = plan.groups.as_ref().expect("shared fits by default");
    let n = scene.splats.len();
    let alone = CoverGroups::new(&scene.splats, plan.em.radius, None).unwrap();
    let cover = CoverGroups::new(&scene.splats, plan.em.radius, Some(fits)).unwrap();
    assert_eq!(cover.splats as usize, n);
    let leaders = &cover.words[n..];
    assert_eq!(leaders.len(), cover.groups as usize);
    for (g, &l) in leaders.iter().enumerate() {
        assert_eq!(fits.leader(l as usize), None, "group {g} led by a follower");
        assert_eq!(cover.words[l as usize], g as u32);
    }
    for i in 0..n {
        let led = cover.words[i] as usize;
        assert!(led < leaders.len(), "splat {i} in no group");
        if let Some(l) = fits.leader(i) {
            assert_eq!(
                cover.words[i], cover.words[l],
                "follower {i} apart from its leader"
            );
        }
    }
    // The box's glossy block: its followers' measures are the ones saved.
    assert!(cover.groups as usize <= n - fits.followers as usize);
    assert!(
        cover.groups < alone.groups,
        "{} groups with fits, {} without",
        cover.groups,
        alone.groups
    );
}

/// Two splats at one point that face apart, and one just across a cell's face, each lead their
/// own group; one facing the first within the cone joins it. Bad cells are errors.
#[test]
fn splats_that_face_apart_or_lie_apart_do_not_share() {
    let splat = |c: [f32; 3], n: [f32; 3]| Splat {
        center: c,
        normal: n,
        radius: 0.01,
        ..Default::default()
    };
    let materials = [Material {
        specular: [0.3; 3],
        ..Default::default()
    }];
    let tilted = Vec3::new(0.3, 0.0, 1.0).normalize().to_array();
    let splats = [
        splat([0.5, 0.5, 0.5], [0.0, 0.0, 1.0]),
        splat([0.5, 0.5, 0.5], [0.0, 0.0, -1.0]),
        splat([1.01, 0.5, 0.5], [0.0, 0.0, 1.0]),
        splat([0.6, 0.6, 0.5], tilted),
    ];
    let g = FitGroups::new(&splats, &materials, false, 1.0).unwrap();
    assert_eq!((g.groups, g.followers), (3, 1));
    assert_eq!(g.leader(3), Some(0));
    assert_eq!([g.leader(0), g.leader(1), g.leader(2)], [None; 3]);
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert!(FitGroups::new(&splats, &materials, false, bad).is_err());
    }
}

/// A cell whose normals fan over 40° makes one group, led by the splat in the fan's middle,
/// whichever splat comes first: led by the first in splat order (the fan's edge), the far
/// side's splats, 30° and 40° from it, would lead a second group.
#[test]
fn a_curved_cell_is_led_from_its_middle() {
    let materials = [Material {
        specular: [0.3; 3],
        ..Default::default()
    }];
    let fan: Vec<Splat> = [20.0f32, 10.0, 0.0, -10.0, -20.0]
        .iter()
        .enumerate()
        .map(|(k, deg)| {
            let (sin, cos) = deg.to_radians().sin_cos();
            Splat {
                center: [0.1 + 0.1 * k as f32, 0.5, 0.5],
                normal: [sin, 0.0, cos],
                radius: 0.01,
                ..Default::default()
            }
        })
        .collect();
    let g = FitGroups::new(&fan, &materials, false, 1.0).unwrap();
    assert_eq!((g.groups, g.followers), (1, 4));
    assert_eq!(g.words[2], 0, "the middle splat leads group 0");
    for i in [0, 1, 3, 4] {
        assert_eq!(g.leader(i), Some(2), "splat {i}");
    }
    let members = &g.words[g.members_at() as usize..];
    assert_eq!(
        members,
        [2, 0, 1, 3, 4],
        "the leader first, then the rest in splat order"
    );
}

/// The shared fit on the device against the mirror's, from the same bins: the same leaders
/// fitted, each follower served its leader's lobes on both, and the glossy splats' light
/// within the final-gathering tolerances (99 % of splats within 1e-3 where the device rounds
/// as the mirror does, 90 % elsewhere; the means within 1e-3).
#[test]
fn shared_fits_match_the_mirror() {
    let gpu = common::gpu();
    let mut scene = cornell(100_000);
    scene.bake.gather = 8;
    let grid = common::host_grid(&scene);
    let plan = BakePlan::new(&scene, gpu.bake_limits()).unwrap();
    let quiet = Progress::new(false);
    // The mirror's photons binned, fitted there, and read back for the device's fit.
    let (on_cpu, bins) = on_mirror(&scene, &grid, |ex, on| {
        let traced = bake::trace(ex, &plan, on, &quiet)?;
        let binned = bake::bin_traced(ex, &plan, on, &traced, &quiet)?;
        let lobes = bake::fit(ex, &scene, &plan, on, (&binned.bins, None), &quiet)?.0;
        Ok((lobes, binned.bins.read_back(ex)?))
    })
    .unwrap();
    let on_gpu = {
        let on_gpu = GpuScene::upload(&gpu, &scene).unwrap();
        let uploaded = GpuBins::upload(&gpu, &bins).unwrap();
        on_device(&scene, &gpu, &on_gpu, |ex, on| {
            bake::fit(ex, &scene, &plan, on, (&uploaded, None), &quiet).map(|(lobes, _)| lobes)
        })
        .unwrap()
    };
    let groups = plan.groups.as_ref().unwrap();
    assert_eq!(on_gpu.stats.fitted, on_cpu.stats.fitted);
    assert_eq!(on_gpu.stats.served, on_cpu.stats.served);
    assert!(
        on_cpu.stats.served > 2 * on_cpu.stats.fitted,
        "{:?}",
        on_cpu.stats
    );
    let n = scene.splats.len();
    let lit: Vec<usize> = (0..n).filter(|&i| on_cpu.light[i].lobes > 0).collect();
    for map in [&on_gpu, &on_cpu] {
        for &i in &lit {
            if let Some(l) = groups.leader(i) {
                assert_eq!(map.splat_lobes(i), map.splat_lobes(l), "splat {i}");
                assert_eq!(map.light[i].irradiance, map.light[l].irradiance);
            }
        }
    }
    let grey = |map: &LobeMap| -> Vec<f32> { lit.iter().map(|&i| lobe_light(map, i)).collect() };
    let (a, b) = (grey(&on_gpu), grey(&on_cpu));
    let close = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| (*x - *y).abs() <= 1e-3 * y.abs().max(1e-3))
        .count();
    eprintln!("glossy splats: {}", common::apart(&a, &b));
    let share = if common::rounds_like_the_mirror(&gpu) {
        0.99
    } else {
        0.90
    };
    assert!(
        close as f64 >= share * a.len() as f64,
        "{close} of {}",
        a.len()
    );
    let mean = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
    assert!((mean(&a) - mean(&b)).abs() <= 1e-3 * mean(&b));
}

/// Shared fits estimate the same light as each splat's own: over the glossy block, the mean of
/// the lobes' irradiance with cells of one search radius within 2 % of every splat's own fit
/// (measured 0.004 %), with a third of the fits or fewer.
#[test]
fn shared_fits_keep_the_light_with_fewer_fits() {
    let own = {
        let mut scene = cornell(200_000);
        scene.bake.share = 0.0;
        let grid = common::host_grid(&scene);
        bake(&scene, BakeDevice::Cpu(&grid), &Progress::new(false)).unwrap()
    };
    let scene = cornell(200_000);
    let grid = common::host_grid(&scene);
    let shared = bake(&scene, BakeDevice::Cpu(&grid), &Progress::new(false)).unwrap();
    let n = scene.splats.len();
    let glossy: Vec<usize> = (0..n).filter(|&i| glossy(&scene, i)).collect();
    let mean = |map: &LobeMap| {
        glossy
            .iter()
            .map(|&i| lobe_light(map, i) as f64)
            .sum::<f64>()
            / glossy.len() as f64
    };
    let (a, b) = (mean(&shared.lobes), mean(&own.lobes));
    eprintln!(
        "glossy light {a:.5} shared ({} fits), {b:.5} own ({} fits)",
        shared.lobes.stats.fitted, own.lobes.stats.fitted
    );
    assert!((a / b - 1.0).abs() <= 0.02, "{a} against {b}");
    assert!(3 * shared.lobes.stats.fitted <= own.lobes.stats.fitted);
    assert_eq!(shared.em.splats_served, Some(shared.lobes.stats.served));
    assert!(shared.lobes.check_packed().is_ok());
}
