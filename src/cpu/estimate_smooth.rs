//! Mirror of `wgsl/estimate_smooth.wgsl`: each splat's photon irradiance, the least noisy of its
//! own and planes fitted to its surface's estimates within half of and all of `smooth` search radii
//! that agree with the narrower ones within their noise; chosen once a coverage group, at its
//! leader (first pass), and read by each member at its own place (second pass).
// `!(x > y)` is meant: NaN must fail these tests (a degenerate fit, an unlit splat), as it does
// in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::{UVec2, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::shared::bins::{bin_box_spanning, bin_row, bin_row_count, bin_row_untrimmed};
use crate::shared::lobes::{
    SMOOTH_BUDGET, SMOOTH_CONFIDENCE, SMOOTH_COS_MIN, SMOOTH_DET_MIN,
    SMOOTH_PHOTONS_ENOUGH, SMOOTH_SPAN,
};
use crate::shared::sampling::frame_of;
use crate::types::{BinParams, DepositParams, EmParams, Splat, SplatLight};

pub const WG: u32 = 64;

/// The deposit records `estimate_smooth` finds its neighbours by: list starts and keys.
pub struct Records<'a> {
    pub cell_start: &'a [u32],
    pub keys: &'a [[u32; 2]],
}

/// One scale's weighted sums for a plane fitted to the neighbours' light over the tangent
/// plane (offsets u, v in units of the widest kernel): the moments of [1, u, v] under the
/// weights w and w², and the light's moments under w.
#[derive(Clone, Copy, Default)]
struct Moments {
    m: [f32; 6],
    m2: [f32; 6],
    r: [Vec3; 3],
}

impl Moments {
    fn add(&mut self, w: f32, u: f32, v: f32, e: Vec3) {
        let x = [1.0, u, v];
        let pairs = [
            x[0] * x[0],
            x[0] * x[1],
            x[0] * x[2],
            x[1] * x[1],
            x[1] * x[2],
            x[2] * x[2],
        ];
        for (k, p) in pairs.iter().enumerate() {
            self.m[k] += w * p;
            self.m2[k] += w * w * p;
        }
        for (k, xk) in x.iter().enumerate() {
            self.r[k] += w * xk * e;
        }
    }

    /// The fitted plane (its light at the splat and its slopes along u and v), and how much
    /// more noise its light at the splat has than the weighted mean of the same neighbours
    /// would (independent estimates: the sum of the squared weights of the fit's equivalent
    /// kernel over the mean's); `None` where the neighbours do not span the plane (a line of
    /// splats, too few).
    fn solve(&self) -> Option<([Vec3; 3], f32)> {
        let [m00, m01, m02, m11, m12, m22] = self.m;
        // The cofactors of the symmetric 3 × 3 moment matrix (its adjugate, symmetric too).
        let c = [
            m11 * m22 - m12 * m12,
            m12 * m02 - m01 * m22,
            m01 * m12 - m11 * m02,
        ];
        let det = m00 * c[0] + m01 * c[1] + m02 * c[2];
        if !(det > SMOOTH_DET_MIN * m00 * m00 * m00) {
            return None;
        }
        let (c11, c12, c22) = (
            m00 * m22 - m02 * m02,
            m01 * m02 - m00 * m12,
            m00 * m11 - m01 * m01,
        );
        let [r0, r1, r2] = self.r;
        let plane = [
            (c[0] * r0 + c[1] * r1 + c[2] * r2) / det,
            (c[1] * r0 + c11 * r1 + c12 * r2) / det,
            (c[2] * r0 + c12 * r1 + c22 * r2) / det,
        ];
        let [q00, q01, q02, q11, q12, q22] = self.m2;
        let fit = c[0] * c[0] * q00
            + c[1] * c[1] * q11
            + c[2] * c[2] * q22
            + 2.0 * (c[0] * c[1] * q01 + c[0] * c[2] * q02 + c[1] * c[2] * q12);
        let mean = q00 / (m00 * m00);
        Some((plane, fit / (det * det) / mean))
    }
}

/// A group's choice, at its leader: the plane's light there (xyz) and its scale (w: 0, its
/// own estimate, which the members keep; 1 and 2, the fits), the plane's slopes along the
/// leader's tangent and bitangent per widest kernel (w of the first: 1 where the leader's box
/// held more records than the budget and an even subset of them was fitted).
pub type Choice = [[f32; 4]; 3];

const KEEP: Choice = [[0.0; 4]; 3];

