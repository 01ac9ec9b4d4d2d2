//! Twin of `wgsl/shared/splat.wgsl`: a splat's triangle, a pixel's view ray, the ray–disk hit
//! with its radial weight, the reversed depth, and a lobe's width in the form the shading takes.
// `!(x < y)` is meant: NaN must fail these tests, as it does in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Vec2, Vec3, Vec4};

use super::lobes::FAMILY_WARD;
use super::sampling::frame_of;
use crate::types::{
    Camera, LOD_LEVELS, LodSpread, Material, Splat, SplatChunk, SplatLod, SurfaceClip,
};

pub const KERNEL_SHARPNESS: f32 = 2.0;

/// A fragment blends only where its splat's normal is within 60° of the normal of the pixel's
/// nearest splat (`front`, octahedral, the visibility pass's second output); see
/// `wgsl/shared/splat.wgsl`.
pub const FRONT_COS_MIN: f32 = 0.5;

pub fn same_surface(front: u32, n: Vec3) -> bool {
    super::octahedral::oct_decode(front).dot(n) >= FRONT_COS_MIN
}
pub const SHADOW_RAY_BUDGET: u32 = 16_384;

/// Light terms a frame shows (`ShadeParams::show`): direct diffuse and specular (shadow rays),
/// indirect diffuse (total irradiance) and specular (the lobes).
pub const SHOW_DIRECT_DIFFUSE: u32 = 1;
pub const SHOW_DIRECT_SPECULAR: u32 = 2;
pub const SHOW_INDIRECT_DIFFUSE: u32 = 4;
pub const SHOW_INDIRECT_SPECULAR: u32 = 8;
pub const SHOW_ALL: u32 = 15;

pub const SPLAT_CORNERS: u32 = 3;
const SQRT_3: f32 = 1.732_050_8;

/// Splats one instance of the raster passes' draw holds (see the WGSL): the draw is
/// `SPLAT_CORNERS × SPLATS_PER_INSTANCE` vertices times `instances(count)`.
pub const SPLATS_PER_INSTANCE: u32 = 32;

/// The instances that draw `count` splats.
pub fn instances(count: u32) -> u32 {
    count.div_ceil(SPLATS_PER_INSTANCE)
}

/// Level of detail of moving frames (`Camera::lod`): the merge tree's levels above the splats
/// themselves (`lod`); see `wgsl/shared/splat.wgsl`.
pub const LOD_MAX_LEVEL: u32 = 5;

/// The radius splat `s` is drawn with this frame at its `level` (`lod_level`): that level's
/// disk (`lod`), its own radius with the level of detail off, or 0 where its parent's disk may
/// project within it too (and then covers it).
pub fn lod_radius(cam: &Camera, s: &Splat, lod: &SplatLod, level: u32) -> f32 {
    if !(cam.lod > 0.0) {
        return s.radius;
    }
    // The parent lies at least `parent_gap` nearer: if its disk fits even there, it fits.
    let z = lod_depth(cam, s);
    if level == lod.top
        && lod.parent_extent > 0.0
        && lod_fits(cam, lod.parent_extent, z - lod.parent_gap)
    {
        return 0.0;
    }
    match level {
        0 => s.radius,
        k => lod.extent[k as usize - 1],
    }
}

/// The level of the merge tree splat `s` is drawn at this frame: the coarsest of its levels
/// whose disk projects within `cam.lod` pixels; 0 (its own disk) with the level of detail off.
pub fn lod_level(cam: &Camera, s: &Splat, lod: &SplatLod) -> u32 {
    if !(cam.lod > 0.0) {
        return 0;
    }
    let z = lod_depth(cam, s);
    let mut level = 0;
    for k in 1..=lod.top.min(LOD_MAX_LEVEL) {
        if lod_fits(cam, lod.extent[k as usize - 1], z) {
            level = k;
        }
    }
    level
}

/// The depth of splat `s`'s centre along the view, as the level of detail measures it.
fn lod_depth(cam: &Camera, s: &Splat) -> f32 {
    (Vec3::from(s.center) - Vec3::from(cam.eye)).dot(Vec3::from(cam.forward))
}

