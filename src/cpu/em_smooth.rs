//! Mirror of `wgsl/em_smooth.wgsl`: each splat's photon irradiance, the least noisy of its own
//! and planes fitted to its surface's estimates within half of and all of `smooth` search
//! radii that agree with the narrower ones within their noise.
// `!(x > y)` is meant: NaN must fail these tests (a degenerate fit, an unlit splat), as it does
// in the WGSL twin.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::shared::bins::{bin_box_spanning, bin_row, bin_row_count};
use crate::shared::lobes::{
    EM_SMOOTH_APPLY, SMOOTH_BUDGET, SMOOTH_CONFIDENCE, SMOOTH_COS_MIN, SMOOTH_DET_MIN,
    SMOOTH_PHOTONS_ENOUGH, SMOOTH_SPAN,
};
use crate::shared::sampling::frame_of;
use crate::types::{BinParams, DepositParams, EmParams, Splat, SplatLight};

pub const WG: u32 = 64;

/// The deposit records `em_smooth` finds its neighbours by: list starts and keys.
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

    /// The fitted plane's light at the splat, and how much more noise it has than the
    /// weighted mean of the same neighbours would (independent estimates: the sum of the
    /// squared weights of the fit's equivalent kernel over the mean's); `None` where the
    /// neighbours do not span the plane (a line of splats, too few).
    fn solve(&self) -> Option<(Vec3, f32)> {
        let [m00, m01, m02, m11, m12, m22] = self.m;
        // The first row of the cofactors of the symmetric 3 × 3 moment matrix.
        let c = [
            m11 * m22 - m12 * m12,
            m12 * m02 - m01 * m22,
            m01 * m12 - m11 * m02,
        ];
        let det = m00 * c[0] + m01 * c[1] + m02 * c[2];
        if !(det > SMOOTH_DET_MIN * m00 * m00 * m00) {
            return None;
        }
        let e = (c[0] * self.r[0] + c[1] * self.r[1] + c[2] * self.r[2]) / det;
        let [q00, q01, q02, q11, q12, q22] = self.m2;
        let fit = c[0] * c[0] * q00
            + c[1] * c[1] * q11
            + c[2] * c[2] * q22
            + 2.0 * (c[0] * c[1] * q01 + c[0] * c[2] * q02 + c[1] * c[2] * q12);
        let mean = q00 / (m00 * m00);
        Some((e, fit / (det * det) / mean))
    }
}

/// How the first pass ended for a splat.
enum Choice {
    /// No photons (or lobes of its own): not counted.
    Unlit,
    /// Irradiance and scale (0: its own, 1 and 2: the fits), and whether its box held more
    /// records than the budget (an even subset of them was fitted).
    Chosen([f32; 4], bool),
}

/// The first pass: splat `i`'s chosen irradiance and scale.
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
    let own = Vec3::from(l.irradiance);
    let keep = [own.x, own.y, own.z, 0.0];
    if l.photons == 0 || l.lobes > 0 {
        return Choice::Unlit;
    }
    let level = (own.x + own.y + own.z) / 3.0;
    if !(level > 0.0) || l.photons >= SMOOTH_PHOTONS_ENOUGH {
        return Choice::Chosen(keep, false);
    }
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
    let mut scales = [Moments::default(); 2];
    // Past the budget, every stride-th record of the box (bin order is the order of space, so
    // the subset is even and the same on every run).
    let rows = bin_row_count(&bx);
    let records_in = (0..rows)
        .map(|r| {
            let row = bin_row(&bx, r, bins);
            records.cell_start[row.y as usize] - records.cell_start[row.x as usize]
        })
        .sum::<u32>();
    let stride = records_in.div_ceil(SMOOTH_BUDGET).max(1);
    let mut skip = 0;
    for r in 0..rows {
        let row = bin_row(&bx, r, bins);
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
        skip = k - end;
    }
    let sigma = level / (l.photons as f32).sqrt();
    let mut lo = level - SMOOTH_CONFIDENCE * sigma;
    let mut hi = level + SMOOTH_CONFIDENCE * sigma;
    let (mut chosen, mut narrowest) = (keep, SMOOTH_CONFIDENCE * sigma);
    for (k, moments) in scales.iter().enumerate() {
        let Some((e, inflation)) = moments.solve() else {
            break;
        };
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
            (chosen, narrowest) = ([e.x, e.y, e.z, (k + 1) as f32], half_width);
        }
    }
    Choice::Chosen(chosen, stride > 1)
}

#[allow(clippy::too_many_arguments)]
pub fn em_smooth(
    em: &EmParams,
    deposit: &DepositParams,
    bins: &BinParams,
    splats: &[Splat],
    records: &Records,
    light: &mut [SplatLight],
    smoothed: &mut [[f32; 4]],
    counters: &mut [u32; 4],
    groups: u32,
) {
    let count = (groups * WG).min(em.splat_count) as usize;
    if em.flags & EM_SMOOTH_APPLY != 0 {
        light[..count]
            .par_iter_mut()
            .zip(&smoothed[..count])
            .filter(|(l, _)| l.photons > 0 && l.lobes == 0)
            .for_each(|(l, e)| l.irradiance = [e[0], e[1], e[2]]);
        return;
    }
    let light = &*light;
    let counts = smoothed[..count]
        .par_iter_mut()
        .enumerate()
        .map(|(i, out)| {
            let own = light[i].irradiance;
            let mut counts = [0u32; 4];
            *out = match choose(em, deposit, bins, splats, records, light, i) {
                Choice::Unlit => [own[0], own[1], own[2], 0.0],
                Choice::Chosen(e, subset) => {
                    counts[e[3] as usize] = 1;
                    counts[3] = u32::from(subset);
                    e
                }
            };
            counts
        })
        .reduce(|| [0; 4], |a, b| std::array::from_fn(|k| a[k] + b[k]));
    for (c, n) in counters.iter_mut().zip(counts) {
        *c += n;
    }
}

/// The executor's entry: `em_smooth`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let deposit = b.param(1)?;
    let bins = b.param(2)?;
    let splats = b.get(3)?;
    let cell_start = b.get(4)?;
    let keys = b.get(5)?;
    let mut light = b.get_mut(6)?;
    let mut smoothed = b.get_mut(7)?;
    let mut counters = b.get_mut(8)?;
    let counters = b.counters::<4>(&mut counters)?;
    let records = Records {
        cell_start: &cell_start,
        keys: view(&keys),
    };
    em_smooth(
        &em,
        &deposit,
        &bins,
        view(&splats),
        &records,
        view_mut(&mut light),
        view_mut(&mut smoothed),
        counters,
        groups,
    );
    Ok(())
}
