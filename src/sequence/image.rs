//! What frames run as sequences: the tone map, the temporal pass, the compute splatter's
//! tile lists and the path tracer's samples.

use crate::error::{Error, Result};
use crate::shaders::Stage;
use crate::shaders::stage_shape;
use crate::shared::dispatch::groups_for;
use crate::tone::{ToneConfig, reduce_levels};
use crate::types::{Camera, GridParams, PathParams, TemporalParams, TileParams};

pub use crate::shared::splat::TILE;

use super::{Executor, exclusive_scan, groups};

/// A tone-mapped image where it was made.
pub struct Toned<B> {
    /// RGBA8 sRGB, one u32 per pixel.
    pub rgba: B,
    /// (Σ log(ε + Y), count) over the finite pixels.
    pub log_sum: B,
}

/// Tone mapping of `pixels` HDR pixels (`vec4<f32>` each): `tonemap_reduce` level by level
/// down to one (Σ log, count), then `tonemap_apply` per pixel.
pub fn tone_map<E: Executor>(
    ex: &mut E,
    hdr: &E::Buffer,
    pixels: u32,
    cfg: &ToneConfig,
) -> Result<Toned<E::Buffer>> {
    cfg.validate()?;
    let sums_in = log_sum(ex, hdr, pixels, cfg)?;
    let rgba = ex.zeroed("tone-mapped image", pixels.max(1) as u64 * 4)?;
    let params = ex.uniform("tone params", &cfg.params(pixels, 0))?;
    let bindings = [&params, hdr, &sums_in, &rgba];
    ex.dispatch(
        Stage::TonemapApply,
        &bindings,
        groups(Stage::TonemapApply, pixels)?,
    )?;
    Ok(Toned {
        rgba,
        log_sum: sums_in,
    })
}

/// The log-average's sum of `pixels` HDR pixels, (Σ log(ε + Y), count) over the finite ones, in
/// a buffer of one `vec2<f32>`: `tonemap_reduce` level by level down to one.
pub fn log_sum<E: Executor>(
    ex: &mut E,
    hdr: &E::Buffer,
    pixels: u32,
    cfg: &ToneConfig,
) -> Result<E::Buffer> {
    let block = stage_shape(Stage::TonemapReduce)?.per_group(Stage::TonemapReduce)?;
    let mut sums_in = ex.zeroed("tone sums", 8)?;
    for (level, &count) in reduce_levels(pixels, block).iter().enumerate() {
        let blocks = groups_for(count, block).max(1);
        let sums_out = ex.zeroed("tone sums", blocks as u64 * 8)?;
        let params = ex.uniform("tone params", &cfg.params(count, level as u32))?;
        let bindings = [&params, hdr, &sums_in, &sums_out];
        ex.dispatch(Stage::TonemapReduce, &bindings, blocks)?;
        sums_in = sums_out;
    }
    Ok(sums_in)
}

/// The moving frames' history buffers of one frame: the resolved image (w: the frames it
/// holds) and the surface each pixel kept.
pub struct TemporalHistory<'a, B> {
    pub image: &'a B,
    pub surface: &'a B,
}

/// Temporal anti-aliasing of a moving frame (`temporal`): `hdr` and its `surface`, drawn with
/// `cam`, blended into `last` (drawn with `prev`), resolved into `next`, whose image is then
/// copied into `hdr`. The frame's log-average (`log_sum`) sets the scale of the pass's weights.
#[allow(clippy::too_many_arguments)]
pub fn temporal<E: Executor>(
    ex: &mut E,
    cam: &Camera,
    prev: &Camera,
    params: &TemporalParams,
    hdr: &E::Buffer,
    surface: &E::Buffer,
    last: TemporalHistory<E::Buffer>,
    next: TemporalHistory<E::Buffer>,
) -> Result<()> {
    let pixels = params.width * params.height;
    let cam_buf = ex.uniform("camera", cam)?;
    let prev_buf = ex.uniform("last camera", prev)?;
    let params_buf = ex.uniform("temporal params", params)?;
    let frame_log_sum = log_sum(ex, hdr, pixels, &ToneConfig::default())?;
    let bindings = [
        &cam_buf,
        &prev_buf,
        &params_buf,
        hdr,
        surface,
        last.image,
        last.surface,
        next.image,
        next.surface,
        &frame_log_sum,
    ];
    ex.dispatch(Stage::Temporal, &bindings, groups(Stage::Temporal, pixels)?)?;
    ex.copy(next.image, 0, hdr, 0, pixels as u64 * 16)
}