/// `LodSpread`'s unit: a byte of 255 is this much Ward roughness.
pub const LOD_SPREAD_SCALE: f32 = 255.0;

/// The word of `spread` for `level` of the merge tree (`LodSpread`); 0 at level 0, the splat
/// itself.
pub fn lod_word(spread: &LodSpread, level: u32) -> u32 {
    match level {
        0 => 0,
        k => spread[k as usize - 1],
    }
}

/// The Ward roughness a glossy splat of roughness `alpha` is shaded with where it is drawn at
/// the level whose word is `word` (`lod_word`): its own, widened by the spread of the normals
/// its disk stands for there (`lod::normal_spread`), as the slopes' variances add.
pub fn lod_roughness(alpha: f32, word: u32) -> f32 {
    let widen = (word & 0xff) as f32 / LOD_SPREAD_SCALE;
    (alpha * alpha + widen * widen).sqrt()
}

/// The normal a glossy splat of normal `own` is shaded with at the level whose word is `word`:
/// the mean direction of the normals its disk stands for, where they spread; else its own.
pub fn lod_normal(word: u32, own: Vec3) -> Vec3 {
    if word & 0xff == 0 {
        return own;
    }
    let (x, y) = (((word >> 8) & 0xfff) << 4, (word >> 20) << 4);
    super::octahedral::oct_decode(x | (y << 16))
}

/// Whether a disk of radius `extent` at `depth` projects within the level of detail. Products,
/// no quotient, so that the device and the mirror decide alike.
pub fn lod_fits(cam: &Camera, extent: f32, depth: f32) -> bool {
    depth > cam.near && extent * cam.size[1] <= cam.lod * 2.0 * cam.tan_y * depth
}

/// The radius splat `s` is drawn with in a frame of baked direct light (`splat_select`) at
/// its `level` (`lod_level`): that level's disk where the level of detail is on, 0 where it
/// faces away, lies outside the view or its parent's disk stands in for it.
pub fn drawn_radius(cam: &Camera, s: &Splat, lod: &SplatLod, level: u32) -> f32 {
    let mut s = *s;
    if cam.lod > 0.0 {
        s.radius = lod_radius(cam, &s, lod, level);
    }
    match faces_camera(&s, Vec3::from(cam.eye)) && s.radius > 0.0 && in_view(cam, &s) {
        true => s.radius,
        false => 0.0,
    }
}

const _: () = assert!(LOD_LEVELS == LOD_MAX_LEVEL as usize + 1);

/// The levels of chunk `ch` whose splats a frame visits (bit t: those whose top level is t), or
/// of a node of chunks (`lod::LodTree::nodes`) whose subtree's splats it may visit: not levels
/// it holds none of, not those that lie outside the view, and with the level of detail on, not
/// those whose parents' disks project within it even at the chunk's nearest depth, and their
/// own top-level disks too (then `lod_radius` gives every one of them 0). Conservative: a splat
/// that `drawn_radius` draws is always visited (`in_view`'s test holds for a sphere that holds
/// its splats' with the margin its gradient asks for, a small slack for rounding).
pub fn chunk_visits(cam: &Camera, ch: &SplatChunk) -> u32 {
    let c = Vec3::from(ch.center) - Vec3::from(cam.eye);
    let z = c.dot(Vec3::from(cam.forward));
    let d = ch.centre_reach;
    let nearest = z - d - 1e-4 * (z.abs() + d);
    let mut visits = 0;
    for t in 0..LOD_LEVELS {
        // A level it holds no splat of is never visited, so that a node whose subtree holds
        // none rules it out for all of it.
        if ch.level(t).is_empty() {
            continue;
        }
        // Level t's splats are drawn no wider than their disk at level t.
        let r = 2.0 * ch.level_fit[t];
        let slack = 1e-4 * (z.abs() + d + r);
        let edge = |axis: [f32; 3], tan: f32, size: f32| {
            let a = tan * (1.0 + 2.0 / size);
            c.dot(Vec3::from(axis)).abs() - a * z
                <= r * (1.0 + tan * tan).sqrt() + d * (1.0 + a * a).sqrt() + slack
        };
        let shown = z + d + slack >= cam.near - r
            && edge(cam.right, cam.tan_x, cam.size[0])
            && edge(cam.up, cam.tan_y, cam.size[1]);
        let covered = cam.lod > 0.0
            && ch.parent_fit[t] > 0.0
            && (t == 0 || lod_fits(cam, ch.level_fit[t], nearest))
            && lod_fits(cam, ch.parent_fit[t], nearest - ch.parent_gap[t]);
        if shown && !covered {
            visits |= 1 << t;
        }
    }
    visits
}

