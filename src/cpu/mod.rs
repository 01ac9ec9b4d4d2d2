//! CPU mirrors of the WGSL stages: one file per `wgsl/<stage>.wgsl`, with the same name, the
//! same bindings as arguments in binding order, and the same loop shape (workgroups, then
//! local invocations), so that a difference between the two points at one line.
//! They are the reference for the parity tests and a fallback when no GPU is wanted.

pub mod bin_count;
pub mod bin_place;
pub mod bin_rank;
pub mod bin_scatter;
pub mod em_fit;
pub mod em_select;
pub mod grid_count;
pub mod grid_distance;
pub mod grid_rank;
pub mod grid_scatter;
pub mod photon_resolve;
pub mod photon_trace;
pub mod photon_view;
pub mod present;
pub mod reference_gather;
pub mod scan_apply;
pub mod scan_reduce;
pub mod shade;
pub mod splat_attributes;
pub mod splat_visibility;
pub mod tonemap_apply;
pub mod tonemap_reduce;
pub mod trace_rays;

use std::time::Instant;

use crate::bins::PhotonBins;
use crate::em::{EmConfig, EmStats, FitShape, LobeMap};
use crate::error::{Error, Result};
use crate::grid::{SplatGrid, check_cell_len};
use crate::photons::{
    PhotonConfig, PhotonMap, PhotonStats, StoreAction, StorePlanner, emitters, first_capacity,
    ms_since,
};
use crate::shared::trace::Geometry;
use crate::types::{
    BinParams, BinnedPhoton, DistanceParams, EmParams, GridParams, Lobe, ScanParams, Splat,
    SplatLight,
};
use crate::types::{Light, Material, Photon, TraceCounters};

pub use crate::shared::dispatch::groups_for;

/// Tone mapping as `gpu::tone::tone_map` records it: the reduction level by level, then the
/// operator; returns RGBA8 pixels and (Σ log(ε + Y), count).
pub fn tone_map(cfg: &crate::tone::ToneConfig, hdr: &[[f32; 4]]) -> Result<(Vec<u32>, [f32; 2])> {
    cfg.validate()?;
    let pixels = u32::try_from(hdr.len())
        .map_err(|_| Error::Invalid("too many pixels to tone-map".into()))?;
    let mut sums_in = vec![[0.0f32; 2]];
    for (level, &count) in crate::tone::reduce_levels(pixels, tonemap_reduce::BLOCK)
        .iter()
        .enumerate()
    {
        let blocks = groups_for(count, tonemap_reduce::BLOCK).max(1);
        let mut sums_out = vec![[0.0f32; 2]; blocks as usize];
        let params = cfg.params(count, level as u32);
        tonemap_reduce::tonemap_reduce(&params, hdr, &sums_in, &mut sums_out, blocks);
        sums_in = sums_out;
    }
    let mut rgba = vec![0u32; hdr.len()];
    tonemap_apply::tonemap_apply(&cfg.params(pixels, 0), hdr, &sums_in, &mut rgba);
    Ok((rgba, sums_in[0]))
}

/// The photon view of `cam` as `gpu::photon_view::photon_image` records it: every page (here
/// one) through `photon_view`, then `photon_resolve`; HDR pixels, rows from the top.
pub fn photon_image(
    cam: &crate::types::Camera,
    materials: &[Material],
    photons: &[Photon],
    geo: &Geometry,
    scale: f32,
) -> Vec<[f32; 4]> {
    let (width, height) = (cam.size[0] as u32, cam.size[1] as u32);
    let pixels = (width * height) as usize;
    let mut sums = vec![0u32; 3 * pixels];
    let mut params = crate::types::PhotonViewParams {
        count: photons.len() as u32,
        width,
        height,
        scale,
    };
    photon_view::photon_view(&params, cam, materials, photons, &mut sums, geo);
    params.count = pixels as u32;
    let mut hdr = vec![[0.0f32; 4]; pixels];
    photon_resolve::photon_resolve(&params, &sums, &mut hdr);
    hdr
}

/// Exclusive scan of `values` in place, level by level exactly as `gpu::scan` records it:
/// reduce blocks, scan the block sums recursively, apply.
pub fn exclusive_scan(values: &mut [u32]) {
    let len = values.len() as u32;
    let params = ScanParams {
        len,
        ..Default::default()
    };
    let blocks = groups_for(len, scan_reduce::BLOCK);
    if blocks <= 1 {
        scan_apply::scan_apply(&params, values, &[0], blocks);
        return;
    }
    let mut block_sums = vec![0u32; blocks as usize];
    scan_reduce::scan_reduce(&params, values, &mut block_sums, blocks);
    exclusive_scan(&mut block_sums);
    scan_apply::scan_apply(&params, values, &block_sums, blocks);
}

