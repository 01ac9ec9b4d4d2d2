//! Twin of `wgsl/shared/lobes.wgsl`: the vMF and Ward-like lobe families, their constant
//! initial mixture and the M-step of one lobe (see the WGSL file for the math).

use glam::Vec3;

use super::sampling::{Frame, PI, polar, to_world};
use super::ward::tan2_to_normal;

pub const MAX_LOBES: u32 = 8;
pub const FAMILY_VMF: u32 = 0;
pub const FAMILY_WARD: u32 = 1;
pub const EM_SPARSE: u32 = 1;
pub const EM_PRIORS: u32 = 2;
pub const EM_FIT_ALL: u32 = 4;
/// The invocations' sums combine by a subgroup butterfly (the `subgroups` variant of
/// `em_fit`); the CPU mirror then adds in that order.
pub const EM_SUBGROUP_REDUCE: u32 = 8;
/// Fitted splats take only their irradiance from the photons; a dispatch over final
/// gathering's samples fits their lobes after (`em_fit.wgsl`, "Gathered samples").
pub const EM_DEFER_FIT: u32 = 16;
/// The bins hold deposits: `deposit_share` lights every splat, and `fit_select` lists only the
/// fitted splats (on the fit list).
pub const EM_SHARE: u32 = 32;
/// The fitted splats share fits in groups (`fit_groups`): `fit_select` lists the groups'
/// leaders alone, and `final_gather` casts a group's rays from its members.
pub const EM_GROUPS: u32 = 64;
/// `estimate_smooth`: a neighbour counts where it faces within this cosine of the splat (11°): the
/// same flat stretch of surface. On a curved model the light changes with the normal, and not
/// linearly; at the shared fits' 26° a diffuse ball read 1.3 % brighter (tests/accuracy.rs).
pub const SMOOTH_COS_MIN: f32 = 0.98;
/// `estimate_smooth`: the half width of a scale's interval, in its standard deviations. Wider keeps
/// more noise out and lets more of a change of the light in.
pub const SMOOTH_CONFIDENCE: f32 = 2.0;
/// `estimate_smooth`: past this many photons in its gather disk a splat's own estimate is within
/// half a percent, and it keeps it (no work where the photons already suffice).
pub const SMOOTH_PHOTONS_ENOUGH: u32 = 40_000;
/// `estimate_smooth`: the most deposit records a splat's fit visits. The default box's splats find
/// 100–200 in their boxes; past the budget (a dense scan, whose every R holds thousands of
/// splats) an even subset, every ⌈records / budget⌉-th, so that the stage's time follows the
/// splats, not their density, and stays within lavapipe's loop limit.
pub const SMOOTH_BUDGET: u32 = 128;
/// `estimate_smooth`: the least determinant of a scale's moments (over the cube of its total
/// weight) for a plane through the neighbours' light: below it they lie along a line, or are too
/// few.
pub const SMOOTH_DET_MIN: f32 = 1e-6;
/// `estimate_smooth`: the most cells its box spans per axis, less one. The deposit bins' cells are
/// half a reach (R plus a deposit's spread past its mean); the box's radius, the widest kernel
/// plus a deposit's reach past R, is at most 2 reach for kernels up to 2 R (`MAX_SMOOTH`): 4
/// reach wide, 8 cells and a part.
pub const SMOOTH_SPAN: u32 = 8;
/// A splat's word in the groups when another splat's fit serves it (`fit_groups`).
pub const FOLLOWER_BIT: u32 = 0x8000_0000;
/// Most candidate photons of a splat `estimate_gather` sums in one invocation.
pub const GATHER_MAX: u32 = 16384;

pub const SPARSE_THRESHOLD: f32 = 0.02;
pub const SPARSE_PERIOD: u32 = 8;

pub const SHARPNESS_MIN: f32 = 0.01;
pub const SHARPNESS_MAX: f32 = 32000.0;
pub const WARD_B2_MIN: f32 = 1.5625e-5;
pub const WARD_B2_MAX: f32 = 1.0;
pub const LOG_WEIGHT_MIN: f32 = -80.0;
pub const PRIOR_WEIGHT: f32 = 0.01;
pub const PRIOR_RESULTANT: f32 = 0.02;
pub const PRUNE_PENALTY: f32 = 2.0;
pub const PRUNE_FROM: u32 = 2;
pub const PRUNE_PERIOD: u32 = 4;

