//! Mirror of `wgsl/em_fit.wgsl`: each workgroup's invocations run one after another between
//! its reductions, with their private state in `Invocation` and the workgroup's photon cache
//! in `Cache`; workgroups run in parallel (each writes only its own splat).
//! `EM_SUBGROUP_REDUCE` in the flags selects the sum order of the `subgroups` variant.

use super::{Mirror, MirrorRow};
use crate::shaders::Stage;
use super::bindings::{Bindings, view, view_mut};
use crate::error::Result;
use glam::Vec3;
use rayon::prelude::*;

use super::fit_select::FIT_BIT;
use crate::shared::bins::{
    BinBox, SURFACE_COS_MIN, bin_box, bin_row, bin_row_count, photon_weight,
};
use crate::shared::lobes::*;
use crate::shared::octahedral::{oct_decode, surface_decode};
use crate::shared::sampling::frame_of;
use crate::types::{BinParams, BinnedPhoton, EmParams, Lobe, Splat, SplatLight};

/// Photons cached per workgroup (`CACHE_SLOTS / workgroup_size` per invocation).
pub const CACHE_SLOTS: u32 = 512;
/// Cached photons per invocation whose responsibilities sparse EM keeps.
const FROZEN: u32 = 8;
/// The slot of a photon that is not cached.
const NOT_CACHED: u32 = u32::MAX;
/// The log weight of a dropped lobe.
const DROPPED_LOG: f32 = -3.0e38;
/// Floor of 1 − h in a loss sum.
const REST_MIN: f32 = 1e-30;
const SUM_LOG: usize = 0;
const SUM_WEIGHT: usize = 1;
const SUM_COUNT: usize = 2;
const SUM_RGB: usize = 3;
const LOBE_SUMS: usize = 6;
const LOBE_SLOTS: usize = 6;
const LOBE_LOSS: usize = 5;
const SUMS: usize = 54;
const PASS_EM: u32 = 0;
const PASS_FINAL: u32 = 1;
const L: usize = MAX_LOBES as usize;
const F: usize = FROZEN as usize;
/// Most invocations per workgroup (`MAX_WG` in WGSL).
const MAX_WG: usize = 32;

/// The read-only inputs of a dispatch (bindings 0–6).
struct Inputs<'a> {
    em: &'a EmParams,
    bins: &'a BinParams,
    cell_start: &'a [u32],
    bin_geom: &'a [BinnedPhoton],
    bin_power: &'a [[f32; 4]],
}

/// The splat and the mixture: the same in every invocation of a workgroup.
#[derive(Clone, Copy, Default)]
struct Splat1 {
    center: Vec3,
    normal: Vec3,
    slab: f32,
    lobe_count: u32,
    mix_axis: [Vec3; L],
    mix_sharpness: [f32; L],
    mix_weight: [f32; L],
    mix_mirror: [Vec3; L],
    mix_log: [f32; L],
    /// The lobes not dropped by pruning, one bit each.
    alive: u32,
    /// The candidate stride s (`em_fit.wgsl`, "Bounded cost"); 1 visits every candidate.
    stride: u32,
    /// With gathered samples, the splat's first.
    sample_first: u32,
}

/// The workgroup's photon cache (workgroup memory in WGSL): slot c of invocation t at
/// c · workgroup_size + t.
struct Cache {
    dir: Vec<[f32; 4]>,
    index: Vec<u32>,
}

/// One invocation's private state.
#[derive(Clone, Copy)]
struct Invocation {
    resp: [f32; L],
    stat: [f32; L],
    acc: [f32; SUMS],
    frozen_h: [[f32; L]; F],
    frozen_hx: [[f32; L]; F],
    frozen_mask: u32,
    cached: u32,
    streaming: bool,
    resume_row: u32,
    resume_j: u32,
    resume_offset: u32,
}

impl Default for Invocation {
    fn default() -> Self {
        Invocation {
            resp: [0.0; L],
            stat: [0.0; L],
            acc: [0.0; SUMS],
            frozen_h: [[0.0; L]; F],
            frozen_hx: [[0.0; L]; F],
            frozen_mask: 0,
            cached: 0,
            streaming: false,
            resume_row: 0,
            resume_j: 0,
            resume_offset: 0,
        }
    }
}