pub fn splat_corner(s: &Splat, i: u32) -> Vec3 {
    let f = frame_of(Vec3::from(s.normal));
    let (x, y) = match i {
        0 => (0.0, 2.0),
        1 => (-SQRT_3, -1.0),
        _ => (SQRT_3, -1.0),
    };
    Vec3::from(s.center) + s.radius * (x * f.t + y * f.b)
}

pub fn faces_camera(s: &Splat, eye: Vec3) -> bool {
    Vec3::from(s.normal).dot(eye - Vec3::from(s.center)) > 0.0
}

/// Whether splat `s` may cover a pixel of the view (a conservative frustum test; see the WGSL).
pub fn in_view(cam: &Camera, s: &Splat) -> bool {
    let v = Vec3::from(s.center) - Vec3::from(cam.eye);
    let r = 2.0 * s.radius;
    let z = v.dot(Vec3::from(cam.forward));
    let x_edge = cam.tan_x * (1.0 + 2.0 / cam.size[0]) * z;
    let y_edge = cam.tan_y * (1.0 + 2.0 / cam.size[1]) * z;
    z >= cam.near - r
        && v.dot(Vec3::from(cam.right)).abs() - x_edge <= r * (1.0 + cam.tan_x * cam.tan_x).sqrt()
        && v.dot(Vec3::from(cam.up)).abs() - y_edge <= r * (1.0 + cam.tan_y * cam.tan_y).sqrt()
}

pub fn clip_position(cam: &Camera, p: Vec3) -> Vec4 {
    let v = p - Vec3::from(cam.eye);
    let z = v.dot(Vec3::from(cam.forward));
    // The jitter moves the image under the pixel grid, so that the pixel centre the
    // rasterizer samples lies on the jittered ray `pixel_ray` casts.
    let shift = Vec2::from(cam.jitter) * 2.0 / Vec2::from(cam.size);
    Vec4::new(
        v.dot(Vec3::from(cam.right)) / cam.tan_x - shift.x * z,
        v.dot(Vec3::from(cam.up)) / cam.tan_y + shift.y * z,
        cam.near,
        z,
    )
}

pub fn view_depth(cam: &Camera, z: f32) -> f32 {
    cam.near / z
}

pub fn pixel_ray(cam: &Camera, pixel: Vec2) -> Vec3 {
    let size = Vec2::from(cam.size);
    let pixel = pixel + Vec2::from(cam.jitter);
    let ndc = Vec2::new(pixel.x / size.x * 2.0 - 1.0, 1.0 - pixel.y / size.y * 2.0);
    (Vec3::from(cam.forward)
        + (ndc.x * cam.tan_x) * Vec3::from(cam.right)
        + (ndc.y * cam.tan_y) * Vec3::from(cam.up))
    .normalize()
}

/// Where world point `p` lies in the image of `cam` without its jitter: the point in pixels
/// (`pixel_ray(cam, xy - jitter)` points at `p`) and the view depth z (z <= 0: at or behind
/// the eye, and xy means nothing).
pub fn project_point(cam: &Camera, p: Vec3) -> Vec3 {
    let v = p - Vec3::from(cam.eye);
    let z = v.dot(Vec3::from(cam.forward));
    let ndc = Vec2::new(
        v.dot(Vec3::from(cam.right)) / cam.tan_x,
        v.dot(Vec3::from(cam.up)) / cam.tan_y,
    ) / z;
    Vec3::new(
        (ndc.x * 0.5 + 0.5) * cam.size[0],
        (0.5 - ndc.y * 0.5) * cam.size[1],
        z,
    )
}

