//! Mirror of `wgsl/splat_visibility.wgsl`, with the rasterizer the GPU has in hardware: the
//! image is cut into tiles, each tile lists the front-facing splats whose projected triangle
//! touches it in draw order, and each tile runs its splats over its pixels in that order, so
//! every pixel sees the same fragments in the same order as on the GPU.
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::MirrorRow;
use crate::shaders::Stage;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::shared::octahedral::oct_encode;
use crate::shared::splat::{
    SPLAT_CORNERS, clip_position, covers, drawn_keeps, faces_camera, in_view, pixel_ray,
    splat_corner, splat_hit, view_depth,
};
use crate::types::{Camera, Splat, SurfaceClip};

/// Tile edge in pixels.
pub const TILE: u32 = 32;

/// The splats that may cover each tile, in draw order; tiles row by row.
pub struct Tiles {
    pub width: u32,
    pub height: u32,
    pub cols: u32,
    pub lists: Vec<Vec<u32>>,
    /// Each splat's `splat_bounds`, computed once for both passes.
    pub bounds: Vec<Option<Rect>>,
}

/// Pixel rectangle `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug)]
pub struct Rect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

/// The pixels a splat's triangle may cover: the bounds of its projected corners, or the whole
/// image when some corner, not all, lies behind the near plane (the GPU clips such a triangle
/// there; the per-pixel disk test decides either way). `None` for a back-facing splat, one of
/// radius 0 (left out by the level of detail, `drawn_splats`), one outside the view (`in_view`)
/// and one wholly behind the near plane: a ground seen from just above it has half its splats
/// behind the eye, and each of them cost every pixel of every frame (a 96² still of a 40,000-
/// splat ground 47.8 s, where the device, which clips them, took 0.42 s).
pub fn splat_bounds(cam: &Camera, s: &Splat) -> Option<Rect> {
    if !faces_camera(s, Vec3::from(cam.eye)) || !(s.radius > 0.0) || !in_view(cam, s) {
        return None;
    }
    let size = Vec2::from(cam.size);
    let (mut lo, mut hi) = (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN));
    let mut behind = 0;
    for i in 0..SPLAT_CORNERS {
        let c = clip_position(cam, splat_corner(s, i));
        if !(c.w > cam.near) {
            behind += 1;
            continue;
        }
        let ndc = Vec2::new(c.x, c.y) / c.w;
        let p = Vec2::new((ndc.x * 0.5 + 0.5) * size.x, (0.5 - ndc.y * 0.5) * size.y);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if behind == SPLAT_CORNERS {
        return None;
    }
    if behind > 0 {
        (lo, hi) = (Vec2::ZERO, size);
    }
    let lo = lo.max(Vec2::ZERO).floor();
    let hi = hi.min(size).ceil();
    (lo.x < hi.x && lo.y < hi.y).then_some(Rect {
        x0: lo.x as u32,
        y0: lo.y as u32,
        x1: hi.x as u32,
        y1: hi.y as u32,
    })
}

pub fn bin_tiles(cam: &Camera, splats: &[Splat]) -> Tiles {
    let (width, height) = (cam.size[0] as u32, cam.size[1] as u32);
    let cols = width.div_ceil(TILE);
    let rows = height.div_ceil(TILE);
    let bounds: Vec<Option<Rect>> = splats.par_iter().map(|s| splat_bounds(cam, s)).collect();
    let mut lists = vec![Vec::new(); (cols * rows) as usize];
    for (i, r) in bounds.iter().enumerate() {
        let Some(r) = r else { continue };
        for ty in r.y0 / TILE..r.y1.div_ceil(TILE) {
            for tx in r.x0 / TILE..r.x1.div_ceil(TILE) {
                lists[(ty * cols + tx) as usize].push(i as u32);
            }
        }
    }
    Tiles {
        width,
        height,
        cols,
        lists,
        bounds,
    }
}

/// Runs `shade(tile state, tile, splat, pixel in tile, pixel centre)` for every pixel of every
/// listed splat's bounds in each tile, tiles in parallel, splats in draw order; returns each
/// tile's state.
pub fn raster<T: Send>(
    tiles: &Tiles,
    init: impl Fn() -> T + Sync,
    shade: impl Fn(&mut T, Rect, u32, usize, Vec2) + Sync,
) -> Vec<(Rect, T)> {
    tiles
        .lists
        .par_iter()
        .enumerate()
        .map(|(t, list)| {
            let t = t as u32;
            let tile = Rect {
                x0: (t % tiles.cols) * TILE,
                y0: (t / tiles.cols) * TILE,
                x1: ((t % tiles.cols + 1) * TILE).min(tiles.width),
                y1: ((t / tiles.cols + 1) * TILE).min(tiles.height),
            };
            let mut out = init();
            for &i in list {
                // Listed splats have bounds.
                let Some(r) = tiles.bounds[i as usize] else {
                    continue;
                };
                for y in r.y0.max(tile.y0)..r.y1.min(tile.y1) {
                    for x in r.x0.max(tile.x0)..r.x1.min(tile.x1) {
                        let local = ((y - tile.y0) * TILE + (x - tile.x0)) as usize;
                        let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        shade(&mut out, tile, i, local, centre);
                    }
                }
            }
            (tile, out)
        })
        .collect()
}

/// Copies per-tile pixel blocks (`TILE` wide) into one image.
pub fn gather<P: Copy + Default>(tiles: &Tiles, blocks: &[(Rect, Vec<P>)]) -> Vec<P> {
    let w = tiles.width as usize;
    let mut image = vec![P::default(); w * tiles.height as usize];
    for (r, block) in blocks {
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                let local = ((y - r.y0) * TILE + (x - r.x0)) as usize;
                image[y as usize * w + x as usize] = block[local];
            }
        }
    }
    image
}

/// The visibility pass's targets: per pixel, the greatest (nearest) reversed depth of a
/// covering splat's hit pushed back by the tolerance, 0 where nothing covers, and the normal
/// of the first splat that reached it.
pub fn splat_visibility(
    cam: &Camera,
    splats: &[Splat],
    clips: &[SurfaceClip],
    tiles: &Tiles,
) -> Vec<Visible> {
    let eye = Vec3::from(cam.eye);
    let forward = Vec3::from(cam.forward);
    let blocks = raster(
        tiles,
        || vec![Visible::default(); (TILE * TILE) as usize],
        |out, _, i, local, centre| {
            let s = &splats[i as usize];
            let d = pixel_ray(cam, centre);
            let h = splat_hit(s, eye, d);
            if !covers(cam, h, d) || !drawn_keeps(clips, s, eye + h.t * d) {
                return;
            }
            let z = h.t * d.dot(forward);
            let v = view_depth(cam, z + cam.depth_tolerance * s.radius);
            // Depth test `Greater`; the front target is written with the depth.
            if v > out[local].depth {
                out[local] = Visible {
                    depth: v,
                    front: oct_encode(Vec3::from(s.normal)),
                };
            }
        },
    );
    gather(tiles, &blocks)
}

/// What the visibility pass leaves at a pixel: the depth buffer's value and the front
/// target's (the nearest splat's normal, octahedral).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Visible {
    pub depth: f32,
    pub front: u32,
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::SplatVisibility,
        entry: "main",
        workgroup_size: None,
        items: 1,
        run: None,
    },
];