/// Invocation `lid`'s first candidate of a row: (offset + position) = lid · stride mod
/// wg · stride.
fn first_in_row(wg: u32, stride: u32, begin: u32, offset: u32, lid: u32) -> u32 {
    let step = wg * stride;
    begin + (lid * stride + step - offset % step) % step
}

struct Candidate {
    ok: bool,
    dir: Vec3,
    weight: f32,
}

/// The splat's candidate rows: its bin rows, or the one row of its gathered samples.
fn row_count(inp: &Inputs, bx: &BinBox) -> u32 {
    if inp.em.gathered > 0 {
        1
    } else {
        bin_row_count(bx)
    }
}

/// Candidates `[begin, end)` of row `r`.
fn row_span(inp: &Inputs, sp: &Splat1, bx: &BinBox, r: u32) -> (u32, u32) {
    if inp.em.gathered > 0 {
        return (sp.sample_first, sp.sample_first + inp.em.gathered);
    }
    let row = bin_row(bx, r, inp.bins);
    (
        inp.cell_start[row.x as usize],
        inp.cell_start[row.y as usize],
    )
}

fn accept(inp: &Inputs, sp: &Splat1, j: u32) -> Candidate {
    if inp.em.gathered > 0 {
        let sample = inp.bin_power[j as usize];
        let weight = photon_weight(sample) * sp.stride as f32;
        return Candidate {
            ok: weight > 0.0,
            dir: oct_decode(sample[3].to_bits()),
            weight,
        };
    }
    let g = inp.bin_geom[j as usize];
    let d = Vec3::from(g.position) - sp.center;
    let mut c = Candidate {
        ok: d.dot(d) <= inp.em.radius2 && d.dot(sp.normal).abs() <= sp.slab,
        dir: Vec3::ZERO,
        weight: 0.0,
    };
    if c.ok {
        let power = inp.bin_power[j as usize];
        c.dir = oct_decode(g.direction);
        c.ok = c.dir.dot(sp.normal) > 0.0
            && surface_decode(power[3]).dot(sp.normal) >= SURFACE_COS_MIN;
        c.weight = photon_weight(power) * sp.stride as f32;
    }
    c
}

fn prepare_mixture(em: &EmParams, sp: &mut Splat1) {
    for k in 0..sp.lobe_count as usize {
        sp.mix_mirror[k] = mirror_axis(sp.normal, sp.mix_axis[k]);
        sp.mix_log[k] = sp.mix_weight[k].max(1e-35).ln().max(LOG_WEIGHT_MIN)
            + lobe_log_norm(em.family, sp.normal, sp.mix_axis[k], sp.mix_sharpness[k]);
        if sp.alive & (1 << k) == 0 {
            sp.mix_log[k] = DROPPED_LOG;
        }
    }
}

fn e_step(
    em: &EmParams,
    sp: &Splat1,
    v: &mut Invocation,
    w: Vec3,
    slot: u32,
    sparse: bool,
    full: bool,
) -> f32 {
    let use_frozen = sparse && !full && slot < FROZEN;
    let s_ = slot as usize;
    v.frozen_mask = 0;
    let mut frozen_sum = 0.0;
    let mut m = -3.0e38f32;
    for k in 0..sp.lobe_count as usize {
        if use_frozen && v.frozen_h[s_][k] < SPARSE_THRESHOLD {
            v.frozen_mask |= 1 << k;
            frozen_sum += v.frozen_h[s_][k];
            continue;
        }
        v.stat[k] = lobe_stat(em.family, sp.normal, sp.mix_axis[k], sp.mix_mirror[k], w);
        v.resp[k] = sp.mix_log[k] + lobe_exponent(em.family, sp.mix_sharpness[k], v.stat[k]);
        m = m.max(v.resp[k]);
    }
    let mut s = 0.0;
    for k in 0..sp.lobe_count as usize {
        if v.frozen_mask & (1 << k) == 0 {
            v.resp[k] = (v.resp[k] - m).exp();
            s += v.resp[k];
        }
    }
    let scale = (1.0 - frozen_sum) / s;
    for k in 0..sp.lobe_count as usize {
        if v.frozen_mask & (1 << k) != 0 {
            v.resp[k] = v.frozen_h[s_][k];
            v.stat[k] = v.frozen_hx[s_][k];
        } else {
            v.resp[k] *= scale;
            if sparse && slot < FROZEN {
                v.frozen_h[s_][k] = v.resp[k];
                v.frozen_hx[s_][k] = v.resp[k] * v.stat[k];
            }
        }
    }
    m + s.ln()
}