/// The first pass: leader `i`'s choice for its group.
fn choose(
    em: &EmParams,
    deposit: &DepositParams,
    bins: &BinParams,
    splats: &[Splat],
    records: &Records,
    light: &[SplatLight],
    i: usize,
) -> Choice {
    let l = &light[i];
    if !smoothable(l) {
        return KEEP;
    }
    let own = Vec3::from(l.irradiance);
    let level = (own.x + own.y + own.z) / 3.0;
    let s = &splats[i];
    let (center, normal) = (Vec3::from(s.center), Vec3::from(s.normal));
    let f = frame_of(normal);
    let slab = em.slab * s.radius;
    let widest = em.smooth_radii * em.radius;
    let inv_h2 = Vec2::new(4.0, 1.0) / (widest * widest);
    let bx = bin_box_spanning(
        center,
        widest + deposit.reach - em.radius,
        bins,
        SMOOTH_SPAN,
    );
    // Rows empty untrimmed (most of the box on a flat scan) are skipped before trimming.
    let records_of =
        |row: UVec2| records.cell_start[row.y as usize] - records.cell_start[row.x as usize];
    let rows = bin_row_count(&bx);
    let row_lists = |r: u32| {
        let all = bin_row_untrimmed(&bx, r, bins);
        (records_of(all) > 0).then(|| bin_row(&bx, r, bins))
    };
    // Past the budget, every stride-th record of the box (bin order is the order of space, so
    // the subset is even and the same on every run). The untrimmed rows bound the count: the
    // trimmed count is needed only past the budget.
    let mut records_in: u32 = (0..rows)
        .map(|r| records_of(bin_row_untrimmed(&bx, r, bins)))
        .sum();
    if records_in > SMOOTH_BUDGET {
        records_in = (0..rows).filter_map(row_lists).map(records_of).sum();
    }
    let stride = records_in.div_ceil(SMOOTH_BUDGET).max(1);
    let mut scales = [Moments::default(); 2];
    let mut skip = 0;
    for row in (0..rows).filter_map(row_lists) {
        let (first, end) = (
            records.cell_start[row.x as usize],
            records.cell_start[row.y as usize],
        );
        let mut k = first + skip;
        while k < end {
            let j = records.keys[k as usize][0] as usize;
            k += stride;
            let n = &splats[j];
            let d = Vec3::from(n.center) - center;
            let w = (Vec2::ONE - d.dot(d) * inv_h2).max(Vec2::ZERO);
            if w.y == 0.0
                || n.object != s.object
                || d.dot(normal).abs() > slab
                || Vec3::from(n.normal).dot(normal) < SMOOTH_COS_MIN
            {
                continue;
            }
            let (u, v) = (d.dot(f.t) / widest, d.dot(f.b) / widest);
            let e = Vec3::from(light[j].irradiance);
            scales[0].add(w.x, u, v, e);
            scales[1].add(w.y, u, v, e);
        }
        // An empty row leaves k at first + skip: the skip carries over unchanged.
        skip = k - end;
    }
    let sigma = level / (l.photons as f32).sqrt();
    let mut lo = level - SMOOTH_CONFIDENCE * sigma;
    let mut hi = level + SMOOTH_CONFIDENCE * sigma;
    let (mut chosen, mut narrowest) = (KEEP, SMOOTH_CONFIDENCE * sigma);
    for (k, moments) in scales.iter().enumerate() {
        let Some((plane, inflation)) = moments.solve() else {
            break;
        };
        let e = plane[0];
        let ratio = em.smooth_radii * (k + 1) as f32 * 0.5;
        let m = (e.x + e.y + e.z) / 3.0;
        let half_width =
            SMOOTH_CONFIDENCE * sigma * (inflation / (1.0 + 0.75 * ratio * ratio)).sqrt();
        lo = lo.max(m - half_width);
        hi = hi.min(m + half_width);
        if lo > hi {
            break;
        }
        // A fit noisier than the choice so far (one-sided neighbours) is no better.
        if half_width < narrowest {
            chosen = plane.map(|p| p.extend(0.0).into());
            chosen[0][3] = (k + 1) as f32;
            narrowest = half_width;
        }
    }
    chosen[1][3] = f32::from(u8::from(stride > 1));
    chosen
}

/// Whether a splat's estimate is one to smooth: lit by photons (not by the photon fit's
/// lobes, which carry their own irradiance), above zero and with fewer than
/// `SMOOTH_PHOTONS_ENOUGH` photons.
fn smoothable(l: &SplatLight) -> bool {
    let level = (l.irradiance[0] + l.irradiance[1] + l.irradiance[2]) / 3.0;
    l.photons > 0 && l.lobes == 0 && level > 0.0 && l.photons < SMOOTH_PHOTONS_ENOUGH
}

