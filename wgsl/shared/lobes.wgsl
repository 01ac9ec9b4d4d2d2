// The two lobe families the EM fit can use (docs/design.md section 6), their constant initial
// mixture, and the M-step of one lobe. Twin: src/shared/lobes.rs.
//
// vMF: p(w) = k / (2 pi (1 - exp(-2k))) exp(k (w.mu - 1)), a density on the sphere; M-step
//   mu = normalize(sum w h w), k from Banerjee's r(3 - r^2) / (1 - r^2) of the mean resultant
//   length r, with light MAP priors (pseudo-counts) on weights and on r.
// Ward-like (the thesis's lobe): g(w) = exp(-tan^2 d / b^2) / (4 pi b^2), d the angle between
//   n and the half-vector of w and the lobe axis mirrored about n. Its hemispherical integral
//   is about cos(theta_axis) kappa(b), kappa(b) = (1 - a e^a E1(a)) / b^2 with a = 1/b^2, so
//   densities divide by that. M-step as the thesis: b^2 = sum w h tan^2 d / sum w h (the ML
//   estimate; the thesis prints b) and the axis the normalized weighted mean direction (a
//   heuristic, so this family's EM is not guaranteed to raise the likelihood).
// `sharpness` is k for vMF and 1/b^2 for Ward: the factor of the exponent either way.

// #import sampling
// #import ward

const MAX_LOBES: u32 = 8u;
const FAMILY_VMF: u32 = 0u;
const FAMILY_WARD: u32 = 1u;
// EmParams.flags
const EM_SPARSE: u32 = 1u;
const EM_PRIORS: u32 = 2u;
const EM_FIT_ALL: u32 = 4u;
const EM_SUBGROUP_REDUCE: u32 = 8u;
// Fitted splats take only their irradiance from the photons: a dispatch over final gathering's
// samples fits their lobes after (em_fit.wgsl, "Gathered samples").
const EM_DEFER_FIT: u32 = 16u;
// The bins hold deposits: deposit_share lights every splat, and fit_select lists only the fitted
// splats (on the fit list).
const EM_SHARE: u32 = 32u;
// The fitted splats share fits in groups (src/fit_groups.rs): fit_select lists the groups'
// leaders alone, and final_gather casts a group's rays from its members.
const EM_GROUPS: u32 = 64u;
// estimate_smooth (src/shared/lobes.rs says why each): a neighbour faces within this cosine of the
// splat (11 degrees), the intervals' half width in standard deviations,
// the photons past which the own estimate is kept, the records a splat's fit visits, and the
// least determinant of a plane's moments over the cube of their weight.
const SMOOTH_COS_MIN: f32 = 0.98;
const SMOOTH_CONFIDENCE: f32 = 2.0;
const SMOOTH_PHOTONS_ENOUGH: u32 = 40000u;
const SMOOTH_BUDGET: u32 = 128u;
const SMOOTH_DET_MIN: f32 = 1e-6;
const SMOOTH_SPAN: u32 = 8u;
// A splat's word in the groups when another splat's fit serves it.
const FOLLOWER_BIT: u32 = 0x80000000u;

// A fit-list entry is a splat index with this bit set when the splat's lobes are fitted.
const FIT_BIT: u32 = 0x80000000u;
// Most candidate photons of a splat estimate_gather sums in one invocation (fit_select): well under
// llvmpipe's loop limit of about 65k iterations.
const GATHER_MAX: u32 = 16384u;

// Sparse EM (thesis 3.5): responsibilities under this stay frozen between full updates.
const SPARSE_THRESHOLD: f32 = 0.02;
const SPARSE_PERIOD: u32 = 8u;

const SHARPNESS_MIN: f32 = 0.01;
const SHARPNESS_MAX: f32 = 32000.0;
// Ward: b^2 in [1/(2 SHARPNESS_MAX), 1], the vMF range in the small-angle equivalence k = 1/(2 b^2).
const WARD_B2_MIN: f32 = 1.5625e-5;
const WARD_B2_MAX: f32 = 1.0;
// Floor of a lobe's log weight: an emptied lobe keeps finite densities.
const LOG_WEIGHT_MIN: f32 = -80.0;
// MAP priors, in units of the splat's mean photon weight: a pseudo-weight per lobe, and a
// pseudo-weight of resultant length 0 added to each lobe's mean resultant (broadens lobes fit
// to a handful of photons, a single photon gives k ~ 50).
const PRIOR_WEIGHT: f32 = 0.01;
const PRIOR_RESULTANT: f32 = 0.02;
// Pruning (em_fit.wgsl) drops a lobe when the log-likelihood it adds, rescaled to unit mean
// photon weight, is under PRUNE_PENALTY ln(1 + n) for n photons: the BIC's half of a lobe's 4
// parameters (axis 2, sharpness, weight) per ln n, with 1 + n so that a splat of one photon
// still sheds the lobes that add nothing. Losses are summed from iteration PRUNE_FROM on,
// once the initial lobes have moved to the photons: in the pass after a drop, else every
// PRUNE_PERIOD passes (a pass that sums them costs a log per lobe and photon more).
const PRUNE_PENALTY: f32 = 2.0;
const PRUNE_FROM: u32 = 2u;
const PRUNE_PERIOD: u32 = 4u;