/// The distance field of a grid's cell lists: passes x, y, z of `grid_distance`.
pub fn distance_field(grid: &GridParams, cell_start: &[u32]) -> Vec<u32> {
    let cells = grid.cell_count as usize;
    let groups = groups_for(grid.cell_count, grid_distance::WG);
    let (mut a, mut b) = (vec![0u32; cells], vec![0u32; cells]);
    let pass = |axis| DistanceParams {
        axis,
        ..Default::default()
    };
    grid_distance::grid_distance(&pass(0), grid, cell_start, cell_start, &mut a, groups);
    grid_distance::grid_distance(&pass(1), grid, cell_start, &a, &mut b, groups);
    grid_distance::grid_distance(&pass(2), grid, cell_start, &b, &mut a, groups);
    a
}

/// The whole grid build on the CPU: count → exclusive scan → scatter → rank, then the
/// distance field.
pub fn build_grid(params: &GridParams, splats: &[Splat]) -> Result<SplatGrid> {
    let splat_groups = groups_for(params.splat_count, grid_count::WG);
    let mut cell_start = vec![0u32; params.cell_count as usize + 1];
    let mut max_cell_len = 0;
    grid_count::grid_count(
        params,
        splats,
        &mut cell_start,
        &mut max_cell_len,
        splat_groups,
    );
    check_cell_len(max_cell_len)?;
    exclusive_scan(&mut cell_start);
    let params = GridParams {
        entry_count: cell_start[params.cell_count as usize],
        ..*params
    };
    let entries = params.entry_count as usize;
    let mut cursor = vec![0u32; params.cell_count as usize];
    let (mut scratch_splats, mut scratch_cells) = (vec![0u32; entries], vec![0u32; entries]);
    grid_scatter::grid_scatter(
        &params,
        splats,
        &cell_start,
        &mut cursor,
        &mut scratch_splats,
        &mut scratch_cells,
        splat_groups,
    );
    let mut cell_splats = vec![0u32; entries];
    let entry_groups = groups_for(params.entry_count, grid_rank::WG);
    grid_rank::grid_rank(
        &params,
        &cell_start,
        &scratch_splats,
        &scratch_cells,
        &mut cell_splats,
        entry_groups,
    );
    let cell_dist = distance_field(&params, &cell_start);
    Ok(SplatGrid {
        params,
        cell_start,
        cell_splats,
        cell_dist,
    })
}