#[allow(clippy::too_many_arguments)]
fn absorb(
    inp: &Inputs,
    sp: &Splat1,
    v: &mut Invocation,
    w: Vec3,
    weight: f32,
    index: u32,
    slot: u32,
    kind: u32,
    sparse: bool,
    full: bool,
    losses: bool,
) {
    v.acc[SUM_WEIGHT] += weight;
    if kind == PASS_FINAL {
        let p = inp.bin_power[index as usize];
        if sp.stride == 1 {
            v.acc[SUM_COUNT] += 1.0;
            v.acc[SUM_RGB] += p[0];
            v.acc[SUM_RGB + 1] += p[1];
            v.acc[SUM_RGB + 2] += p[2];
        }
        if sp.lobe_count == 0 {
            return;
        }
        v.acc[SUM_LOG] += weight * e_step(inp.em, sp, v, w, slot, false, true);
        for k in 0..sp.lobe_count as usize {
            let o = LOBE_SUMS + LOBE_SLOTS * k;
            v.acc[o] += v.resp[k] * p[0];
            v.acc[o + 1] += v.resp[k] * p[1];
            v.acc[o + 2] += v.resp[k] * p[2];
        }
        return;
    }
    v.acc[SUM_COUNT] += 1.0;
    e_step(inp.em, sp, v, w, slot, sparse, full);
    for k in 0..sp.lobe_count as usize {
        let o = LOBE_SUMS + LOBE_SLOTS * k;
        let wh = weight * v.resp[k];
        let frozen = v.frozen_mask & (1 << k) != 0;
        v.acc[o] += wh;
        v.acc[o + 1] += if frozen {
            weight * v.stat[k]
        } else {
            wh * v.stat[k]
        };
        v.acc[o + 2] += wh * w.x;
        v.acc[o + 3] += wh * w.y;
        v.acc[o + 4] += wh * w.z;
        if losses {
            let mut rest = 0.0;
            for j in 0..sp.lobe_count as usize {
                if j != k {
                    rest += v.resp[j];
                }
            }
            v.acc[o + LOBE_LOSS] -= weight * rest.max(REST_MIN).ln();
        }
    }
}

fn gather(inp: &Inputs, sp: &Splat1, v: &mut Invocation, cache: &mut Cache, lid: u32, bx: &BinBox) {
    let wg = inp.em.workgroup_size;
    let capacity = CACHE_SLOTS / wg;
    v.cached = 0;
    v.streaming = false;
    let mut offset = 0;
    for r in 0..row_count(inp, bx) {
        let (begin, end) = row_span(inp, sp, bx, r);
        let mut j = first_in_row(inp.em.workgroup_size, sp.stride, begin, offset, lid);
        while j < end {
            let c = accept(inp, sp, j);
            if c.ok {
                if v.cached == capacity {
                    v.streaming = true;
                    v.resume_row = r;
                    v.resume_j = j;
                    v.resume_offset = offset;
                    return;
                }
                let slot = (v.cached * wg + lid) as usize;
                cache.dir[slot] = [c.dir.x, c.dir.y, c.dir.z, c.weight];
                cache.index[slot] = j;
                v.cached += 1;
            }
            j += inp.em.workgroup_size * sp.stride;
        }
        offset += end - begin;
    }
}

