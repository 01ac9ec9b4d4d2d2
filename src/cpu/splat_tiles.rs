//! Mirrors of `wgsl/splat_tile_count.wgsl` and `wgsl/splat_tile_scatter.wgsl`: the compute
//! splatter's binning of splats into screen tiles (`grid_rank` then orders each list). The
//! tile pass itself, `splat_compute`, sums the same fragments in the same order as the raster
//! passes, so its mirror is theirs (`splat_visibility`, `splat_attributes`).

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view};
use crate::error::Result;
use crate::shared::splat::tile_rect;
use crate::types::{Camera, Splat, TileParams};

pub const WG: u32 = 64;

fn tiles_of(cam: &Camera, p: &TileParams, s: &Splat) -> impl Iterator<Item = u32> {
    let [x0, y0, x1, y1] = tile_rect(cam, s, p.tiles_x, p.tiles_y);
    let tiles_x = p.tiles_x;
    (y0..=y1)
        .filter(move |_| x0 <= x1)
        .flat_map(move |ty| (x0..=x1).map(move |tx| ty * tiles_x + tx))
}

/// Counts every splat into the tiles it may cover.
pub fn splat_tile_count(cam: &Camera, p: &TileParams, splats: &[Splat], counts: &mut [u32]) {
    for s in &splats[..p.splat_count as usize] {
        for t in tiles_of(cam, p, s) {
            counts[t as usize] += 1;
        }
    }
}

/// Writes (splat, tile) into each tile's list from its start, in splat order (the device's
/// order is the atomics'; `grid_rank` makes both splat order).
pub fn splat_tile_scatter(
    cam: &Camera,
    p: &TileParams,
    splats: &[Splat],
    tile_start: &[u32],
    cursor: &mut [u32],
    scratch_splats: &mut [u32],
    scratch_tiles: &mut [u32],
) {
    for (i, s) in splats[..p.splat_count as usize].iter().enumerate() {
        for t in tiles_of(cam, p, s) {
            let e = (tile_start[t as usize] + cursor[t as usize]) as usize;
            cursor[t as usize] += 1;
            scratch_splats[e] = i as u32;
            scratch_tiles[e] = t;
        }
    }
}

/// The executor's entry: `splat_tile_count`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch_tile_count(b: &Bindings, _groups: u32) -> Result<()> {
    let cam = b.param(0)?;
    let p = b.param(1)?;
    let splats = b.get(2)?;
    let mut counts = b.get_mut(3)?;
    splat_tile_count(&cam, &p, view(&splats), &mut counts);
    Ok(())
}

/// The executor's entry: `splat_tile_scatter`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch_tile_scatter(b: &Bindings, _groups: u32) -> Result<()> {
    let cam = b.param(0)?;
    let p = b.param(1)?;
    let splats = b.get(2)?;
    let tile_start = b.get(3)?;
    let mut cursor = b.get_mut(4)?;
    let mut scratch_splats = b.get_mut(5)?;
    let mut scratch_tiles = b.get_mut(6)?;
    splat_tile_scatter(
        &cam,
        &p,
        view(&splats),
        &tile_start,
        &mut cursor,
        &mut scratch_splats,
        &mut scratch_tiles,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::SplatCompute,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: None,
    },
    MirrorRow {
        stage: Stage::SplatTileCount,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch_tile_count)),
    },
    MirrorRow {
        stage: Stage::SplatTileScatter,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch_tile_scatter)),
    },
];