/// The photon pass on the CPU: the batch loop of `gpu::photons::trace_photons` with one
/// growable store (host memory has no binding limit) and the same store planning.
pub fn trace_photons(
    lights: &[Light],
    materials: &[Material],
    geo: &Geometry,
    cfg: &PhotonConfig,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<PhotonMap> {
    cfg.validate()?;
    let t = Instant::now();
    let emitters = emitters(lights, cfg.photons)?;
    let max_page = u32::MAX as u64;
    let mut planner = StorePlanner::new(max_page, cfg.photons);
    let mut store = vec![Photon::default(); first_capacity(cfg, max_page) as usize];
    let mut count = 0u64;
    let mut stats = PhotonStats::default();
    let mut done = 0u64;
    while done < cfg.photons {
        let paths = (cfg.photons - done).min(cfg.batch as u64) as u32;
        if let StoreAction::Grow(c) = planner.before(count, store.len() as u64, paths, done) {
            store.resize(c as usize, Photon::default());
        }
        let params = cfg.params(&emitters, done as u32, paths);
        let mut counters = TraceCounters {
            stored: count as u32,
            capacity: store.len() as u32,
            ..Default::default()
        };
        photon_trace::photon_trace(
            &params,
            &emitters,
            materials,
            &mut store,
            &mut counters,
            geo,
            groups_for(paths, photon_trace::WG),
        );
        let need = counters.stored as u64 - count;
        if counters.overflow == 0 {
            stats.add_batch(paths, count as u32, &counters);
            planner.record(paths, need);
            count = counters.stored as u64;
            done += paths as u64;
            progress(done, cfg.photons);
            continue;
        }
        stats.reruns += 1;
        match planner.after_overflow(count, store.len() as u64, need, paths, done) {
            StoreAction::Grow(c) => store.resize(c as usize, Photon::default()),
            _ => {
                return Err(Error::Invalid(format!(
                    "more than {max_page} stored photons: emit fewer photons"
                )));
            }
        }
    }
    store.truncate(count as usize);
    stats.pages = 1;
    stats.trace_ms = ms_since(t);
    let mut map = PhotonMap {
        photons: store,
        stats,
    };
    map.sort();
    Ok(map)
}

/// The scene's splat grid, built by the mirror.
pub fn scene_grid(scene: &crate::scene::Scene) -> Result<SplatGrid> {
    build_grid(
        &crate::grid::grid_params(&scene.splats, &scene.grid)?,
        &scene.splats,
    )
}

/// The scene's grid and photons on the CPU: what the GPU path keeps on the device, here on
/// the host. Returns the photons, the grid and the grid build time in ms.
pub fn trace_scene(
    scene: &crate::scene::Scene,
    cfg: &PhotonConfig,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(PhotonMap, SplatGrid, f64)> {
    let t = Instant::now();
    let grid = scene_grid(scene)?;
    let grid_ms = ms_since(t);
    let geo = Geometry {
        grid: &grid,
        splats: &scene.splats,
    };
    let map = trace_photons(&scene.lights, &scene.materials, &geo, cfg, progress)?;
    Ok((map, grid, grid_ms))
}

/// Photon binning on the CPU: the passes of `gpu::bins::bin_photons` over one page holding
/// every photon.
pub fn bin_photons(params: &BinParams, photons: &[Photon]) -> Result<PhotonBins> {
    let n = u32::try_from(photons.len())
        .map_err(|_| Error::Invalid("too many photons to bin".into()))?;
    let params = BinParams {
        photon_count: n,
        ..*params
    };
    let cells = params.cell_count as usize;
    let groups = groups_for(n, bin_count::WG);
    let mut cell_start = vec![0u32; cells + 1];
    let mut chunks = 0;
    bin_count::bin_count(&params, photons, &mut cell_start, &mut chunks, groups);
    exclusive_scan(&mut cell_start);
    let len = n as usize;
    let mut cursor = vec![0u32; cells];
    let mut scratch_keys = vec![[0u32; 2]; len];
    let mut scratch_cells = vec![0u32; len];
    let mut scratch_geom = vec![BinnedPhoton::default(); len];
    let mut scratch_power = vec![[0f32; 4]; len];
    bin_scatter::bin_scatter(
        &params,
        photons,
        &cell_start,
        &mut cursor,
        &mut scratch_keys,
        &mut scratch_cells,
        &mut scratch_geom,
        &mut scratch_power,
        groups,
    );
    let mut slots = vec![0u32; len];
    for chunk in 0..chunks {
        let pass = BinParams {
            rank_chunk: chunk,
            ..params
        };
        bin_rank::bin_rank(
            &pass,
            &cell_start,
            &scratch_keys,
            &scratch_cells,
            &mut slots,
            groups,
        );
    }
    let mut bins = PhotonBins {
        params,
        cell_start,
        keys: vec![[0u32; 2]; len],
        geom: vec![BinnedPhoton::default(); len],
        power: vec![[0f32; 4]; len],
    };
    bin_place::bin_place(
        &params,
        &slots,
        &scratch_keys,
        &scratch_geom,
        &scratch_power,
        &mut bins.keys,
        &mut bins.geom,
        &mut bins.power,
        groups,
    );
    Ok(bins)
}

/// The lobe fit on the CPU: `em_select`, then `em_fit` over the same dispatch ranges and
/// with the same sum order as the GPU path on a device of the given shape.
pub fn fit_lobes(
    cfg: &EmConfig,
    bins: &PhotonBins,
    splats: &[Splat],
    materials: &[Material],
    shape: FitShape,
) -> Result<LobeMap> {
    cfg.validate()?;
    let t = Instant::now();
    let splat_count = u32::try_from(splats.len())
        .map_err(|_| Error::Invalid("too many splats for the lobe fit".into()))?;
    let n = splats.len();
    let mut fit_list = vec![0u32; n];
    let mut counters = [0u32; 3];
    em_select::em_select(
        &cfg.params(splat_count, 0, shape),
        &bins.params,
        splats,
        materials,
        &bins.cell_start,
        &mut fit_list,
        &mut counters,
        groups_for(splat_count, em_select::WG),
    );
    let [listed, max_candidates, fitted] = counters;
    let chunk = crate::em::iterations_per_dispatch(cfg, max_candidates, shape.loop_limited)?;
    // The fit's slots, `cfg.lobes` a splat (also the mixture handed between dispatches).
    let mut dense = vec![Lobe::default(); n * cfg.lobes as usize];
    let mut light = vec![SplatLight::default(); n];
    let mut stats = EmStats {
        listed,
        fitted,
        max_candidates,
        ..Default::default()
    };
    for (begin, end) in crate::em::dispatch_ranges(cfg.iterations, chunk) {
        let params = EmParams {
            iteration_begin: begin,
            iteration_end: end,
            ..cfg.params(splat_count, listed, shape)
        };
        em_fit::em_fit(
            &params,
            &bins.params,
            splats,
            &fit_list,
            &bins.cell_start,
            &bins.geom,
            &bins.power,
            &mut dense,
            &mut light,
            listed,
        );
        stats.dispatches += 1;
    }
    stats.ms = ms_since(t);
    let mut map = LobeMap::pack(cfg.lobes, &dense, light, stats);
    map.stats.photons = map.fitted().map(|l| l.photons as u64).sum();
    Ok(map)
}