#[derive(Clone, Copy, Debug)]
pub struct SplatHit {
    pub t: f32,
    pub q: f32,
}

pub fn splat_hit(s: &Splat, o: Vec3, d: Vec3) -> SplatHit {
    let n = Vec3::from(s.normal);
    let c = Vec3::from(s.center);
    let t = n.dot(c - o) / n.dot(d);
    let v = o + t * d - c;
    SplatHit {
        t,
        q: v.dot(v) / (s.radius * s.radius),
    }
}

pub fn covers(cam: &Camera, h: SplatHit, d: Vec3) -> bool {
    h.q <= 1.0 && h.t * d.dot(Vec3::from(cam.forward)) >= cam.near
}

/// Surfaces whose clips the drawing passes hold, the last entry zero (`DRAWN_CLIPS` in
/// `wgsl/shared/drawn_clip.wgsl`): a later surface is drawn unclipped.
pub const DRAWN_CLIPS: usize = 64;

/// Twin of `wgsl/shared/drawn_clip.wgsl`: whether a pixel's hit at `p` on splat `s` is drawn,
/// where the rows of its surface's clip (`clips[s.object]`; none past the end or past
/// `DRAWN_CLIPS` − 1) that cut its disk keep it.
pub fn drawn_keeps(clips: &[SurfaceClip], s: &Splat, p: Vec3) -> bool {
    let surface = s.object as usize;
    let Some(c) = clips.get(surface).filter(|_| surface < DRAWN_CLIPS - 1) else {
        return true;
    };
    let q = p.extend(1.0);
    c.drawn_rows(s)
        .iter()
        .all(|r| Vec4::from(*r).dot(q).abs() <= 1.0)
}

pub fn splat_weight(q: f32) -> f32 {
    (-KERNEL_SHARPNESS * q).exp()
}

pub fn lobe_beta2(family: u32, sharpness: f32) -> f32 {
    (if family == FAMILY_WARD { 1.0 } else { 0.5 }) / sharpness
}

/// The compute splatter's screen tiles: `TILE` × `TILE` pixels, one workgroup each.
pub const TILE: u32 = 8;

/// The tiles whose pixel centres splat `s`'s triangle may cover, `(x0, y0, x1, y1)` inclusive;
/// none when `x0 > x1`.
pub fn tile_rect(cam: &Camera, s: &Splat, tiles_x: u32, tiles_y: u32) -> [u32; 4] {
    let none = [1, 0, 0, 0];
    if !faces_camera(s, Vec3::from(cam.eye)) {
        return none;
    }
    let mut lo = Vec2::splat(3.0e38);
    let mut hi = Vec2::splat(-3.0e38);
    let mut behind = 0;
    for k in 0..SPLAT_CORNERS {
        let c = clip_position(cam, splat_corner(s, k));
        if !(c.w >= cam.near) {
            behind += 1;
            continue;
        }
        let ndc = Vec2::new(c.x, c.y) / c.w;
        let p = Vec2::new(
            (ndc.x * 0.5 + 0.5) * cam.size[0],
            (0.5 - ndc.y * 0.5) * cam.size[1],
        );
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if behind == SPLAT_CORNERS {
        return none;
    }
    let last = Vec2::new((tiles_x * TILE) as f32 - 1.0, (tiles_y * TILE) as f32 - 1.0);
    if behind > 0 {
        lo = Vec2::ZERO;
        hi = last + 0.5;
    }
    let first = (lo - 0.5 - 1e-3).ceil().max(Vec2::ZERO);
    let end = (hi - 0.5 + 1e-3).floor().min(last);
    if first.x > end.x || first.y > end.y {
        return none;
    }
    [
        first.x as u32 / TILE,
        first.y as u32 / TILE,
        end.x as u32 / TILE,
        end.y as u32 / TILE,
    ]
}

/// `hit_albedo` in WGSL: what a ray that meets splat `s` brings back per unit of its
/// irradiance, times π: its diffuse albedo, and a glossy disk's specular albedo as if it spread
/// that light evenly.
pub fn hit_albedo(s: &Splat, m: &Material) -> Vec3 {
    Vec3::from(s.diffuse) + Vec3::from(m.specular)
}