pub const INITIAL_COS: f32 = 0.5;
pub const INITIAL_VMF: f32 = 4.0;
pub const INITIAL_WARD: f32 = 8.0;

pub fn initial_axis(f: &Frame, k: u32, count: u32) -> Vec3 {
    if k == 0 {
        return f.n;
    }
    to_world(f, polar(INITIAL_COS, (k - 1) as f32 / (count - 1) as f32))
}

pub fn initial_sharpness(family: u32) -> f32 {
    if family == FAMILY_WARD {
        INITIAL_WARD
    } else {
        INITIAL_VMF
    }
}

pub fn ward_kappa(b2: f32) -> f32 {
    let x = b2;
    let num = 0.999_993_6 + x * (7.573_939 + x * (12.464_892 + x * 3.690_723_2));
    let den = 1.0 + x * (9.573_322 + x * (25.632_956 + x * (21.099_653 + x * 3.958_497)));
    num / den
}

pub fn lobe_log_norm(family: u32, n: Vec3, axis: Vec3, sharpness: f32) -> f32 {
    if family == FAMILY_WARD {
        let b2 = 1.0 / sharpness;
        let cos_axis = n.dot(axis).max(0.01);
        return -(4.0 * PI * b2 * cos_axis * ward_kappa(b2)).ln();
    }
    let k = sharpness;
    (k / (2.0 * PI * (1.0 - (-2.0 * k).exp()))).ln()
}

pub fn lobe_stat(family: u32, n: Vec3, axis: Vec3, mirror: Vec3, w: Vec3) -> f32 {
    if family == FAMILY_WARD {
        let h = w + mirror;
        let ch = n.dot(h).max(1e-12);
        return tan2_to_normal(n, h, ch).min(1e12);
    }
    w.dot(axis)
}

pub fn lobe_exponent(family: u32, sharpness: f32, stat: f32) -> f32 {
    if family == FAMILY_WARD {
        return -stat * sharpness;
    }
    sharpness * (stat - 1.0)
}

pub fn mirror_axis(n: Vec3, axis: Vec3) -> Vec3 {
    2.0 * n.dot(axis) * n - axis
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LobeFit {
    pub axis: Vec3,
    pub sharpness: f32,
    pub weight: f32,
}

#[allow(clippy::too_many_arguments)]
pub fn m_step(
    family: u32,
    flags: u32,
    lobes: u32,
    s0: f32,
    s1: f32,
    s2: Vec3,
    total: f32,
    count: f32,
    old: LobeFit,
) -> LobeFit {
    let mut fit = old;
    let priors = flags & EM_PRIORS != 0;
    let mean_w = total / count.max(1.0);
    let prior_w = if priors { PRIOR_WEIGHT * mean_w } else { 0.0 };
    fit.weight = (s0 + prior_w) / (total + lobes as f32 * prior_w).max(1e-30);
    // Scaled by its largest component first: the squares of an emptied lobe's tiny sums
    // would underflow. Sums near the float's subnormal range give no reliable direction.
    let big = s2.x.abs().max(s2.y.abs().max(s2.z.abs()));
    if !(s0 > 1e-30 && big > 1e-30) {
        return fit;
    }
    let v = s2 / big;
    let v_len = v.length();
    fit.axis = v / v_len;
    if family == FAMILY_WARD {
        fit.sharpness = 1.0 / (s1 / s0).clamp(WARD_B2_MIN, WARD_B2_MAX);
        return fit;
    }
    let prior_r = if priors {
        PRIOR_RESULTANT * mean_w
    } else {
        0.0
    };
    let r = (v_len * (big / (s0 + prior_r))).min(0.999_999);
    fit.sharpness = (r * (3.0 - r * r) / (1.0 - r * r)).clamp(SHARPNESS_MIN, SHARPNESS_MAX);
    fit
}
