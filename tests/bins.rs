//! Photon binning: the GPU's lists equal the CPU mirror's (same cells, same photons in the
//! same key order), across store pages and across rank chunks of long cell lists.

mod common;

use std::path::Path;

use glam::Vec3;
use lobelight::bins::{PhotonBins, bin_params};
use lobelight::cpu;
use lobelight::gpu::bins::bin_photons;
use lobelight::gpu::photons::{GpuPhotons, trace_photons};
use lobelight::gpu::scene::GpuScene;
use lobelight::grid::grid_params;
use lobelight::photons::{PhotonConfig, PhotonMap};
use lobelight::scene::{self, file::StoreRange};
use lobelight::shared::bins::{RANK_CHUNK, bin_of};
use lobelight::shared::octahedral::oct_decode;
use lobelight::types::Photon;

/// Lists are identical: cell starts, keys, positions and powers bit for bit; directions
/// within one snorm16 step per component (the GPU's division may round the other way).
fn assert_same_bins(gpu: &PhotonBins, cpu: &PhotonBins) {
    assert_eq!(gpu.params, cpu.params);
    assert_eq!(gpu.cell_start, cpu.cell_start, "cell starts");
    assert_eq!(gpu.keys, cpu.keys, "keys in list order");
    assert_eq!(gpu.power, cpu.power, "powers");
    for (i, (g, c)) in gpu.geom.iter().zip(&cpu.geom).enumerate() {
        assert_eq!(g.position, c.position, "position of binned photon {i}");
        let step = |a: u32, b: u32| {
            let d = |s: u32| ((a >> s) as u16 as i16) as i32 - ((b >> s) as u16 as i16) as i32;
            d(0).abs().max(d(16).abs())
        };
        assert!(
            step(g.direction, c.direction) <= 1,
            "direction code of binned photon {i}: {:#x} vs {:#x}",
            g.direction,
            c.direction
        );
    }
}

/// Every photon of `map` is in the list of its own cell, once, in key order.
fn assert_well_formed(bins: &PhotonBins, map: &PhotonMap) {
    assert_eq!(bins.len(), map.photons.len());
    let by_key: std::collections::HashMap<(u32, u32), &Photon> =
        map.photons.iter().map(|p| (p.key(), p)).collect();
    for c in 0..bins.params.cell_count as usize {
        let (a, b) = (bins.cell_start[c] as usize, bins.cell_start[c + 1] as usize);
        for i in a..b {
            if i > a {
                assert!(bins.keys[i - 1] < bins.keys[i], "cell {c} not in key order");
            }
            let [path, bounce] = bins.keys[i];
            let p = by_key[&(path, bounce)];
            assert_eq!(bin_of(Vec3::from(p.position), &bins.params) as usize, c);
            assert_eq!(bins.geom[i].position, p.position);
            let d = oct_decode(bins.geom[i].direction);
            let err = (d - Vec3::from(p.direction)).length();
            assert!(err < 1e-4, "direction error {err}");
            assert_eq!(&bins.power[i][..3], &p.power[..]);
        }
    }
}

#[test]
fn gpu_bins_equal_cpu_bins_across_pages() {
    let gpu = common::gpu();
    let scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    let cfg = PhotonConfig {
        photons: 60_000,
        store: StoreRange::All,
        batch: 8192,
        page_limit: 20_000,
        ..PhotonConfig::from_scene(&scene)
    };
    let uploaded = GpuScene::upload(&gpu, &scene).unwrap();
    let traced = trace_photons(&gpu, &scene, &uploaded, &cfg, &mut |_, _| {}).unwrap();
    assert!(traced.pages.len() >= 3, "{} pages", traced.pages.len());
    let params = bin_params(&uploaded.grid.params, scene.search_radius()).unwrap();
    let on_gpu = bin_photons(&gpu, &traced, &uploaded.splats, &params)
        .unwrap()
        .download(&gpu)
        .unwrap();
    let map = traced.download(&gpu).unwrap();
    let on_cpu = cpu::bin_photons(&params, &map.photons, &scene.splats).unwrap();
    // Each photon carries the surface it landed on.
    let by_key: std::collections::HashMap<_, _> =
        map.photons.iter().map(|m| (m.key(), m)).collect();
    for (p, q) in on_cpu.power.iter().zip(&on_cpu.keys) {
        let photon = by_key[&(q[0], q[1])];
        let n = glam::Vec3::from(scene.splats[photon.splat as usize].normal);
        let got = lobelight::shared::octahedral::surface_decode(p[3]);
        assert!(
            got.dot(n) > 0.9999,
            "surface {got} of a photon on a splat facing {n}"
        );
    }
    assert_well_formed(&on_cpu, &map);
    assert_same_bins(&on_gpu, &on_cpu);
}

/// 20,000 photons in one cell, stored in scrambled key order: the list is three rank chunks
/// long, and comes out sorted on both sides.
#[test]
fn long_cell_lists_sort_across_rank_chunks() {
    let gpu = common::gpu();
    let mut rng = common::Rng(7);
    let n = 20_000u32;
    assert!(n > 2 * RANK_CHUNK);
    let photons: Vec<Photon> = (0..n)
        .map(|i| Photon {
            position: [0.1 + 1e-3 * rng.f32(), 0.1, 0.1],
            bounce: i % 3,
            direction: rng.unit_vector(),
            splat: 0,
            power: [rng.f32(), rng.f32(), rng.f32()],
            path: (i * 7919) % n,
        })
        .collect();
    let mut keys: Vec<_> = photons.iter().map(|p| p.key()).collect();
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), n as usize, "keys must be unique");
    let splats = common::random_splats(64, 0.01, 0.05, 3);
    let grid = grid_params(&splats, &Default::default()).unwrap();
    let params = bin_params(&grid, 0.2).unwrap();
    let map = PhotonMap {
        photons,
        stats: Default::default(),
    };
    let on_cpu = cpu::bin_photons(&params, &map.photons, &splats).unwrap();
    let uploaded = GpuPhotons::upload(&gpu, &map).unwrap();
    let splat_buffer = gpu.storage("splats", &splats).unwrap();
    let binned = bin_photons(&gpu, &uploaded, &splat_buffer, &params).unwrap();
    assert_eq!(binned.rank_chunks, 3);
    let on_gpu = binned.download(&gpu).unwrap();
    assert_well_formed(&on_cpu, &map);
    assert_same_bins(&on_gpu, &on_cpu);
}