#[allow(clippy::too_many_arguments)]
fn photon_pass(
    inp: &Inputs,
    sp: &Splat1,
    v: &mut Invocation,
    cache: &Cache,
    lid: u32,
    bx: &BinBox,
    kind: u32,
    sparse: bool,
    full: bool,
    losses: bool,
) {
    v.acc = [0.0; SUMS];
    for c in 0..v.cached {
        let slot = (c * inp.em.workgroup_size + lid) as usize;
        let d = cache.dir[slot];
        let index = cache.index[slot];
        absorb(
            inp,
            sp,
            v,
            Vec3::new(d[0], d[1], d[2]),
            d[3],
            index,
            c,
            kind,
            sparse,
            full,
            losses,
        );
    }
    if !v.streaming {
        return;
    }
    let mut offset = v.resume_offset;
    for r in v.resume_row..row_count(inp, bx) {
        let (begin, end) = row_span(inp, sp, bx, r);
        let mut j = if r == v.resume_row {
            v.resume_j
        } else {
            first_in_row(inp.em.workgroup_size, sp.stride, begin, offset, lid)
        };
        while j < end {
            let c = accept(inp, sp, j);
            if c.ok {
                absorb(
                    inp, sp, v, c.dir, c.weight, j, NOT_CACHED, kind, sparse, full, losses,
                );
            }
            j += inp.em.workgroup_size * sp.stride;
        }
        offset += end - begin;
    }
}

/// `irradiance_pass` in WGSL: every photon of invocation `lid` into the count and RGB sums.
fn irradiance_pass(inp: &Inputs, sp: &Splat1, v: &mut Invocation, lid: u32, bx: &BinBox) {
    let wg = inp.em.workgroup_size;
    let mut offset = 0;
    for r in 0..row_count(inp, bx) {
        let (begin, end) = row_span(inp, sp, bx, r);
        let mut j = begin + (lid + wg - offset % wg) % wg;
        while j < end {
            if accept(inp, sp, j).ok {
                let p = inp.bin_power[j as usize];
                v.acc[SUM_COUNT] += 1.0;
                v.acc[SUM_RGB] += p[0];
                v.acc[SUM_RGB + 1] += p[1];
                v.acc[SUM_RGB + 2] += p[2];
            }
            j += wg;
        }
        offset += end - begin;
    }
}

/// The candidates of a splat's bin rows.
fn candidate_count(inp: &Inputs, sp: &Splat1, bx: &BinBox) -> u32 {
    (0..row_count(inp, bx))
        .map(|r| {
            let (begin, end) = row_span(inp, sp, bx, r);
            end - begin
        })
        .sum()
}

/// `weakest_lobe` in WGSL: the lightest live lobe whose loss is under the penalty after an EM
/// pass with sums `total` (before its M-step), or `lobe_count` when none is.
fn weakest_lobe(sp: &Splat1, total: &[f32; SUMS]) -> u32 {
    let n = total[SUM_COUNT];
    let total_weight = total[SUM_WEIGHT];
    let mut weakest = sp.lobe_count;
    if sp.alive.count_ones() < 2 || n < 1.0 || total_weight <= 0.0 {
        return weakest;
    }
    let penalty = PRUNE_PENALTY * (1.0 + n).ln();
    let mut lightest = 2.0;
    for k in 0..sp.lobe_count as usize {
        if sp.alive & (1 << k) == 0 {
            continue;
        }
        let mut rest_weight = 0.0;
        for j in 0..sp.lobe_count as usize {
            if j != k && sp.alive & (1 << j) != 0 {
                rest_weight += sp.mix_weight[j];
            }
        }
        let loss = total[LOBE_SUMS + LOBE_SLOTS * k + LOBE_LOSS] * (n / total_weight)
            + n * rest_weight.max(REST_MIN).ln();
        if loss < penalty && sp.mix_weight[k] < lightest {
            lightest = sp.mix_weight[k];
            weakest = k as u32;
        }
    }
    weakest
}