/// The second pass for splat `i`, its group led by `leader`: its irradiance and scale, the
/// group's plane read at the splat's place in the leader's tangent plane.
fn read_choice(
    em: &EmParams,
    splats: &[Splat],
    (i, leader): (usize, usize),
    choice: &Choice,
    own: [f32; 3],
) -> ([f32; 3], usize) {
    let (s, l) = (&splats[i], &splats[leader]);
    // A member of another object than its leader's (a light's disk just below the ceiling)
    // keeps its own: the leader's plane is of its own surface.
    let scale = choice[0][3] as usize;
    if scale == 0 || s.object != l.object {
        return (own, 0);
    }
    let d = Vec3::from(s.center) - Vec3::from(l.center);
    let f = frame_of(Vec3::from(l.normal));
    let widest = em.smooth_radii * em.radius;
    let (u, v) = (d.dot(f.t) / widest, d.dot(f.b) / widest);
    let [e, du, dv] = choice.map(|c| Vec4::from(c).truncate());
    ((e + u * du + v * dv).into(), scale)
}

/// The first pass (`main`): each of `em.active_count` groups' choice, at its leader
/// (`cover`'s words after the splats').
#[allow(clippy::too_many_arguments)]
pub fn estimate_smooth(
    em: &EmParams,
    deposit: &DepositParams,
    bins: &BinParams,
    splats: &[Splat],
    records: &Records,
    (light, cover): (&[SplatLight], &[u32]),
    smoothed: &mut [Choice],
    groups: u32,
) {
    let invocations = (groups * WG) as usize;
    let leaders = &cover[em.splat_count as usize..];
    let count = invocations.min(em.active_count as usize);
    smoothed[..count]
        .par_iter_mut()
        .zip(&leaders[..count])
        .for_each(|(out, &leader)| {
            *out = choose(em, deposit, bins, splats, records, light, leader as usize)
        });
}

/// The second pass (`apply`): each smoothable splat's irradiance read from its group's choice,
/// counted by scale, and by whether its group fitted a subset.
pub fn apply(
    em: &EmParams,
    splats: &[Splat],
    (light, cover): (&mut [SplatLight], &[u32]),
    smoothed: &[Choice],
    counters: &mut [u32; 4],
    groups: u32,
) {
    let invocations = (groups * WG) as usize;
    let leaders = &cover[em.splat_count as usize..];
    let count = invocations.min(em.splat_count as usize);
    let counts = light[..count]
        .par_iter_mut()
        .zip(&cover[..count])
        .enumerate()
        .filter(|(_, (l, _))| smoothable(l))
        .map(|(i, (l, &g))| {
            let choice = &smoothed[g as usize];
            let leader = leaders[g as usize] as usize;
            let (e, scale) = read_choice(em, splats, (i, leader), choice, l.irradiance);
            l.irradiance = e;
            let mut counts = [0u32; 4];
            counts[scale] = 1;
            counts[3] = choice[1][3] as u32;
            counts
        })
        .reduce(|| [0; 4], |a, b| std::array::from_fn(|k| a[k] + b[k]));
    for (c, n) in counters.iter_mut().zip(counts) {
        *c += n;
    }
}

/// The executor's entry of `main`: `estimate_smooth`'s bindings, unpacked in the order its
/// WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let deposit = b.param(1)?;
    let bins = b.param(2)?;
    let splats = b.get(3)?;
    let cell_start = b.get(4)?;
    let keys = b.get(5)?;
    let light = b.get(6)?;
    let mut smoothed = b.get_mut(7)?;
    let cover = b.get(9)?;
    let records = Records {
        cell_start: &cell_start,
        keys: view(&keys),
    };
    let on = (view(&light), view(&cover));
    let (splats, smoothed) = (view(&splats), view_mut(&mut smoothed));
    estimate_smooth(&em, &deposit, &bins, splats, &records, on, smoothed, groups);
    Ok(())
}

/// The executor's entry of `apply`.
pub fn dispatch_apply(b: &Bindings, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let splats = b.get(3)?;
    let mut light = b.get_mut(6)?;
    let smoothed = b.get(7)?;
    let mut counters = b.get_mut(8)?;
    let cover = b.get(9)?;
    let counters = b.counters::<4>(&mut counters)?;
    let on = (view_mut(&mut light), view(&cover));
    apply(&em, view(&splats), on, view(&smoothed), counters, groups);
    Ok(())
}

/// This file's rows of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::EstimateSmooth,
        entry: "main",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
    MirrorRow {
        stage: Stage::EstimateSmooth,
        entry: "apply",
        workgroup_size: Some(WG),
        items: 1,
        run: Some(Mirror::Plain(dispatch_apply)),
    },
];