// The initial lobes, the same for every splat in its own frame: one along the normal, the
// others evenly around a 60-degree cone, as wide as k = 4 (b^2 = 1/8), equal weights.
const INITIAL_COS: f32 = 0.5;
const INITIAL_VMF: f32 = 4.0;
const INITIAL_WARD: f32 = 8.0;

fn initial_axis(f: Frame, k: u32, count: u32) -> vec3<f32> {
    if k == 0u {
        return f.n;
    }
    return to_world(f, polar(INITIAL_COS, f32(k - 1u) / f32(count - 1u)));
}

fn initial_sharpness(family: u32) -> f32 {
    return select(INITIAL_VMF, INITIAL_WARD, family == FAMILY_WARD);
}

// (1 - a e^a E1(a)) / b^2 for a = 1/b^2 >= 1, written in x = b^2 from the rational
// approximation of x e^x E1(x) of Abramowitz & Stegun 5.1.56 (error < 5e-8).
fn ward_kappa(b2: f32) -> f32 {
    let x = b2;
    let num = 0.9999936053 + x * (7.5739391756 + x * (12.4648921902 + x * 3.6907231885));
    let den = 1.0 + x * (9.5733223454 + x * (25.6329561486 + x * (21.0996530827 + x * 3.9584969228)));
    return num / den;
}

// Log of a lobe density's constant factor.
fn lobe_log_norm(family: u32, n: vec3<f32>, axis: vec3<f32>, sharpness: f32) -> f32 {
    if family == FAMILY_WARD {
        let b2 = 1.0 / sharpness;
        let cos_axis = max(dot(n, axis), 0.01);
        return -log(4.0 * PI * b2 * cos_axis * ward_kappa(b2));
    }
    let k = sharpness;
    return log(k / (2.0 * PI * (1.0 - exp(-2.0 * k))));
}

// The per-photon statistic of a lobe: w.mu for vMF, tan^2 d for Ward (`mirror` is the axis
// reflected about n).
fn lobe_stat(family: u32, n: vec3<f32>, axis: vec3<f32>, mirror: vec3<f32>, w: vec3<f32>) -> f32 {
    if family == FAMILY_WARD {
        let h = w + mirror;
        let ch = max(dot(n, h), 1e-12);
        return min(tan2_to_normal(n, h, ch), 1e12);
    }
    return dot(w, axis);
}

fn lobe_exponent(family: u32, sharpness: f32, stat: f32) -> f32 {
    if family == FAMILY_WARD {
        return -stat * sharpness;
    }
    return sharpness * (stat - 1.0);
}

fn mirror_axis(n: vec3<f32>, axis: vec3<f32>) -> vec3<f32> {
    return 2.0 * dot(n, axis) * n - axis;
}

struct LobeFit {
    axis: vec3<f32>,
    sharpness: f32,
    weight: f32,
}

// M-step of one lobe from its sums: s0 = sum w h, s1 = sum w h stat, s2 = sum w h w, over a
// splat with total weight `total` and `count` photons. An empty lobe keeps axis and sharpness.
fn m_step(family: u32, flags: u32, lobes: u32, s0: f32, s1: f32, s2: vec3<f32>, total: f32,
          count: f32, old: LobeFit) -> LobeFit {
    var fit = old;
    let priors = (flags & EM_PRIORS) != 0u;
    let mean_w = total / max(count, 1.0);
    let prior_w = select(0.0, PRIOR_WEIGHT * mean_w, priors);
    fit.weight = (s0 + prior_w) / max(total + f32(lobes) * prior_w, 1e-30);
    // Scaled by its largest component first: the squares of an emptied lobe's tiny sums
    // would underflow. Sums near the float's subnormal range give no reliable direction.
    let big = max(abs(s2.x), max(abs(s2.y), abs(s2.z)));
    if !(s0 > 1e-30 && big > 1e-30) {
        return fit;
    }
    let v = s2 / big;
    let v_len = length(v);
    fit.axis = v / v_len;
    if family == FAMILY_WARD {
        fit.sharpness = 1.0 / clamp(s1 / s0, WARD_B2_MIN, WARD_B2_MAX);
        return fit;
    }
    let prior_r = select(0.0, PRIOR_RESULTANT * mean_w, priors);
    let r = min(v_len * (big / (s0 + prior_r)), 0.999999);
    fit.sharpness = clamp(r * (3.0 - r * r) / (1.0 - r * r), SHARPNESS_MIN, SHARPNESS_MAX);
    return fit;
}