/// `drop_lobe` in WGSL: drops lobe k and renormalizes the others' weights.
fn drop_lobe(sp: &mut Splat1, k: u32) {
    sp.alive &= !(1 << k);
    let mut rest_weight = 0.0;
    for j in 0..sp.lobe_count as usize {
        if sp.alive & (1 << j) != 0 {
            rest_weight += sp.mix_weight[j];
        }
    }
    for j in 0..sp.lobe_count as usize {
        sp.mix_weight[j] = if sp.alive & (1 << j) != 0 {
            sp.mix_weight[j] / rest_weight
        } else {
            0.0
        };
    }
}

/// The fixed-order sums of `reduce` in WGSL. With `butterfly` (the `subgroups` variant),
/// invocation i adds the value of invocation i ^ step for step = n/2, n/4, …, 1, and the
/// result is invocation 0's; else column q over the invocations 0, 1, …, n − 1.
fn reduce(invocations: &[Invocation], count: usize, butterfly: bool) -> [f32; SUMS] {
    let mut total = [0.0; SUMS];
    for (q, t) in total.iter_mut().enumerate().take(count) {
        let n = invocations.len();
        let mut v = [0.0f32; MAX_WG];
        for (x, inv) in v.iter_mut().zip(invocations) {
            *x = inv.acc[q];
        }
        if butterfly {
            let mut step = n / 2;
            while step > 0 {
                let before = v;
                for (i, x) in v.iter_mut().enumerate().take(n) {
                    *x = before[i] + before[i ^ step];
                }
                step /= 2;
            }
            *t = v[0];
        } else {
            *t = v[..n].iter().fold(0.0, |s, x| s + x);
        }
    }
    total
}

#[allow(clippy::too_many_arguments)]
pub fn em_fit(
    em: &EmParams,
    bins: &BinParams,
    splats: &[Splat],
    fit_list: &[[u32; 2]],
    cell_start: &[u32],
    bin_geom: &[BinnedPhoton],
    bin_power: &[[f32; 4]],
    lobes: &mut [Lobe],
    light: &mut [SplatLight],
    groups: u32,
) {
    let inp = Inputs {
        em,
        bins,
        cell_start,
        bin_geom,
        bin_power,
    };
    let k = em.lobes as usize;
    let results: Vec<Written> = (0..groups)
        .into_par_iter()
        .map(|group| em.list_first + group)
        .filter(|&index| index < em.active_count)
        .filter_map(|index| {
            let [entry, lobe_slot] = fit_list[index as usize];
            // The lobe buffer holds the fitted splats' alone (see fit_select).
            let first = lobe_slot * em.lobes;
            let resume = match entry & FIT_BIT {
                0 => &[][..],
                _ => &lobes[first as usize..first as usize + k],
            };
            let sample_first = (index - em.list_first) * em.gathered;
            fit_splat(&inp, splats, [entry, lobe_slot], sample_first, resume)
        })
        .collect();
    for (splat_index, first, written, out) in results {
        let base = first as usize;
        lobes[base..base + written.len()].copy_from_slice(&written);
        if let Some(out) = out {
            light[splat_index as usize] = out;
        }
    }
}

/// Lobe k of the mixture, with no irradiance yet.
fn mixture(sp: &Splat1, k: usize) -> Lobe {
    Lobe {
        axis: sp.mix_axis[k].into(),
        sharpness: sp.mix_sharpness[k],
        irradiance: [0.0; 3],
        weight: sp.mix_weight[k],
    }
}

/// What one workgroup writes: its splat, the lobes, and the splat's light (last dispatch).
/// What one workgroup writes: its splat, the first of its lobe slots, its lobes and light.
type Written = (u32, u32, Vec<Lobe>, Option<SplatLight>);

