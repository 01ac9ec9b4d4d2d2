//! Photon binning: the GPU's lists equal the CPU mirror's (same cells, same photons in the
//! same key order), across store pages, across rank chunks of long cell lists and with cells
//! split into sub-cell lists.

mod common;

use std::path::Path;

use glam::Vec3;
use lobelight::bins::{PhotonBins, bin_params};
use lobelight::em::{EmConfig, FitShape};
use lobelight::grid::grid_params;
use lobelight::host::FitFrom;
use lobelight::photons::{PhotonConfig, PhotonMap};
use lobelight::renderer::{Engine, Renderer};
use lobelight::scene::{self, file::StoreRange};
use lobelight::shared::bins::{RANK_CHUNK, bin_of, list_count, lists_per_cell};
use lobelight::shared::octahedral::oct_decode;
use lobelight::types::{BinParams, GridParams, Photon};

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

/// Every photon of `map` is in the list of its own cell (or sub-cell), once, in key order.
fn assert_well_formed(bins: &PhotonBins, map: &PhotonMap) {
    assert_eq!(bins.len(), map.photons.len());
    assert_eq!(bins.cell_start.len(), list_count(&bins.params) as usize + 1);
    let by_key: std::collections::HashMap<(u32, u32), &Photon> =
        map.photons.iter().map(|p| (p.key(), p)).collect();
    for c in 0..list_count(&bins.params) as usize {
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
    let device = common::device();
    let scene = std::sync::Arc::new(scene::load(Path::new("scenes/cornell.toml")).unwrap());
    let cfg = PhotonConfig {
        photons: 60_000,
        store: StoreRange::All,
        batch: 8192,
        ..PhotonConfig::from_scene(&scene)
    };
    let renderer = Renderer::new(scene.clone(), &device).unwrap();
    let map = renderer.trace_photons(&cfg, &mut |_, _| {}).unwrap().map;
    let pages: Vec<&[Photon]> = map.photons.chunks(20_000).collect();
    assert!(pages.len() >= 3, "{} pages", pages.len());
    let stored = map.photons.len() as u64;
    let grid = renderer.read_grid().unwrap();
    let params = bin_params(&grid.params, scene.search_radius(), stored).unwrap();
    let on_gpu = device.bin_photons(&params, &pages, &scene.splats).unwrap();
    let on_cpu = Engine::Mirror
        .bin_photons(&params, &[&map.photons], &scene.splats)
        .unwrap();
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
    let device = common::device();
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
    // No photons counted: one list a cell.
    let params = bin_params(&grid, 0.2, 0).unwrap();
    assert_eq!(params.sub, 1);
    let map = PhotonMap {
        photons,
        stats: Default::default(),
    };
    let on_cpu = Engine::Mirror
        .bin_photons(&params, &[&map.photons], &splats)
        .unwrap();
    let on_gpu = device
        .bin_photons(&params, &[&map.photons], &splats)
        .unwrap();
    let longest = on_gpu.cell_start.windows(2).map(|w| w[1] - w[0]).max();
    assert_eq!(
        longest.map(|n| n.div_ceil(RANK_CHUNK)),
        Some(3),
        "rank chunks"
    );
    assert_well_formed(&on_cpu, &map);
    assert_same_bins(&on_gpu, &on_cpu);
}

/// Cells split into 2³, 3³ and 4³ sub-cell lists: the device's lists equal the mirror's, each
/// photon is in its sub-cell's list in key order, a cell's lists hold exactly the photons its
/// one list held, and the lobe fit over them finds the same photons for every splat (counts
/// equal, irradiance equal but for the order of the sums).
#[test]
fn sub_cell_lists_hold_each_cells_photons() {
    let device = common::device();
    let scene = std::sync::Arc::new(scene::load(Path::new("scenes/cornell.toml")).unwrap());
    let cfg = PhotonConfig {
        photons: 60_000,
        ..PhotonConfig::from_scene(&scene)
    };
    let renderer = Renderer::new(scene.clone(), &device).unwrap();
    let map = renderer.trace_photons(&cfg, &mut |_, _| {}).unwrap().map;
    let grid = renderer.read_grid().unwrap();
    // Twice the scene's radius: 4³ sub-cells of its 64 k cells stay within a storage binding.
    let radius = 2.0 * scene.search_radius();
    let whole = bin_params(&grid.params, radius, 0).unwrap();
    assert_eq!(whole.sub, 1);
    let mirror = Engine::Mirror;
    let one = mirror
        .bin_photons(&whole, &[&map.photons], &scene.splats)
        .unwrap();
    let em = EmConfig {
        radius,
        // The photon fit itself.
        gather: 0,
        ..EmConfig::from_scene(&scene)
    };
    let of = (&scene.splats[..], &scene.materials[..]);
    let fit_one = mirror
        .fit_lobes(&em, FitFrom::photons(&one), of, FitShape::default())
        .unwrap();
    for sub in [2, 3, 4] {
        let params = BinParams { sub, ..whole };
        let on_cpu = mirror
            .bin_photons(&params, &[&map.photons], &scene.splats)
            .unwrap();
        let on_gpu = device
            .bin_photons(&params, &[&map.photons], &scene.splats)
            .unwrap();
        assert_well_formed(&on_cpu, &map);
        assert_same_bins(&on_gpu, &on_cpu);
        let per_cell = lists_per_cell(&params) as usize;
        for c in 0..whole.cell_count as usize {
            let mut split = on_cpu.keys[on_cpu.cell_start[c * per_cell] as usize
                ..on_cpu.cell_start[(c + 1) * per_cell] as usize]
                .to_vec();
            split.sort();
            let listed = &one.keys[one.cell_start[c] as usize..one.cell_start[c + 1] as usize];
            assert_eq!(split, listed, "sub {sub}: cell {c}");
        }
        let fit = mirror
            .fit_lobes(&em, FitFrom::photons(&on_cpu), of, FitShape::default())
            .unwrap();
        for (i, (a, b)) in fit_one.light.iter().zip(&fit.light).enumerate() {
            assert_eq!(a.photons, b.photons, "sub {sub}: splat {i}");
            for k in 0..3 {
                let (x, y) = (a.irradiance[k], b.irradiance[k]);
                assert!(
                    (x - y).abs() <= 1e-5 * x.abs().max(1e-20),
                    "sub {sub}: splat {i} irradiance {x} vs {y}"
                );
            }
        }
    }
}

/// Cells are split only while there are photons enough to fill the lists, and never past
/// the cap on lists.
#[test]
fn cells_split_with_the_photon_count() {
    let scene = scene::load(Path::new("scenes/cornell.toml")).unwrap();
    let grid = grid_params(&scene.splats, &Default::default()).unwrap();
    let r = 2.0 * scene.search_radius();
    let cells = bin_params(&grid, r, 0).unwrap().cell_count as u64;
    assert!(cells * 64 <= lobelight::bins::MAX_BIN_LISTS);
    let sub_for = |stored: u64| bin_params(&grid, r, stored).unwrap().sub;
    assert_eq!(sub_for(0), 1);
    let per = lobelight::bins::LISTS_PER_PHOTON;
    // The least photon count for s³ lists a cell.
    let least = |s: u64| (cells * s * s * s).div_ceil(per);
    assert_eq!(sub_for(least(2) - 1), 1);
    assert_eq!(sub_for(least(2)), 2);
    assert_eq!(sub_for(least(3) - 1), 2);
    assert_eq!(sub_for(least(3)), 3);
    assert_eq!(sub_for(least(4)), 4);
    assert_eq!(sub_for(u64::MAX), 4);
    let huge = GridParams {
        dims: [1024, 1024, 1024],
        cell_count: 1 << 30,
        ..grid
    };
    let p = bin_params(&huge, 1e-6, u64::MAX).unwrap();
    assert!(
        list_count(&p) as u64 <= lobelight::bins::MAX_BIN_LISTS,
        "{p:?}"
    );
}