/// Each screen tile's splats, in splat-index order, where they were binned.
pub struct TileLists<B> {
    /// The tiling, with the entry count the binning found.
    pub params: TileParams,
    /// `tiles + 1` list starts (the scanned counts).
    pub start: B,
    /// The lists, one after another.
    pub splats: B,
    /// The longest list.
    pub longest: u32,
}

/// Bins the splats into the screen tiles of `cam` (bound as `cam_buf`): `splat_tile_count`,
/// the exclusive scan, then a split point for the entry total (it sizes the lists),
/// `splat_tile_scatter`, and `grid_rank` to put each list in splat-index order.
pub fn bin_splat_tiles<E: Executor>(
    ex: &mut E,
    cam: &Camera,
    cam_buf: &E::Buffer,
    splats: &E::Buffer,
    splat_count: u32,
) -> Result<TileLists<E::Buffer>> {
    let (width, height) = (cam.size[0] as u32, cam.size[1] as u32);
    let mut params = TileParams {
        tiles_x: width.div_ceil(TILE),
        tiles_y: height.div_ceil(TILE),
        splat_count,
        entry_count: 0,
    };
    let tiles = params.tiles_x * params.tiles_y;
    let uniform = ex.uniform("tile params", &params)?;
    let start = ex.zeroed("tile starts", (tiles as u64 + 1) * 4)?;
    let per_splat = groups(Stage::SplatTileCount, splat_count)?;
    ex.dispatch(
        Stage::SplatTileCount,
        &[cam_buf, &uniform, splats, &start],
        per_splat,
    )?;
    exclusive_scan(ex, &start, tiles + 1)?;
    let starts = ex.read::<u32>(&start, tiles as usize + 1)?;
    params.entry_count = starts[tiles as usize];
    let longest = starts.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0);
    // grid_rank's loop, and the splatter's, walk a whole list per invocation.
    if longest > crate::grid::MAX_CELL_LEN {
        return Err(Error::Invalid(format!(
            "{longest} splats cover one {TILE}×{TILE}-pixel tile (at most {}): the compute \
             splatter cannot draw this view; use --splatter raster",
            crate::grid::MAX_CELL_LEN
        )));
    }
    let entries = params.entry_count.max(1) as u64 * 4;
    let uniform = ex.uniform("tile params", &params)?;
    let cursor = ex.zeroed("tile cursors", tiles.max(1) as u64 * 4)?;
    let scratch_splats = ex.zeroed("tile scratch splats", entries)?;
    let scratch_tiles = ex.zeroed("tile scratch tiles", entries)?;
    let bindings = [
        cam_buf,
        &uniform,
        splats,
        &start,
        &cursor,
        &scratch_splats,
        &scratch_tiles,
    ];
    ex.dispatch(Stage::SplatTileScatter, &bindings, per_splat)?;
    let rank = GridParams {
        entry_count: params.entry_count,
        ..Default::default()
    };
    let rank = ex.uniform("tile rank params", &rank)?;
    let lists = ex.zeroed("tile lists", entries)?;
    let bindings = [&rank, &start, &scratch_splats, &scratch_tiles, &lists];
    let groups = groups(Stage::GridRank, params.entry_count)?;
    ex.dispatch(Stage::GridRank, &bindings, groups)?;
    Ok(TileLists {
        params,
        start,
        splats: lists,
        longest,
    })
}

/// Adds one path-traced sample per pixel (`params.sample`) to the running mean in `hdr`
/// (`path_trace`, one invocation per pixel).
pub fn path_sample<E: Executor>(
    ex: &mut E,
    params: &PathParams,
    cam: &E::Buffer,
    materials: &E::Buffer,
    lights: &E::Buffer,
    hdr: &E::Buffer,
) -> Result<()> {
    let uniform = ex.uniform("path params", params)?;
    let bindings = [&uniform, cam, materials, lights, hdr];
    let pixels = params.width * params.height;
    ex.dispatch_traced(
        Stage::PathTrace,
        &bindings,
        groups(Stage::PathTrace, pixels)?,
    )
}