/// The body of `main` for one workgroup; `resume` is the splat's slice of the lobe buffer.
fn fit_splat(
    inp: &Inputs,
    splats: &[Splat],
    [entry, lobe_slot]: [u32; 2],
    sample_first: u32,
    resume: &[Lobe],
) -> Option<Written> {
    let em = inp.em;
    // The splat's lobes in the lobe buffer, which holds the fitted splats' alone.
    let first = lobe_slot * em.lobes;
    let splat_index = entry & !FIT_BIT;
    let fit = entry & FIT_BIT != 0 && em.flags & EM_DEFER_FIT == 0;
    if em.gathered > 0 && !fit {
        return None;
    }
    let s = &splats[splat_index as usize];
    let mut sp = Splat1 {
        center: Vec3::from(s.center),
        normal: Vec3::from(s.normal),
        slab: em.slab * s.radius,
        lobe_count: if fit { em.lobes } else { 0 },
        sample_first,
        ..Default::default()
    };
    let begin = if fit {
        em.iteration_begin
    } else {
        em.iterations
    };
    let end = if fit { em.iteration_end } else { em.iterations };
    let last = em.iteration_end == em.iterations;
    if !last && !fit {
        return None;
    }
    let f = frame_of(sp.normal);
    #[allow(clippy::needless_range_loop)] // the loop shape of the WGSL
    for k in 0..sp.lobe_count as usize {
        if begin == 0 {
            sp.mix_axis[k] = initial_axis(&f, k as u32, sp.lobe_count);
            sp.mix_sharpness[k] = initial_sharpness(em.family);
            sp.mix_weight[k] = 1.0 / sp.lobe_count as f32;
        } else {
            let l = &resume[k];
            sp.mix_axis[k] = Vec3::from(l.axis);
            sp.mix_sharpness[k] = l.sharpness;
            sp.mix_weight[k] = l.weight;
        }
    }
    // A lobe handed over with sharpness 0 was dropped.
    for k in 0..sp.lobe_count as usize {
        if sp.mix_sharpness[k] > 0.0 {
            sp.alive |= 1 << k;
        }
    }
    let bx = bin_box(sp.center, em.radius, inp.bins);
    sp.stride = 1;
    if fit && em.fit_candidates > 0 {
        sp.stride = candidate_count(inp, &sp, &bx)
            .div_ceil(em.fit_candidates)
            .max(1);
    }
    let mut cache = Cache {
        dir: vec![[0.0; 4]; CACHE_SLOTS as usize],
        index: vec![0; CACHE_SLOTS as usize],
    };
    let mut inv = vec![Invocation::default(); em.workgroup_size as usize];
    for (lid, v) in inv.iter_mut().enumerate() {
        gather(inp, &sp, v, &mut cache, lid as u32, &bx);
    }
    let sparse = em.flags & EM_SPARSE != 0;
    let butterfly = em.flags & EM_SUBGROUP_REDUCE != 0;
    let sums = LOBE_SUMS + LOBE_SLOTS * sp.lobe_count as usize;

    let mut dropped_one = false;
    let mut next_check = begin.max(PRUNE_FROM);
    for it in begin..end {
        prepare_mixture(em, &mut sp);
        let full = it % SPARSE_PERIOD == 0 || it == begin || dropped_one;
        let pruning = it == next_check && sp.lobe_count - sp.alive.count_ones() < em.prune;
        for (lid, v) in inv.iter_mut().enumerate() {
            photon_pass(
                inp, &sp, v, &cache, lid as u32, &bx, PASS_EM, sparse, full, pruning,
            );
        }
        let total = reduce(&inv, sums, butterfly);
        let weakest = if pruning {
            weakest_lobe(&sp, &total)
        } else {
            sp.lobe_count
        };
        let live = sp.alive.count_ones();
        for k in 0..sp.lobe_count as usize {
            if sp.alive & (1 << k) == 0 {
                continue;
            }
            let o = LOBE_SUMS + LOBE_SLOTS * k;
            let old = LobeFit {
                axis: sp.mix_axis[k],
                sharpness: sp.mix_sharpness[k],
                weight: sp.mix_weight[k],
            };
            let s2 = Vec3::new(total[o + 2], total[o + 3], total[o + 4]);
            let next = m_step(
                em.family,
                em.flags,
                live,
                total[o],
                total[o + 1],
                s2,
                total[SUM_WEIGHT],
                total[SUM_COUNT],
                old,
            );
            sp.mix_axis[k] = next.axis;
            sp.mix_sharpness[k] = next.sharpness;
            sp.mix_weight[k] = next.weight;
        }
        dropped_one = weakest < sp.lobe_count;
        if dropped_one {
            drop_lobe(&mut sp, weakest);
        }
        if pruning {
            next_check = it + if dropped_one { 1 } else { PRUNE_PERIOD };
        }
    }

    if !last {
        let kept = (0..sp.lobe_count as usize)
            .map(|k| Lobe {
                sharpness: if sp.alive & (1 << k) != 0 {
                    sp.mix_sharpness[k]
                } else {
                    0.0
                },
                ..mixture(&sp, k)
            })
            .collect();
        return Some((splat_index, first, kept, None));
    }
    prepare_mixture(em, &mut sp);
    for (lid, v) in inv.iter_mut().enumerate() {
        photon_pass(
            inp, &sp, v, &cache, lid as u32, &bx, PASS_FINAL, false, true, false,
        );
        if sp.stride > 1 {
            irradiance_pass(inp, &sp, v, lid as u32, &bx);
        }
    }
    let total = reduce(&inv, sums, butterfly);
    let photons = total[SUM_COUNT] as u32;
    let rgb = Vec3::new(total[SUM_RGB], total[SUM_RGB + 1], total[SUM_RGB + 2]);
    // A subset's lobes share the irradiance of every photon, channel by channel.
    let mut share = Vec3::ONE;
    if sp.stride > 1 {
        let lobe_rgb = (0..sp.lobe_count as usize).fold(Vec3::ZERO, |s, k| {
            let o = LOBE_SUMS + LOBE_SLOTS * k;
            s + Vec3::new(total[o], total[o + 1], total[o + 2])
        });
        share = Vec3::select(lobe_rgb.cmpgt(Vec3::ZERO), rgb / lobe_rgb, Vec3::ZERO);
    }
    let written = if photons > 0 {
        sp.alive.count_ones()
    } else {
        0
    };
    // The live lobes in order, into the first `written` slots.
    let fitted = (0..sp.lobe_count as usize)
        .filter(|&k| sp.alive & (1 << k) != 0)
        .take(written as usize)
        .map(|k| {
            let o = LOBE_SUMS + LOBE_SLOTS * k;
            let e = Vec3::new(total[o], total[o + 1], total[o + 2]) * share * em.inv_area;
            Lobe {
                irradiance: e.into(),
                ..mixture(&sp, k)
            }
        })
        .collect();
    let out = SplatLight {
        irradiance: (rgb * em.inv_area).into(),
        photons,
        log_likelihood: total[SUM_LOG],
        weight: total[SUM_WEIGHT],
        lobes: written,
        // Where the fit wrote them; `LobeMap::pack` moves them into splat order.
        first_lobe: if fit { first } else { 0 },
    };
    Some((splat_index, first, fitted, Some(out)))
}

/// The executor's entry: `em_fit`'s bindings, unpacked in the order its WGSL declares them.
pub fn dispatch(b: &Bindings, groups: u32) -> Result<()> {
    let em = b.param(0)?;
    let bins = b.param(1)?;
    let splats = b.get(2)?;
    let fit_list = b.get(3)?;
    let cell_start = b.get(4)?;
    let geom = b.get(5)?;
    let power = b.get(6)?;
    let mut lobes = b.get_mut(7)?;
    let mut light = b.get_mut(8)?;
    em_fit(
        &em,
        &bins,
        view(&splats),
        view(&fit_list),
        &cell_start,
        view(&geom),
        view(&power),
        view_mut(&mut lobes),
        view_mut(&mut light),
        groups,
    );
    Ok(())
}

/// This file's row of the mirrors' table (`cpu::MIRRORS`).
pub const ROWS: &[MirrorRow] = &[
    MirrorRow {
        stage: Stage::EmFit,
        entry: "main",
        workgroup_size: None,
        items: 1,
        run: Some(Mirror::Plain(dispatch)),
    },
];
