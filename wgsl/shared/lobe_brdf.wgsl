// The specular radiance one light lobe reflects towards a view, I(wo) = integral of
// f_s(w, wo) p(w) dw (docs/design.md section 7), in closed form. Twin: src/shared/lobe_brdf.rs.
//
// Both factors are Gaussians of half-vector slopes: the Ward lobe of the slope m of
// h(w, wo), exactly, and the light lobe of the slope m' of h(w, L'), L' the mirrored axis.
// Over m, with dw = 4 (h.wo) cos^3(theta_h) dm,
//   I = 1 / (4 N) * integral of P_a(m) P_b(m'(m)) / ((h.wo) cos theta_h) dm,
//   P_s(m) = exp(-|m|^2 / s^2) / (pi s^2),
// N the light lobe's hemispherical integral (a table: the horizon cuts broad lobes).
// Linearised about the peak of the product, m' ~ b + J m, the Gaussians convolve in closed
// form, exp(-b^T S^-1 b) / (pi sqrt(det S)) with S = beta^2 I + alpha^2 J J^T: the
// view-dependent stretch of the half-vector warp. The peak is found by re-linearising there
// (LINEARISATIONS). The product's share above the horizon (w.n > 0, linear in m about the
// peak) is a normal cdf. What the Gaussian leaves out, 1 / ((h.wo) cos theta_h) and the
// light lobe's departure from its linearisation, varies across the product for rough
// surfaces and grazing lobes: its mean over the product's Gaussian is taken at 3 x 3
// Gauss-Hermite nodes.

// #import sampling

const LINEARISATIONS: u32 = 2u;

// Gauss-Hermite nodes for a standard normal, exact up to degree 5: 0 and +-sqrt(3),
// weights 2/3 and 1/6.
const HERMITE_NODE: f32 = 1.7320508;
const HERMITE_WEIGHTS: array<f32, 3> = array<f32, 3>(1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0);

// The most a node's exact-over-linearised light-lobe ratio may weigh: far out in a broad
// product the linearised tail can be orders of magnitude below the lobe, and one node must
// not carry the mean.
const NODE_RATIO_MAX: f32 = 8.0;

// The lobe-norm table: N(beta^2, cos theta_L) at NORM_COS_NODES cosines evenly over [0, 1]
// and NORM_B2_NODES values of log2 beta^2 evenly over [NORM_LOG2_B2_MIN, 0].
const NORM_COS_NODES: u32 = 33u;
const NORM_B2_NODES: u32 = 33u;
const NORM_LOG2_B2_MIN: f32 = -16.0;

struct NormLookup {
    index: u32,
    fx: f32,
    fy: f32,
}

// x follows cos theta_L, y follows log2 beta^2; node (x, y) is entry y * NORM_COS_NODES + x.
fn norm_lookup(cos_l: f32, beta2: f32) -> NormLookup {
    let x = clamp(cos_l, 0.0, 1.0) * f32(NORM_COS_NODES - 1u);
    let span = -NORM_LOG2_B2_MIN;
    let y = clamp((log2(max(beta2, 1e-30)) - NORM_LOG2_B2_MIN) / span, 0.0, 1.0)
        * f32(NORM_B2_NODES - 1u);
    let ix = min(u32(x), NORM_COS_NODES - 2u);
    let iy = min(u32(y), NORM_B2_NODES - 2u);
    return NormLookup(iy * NORM_COS_NODES + ix, x - f32(ix), y - f32(iy));
}

struct SlopePoint {
    // The light lobe's half-vector slope m'.
    mp: vec2<f32>,
    // dm'/dm as columns: dm'/dmx and dm'/dmy.
    jx: vec2<f32>,
    jy: vec2<f32>,
    // 1 / ((h.wo) cos theta_h) = |k|^2 / (k.wo) with k = (m, 1).
    w: f32,
    // The incident direction's cosine w.n and its gradient in m.
    wz: f32,
    dwz: vec2<f32>,
    // False where w is undefined (h.wo <= 0) or the light lobe's half-vector is.
    ok: bool,
}

// The slope map at the Ward half-vector slope m, for the local view o and mirrored lobe
// axis lm (normal +z).
fn slope_point(m: vec2<f32>, o: vec3<f32>, lm: vec3<f32>) -> SlopePoint {
    let k = vec3<f32>(m, 1.0);
    let kk = dot(k, k);
    let ko = dot(k, o);
    let w = (2.0 * ko / kk) * k - o;
    let v = w + lm;
    var p: SlopePoint;
    p.ok = ko > 0.0 && v.z > 0.0;
    let vz = select(1.0, v.z, p.ok);
    p.mp = v.xy / vz;
    // dw/dm_j = 2 (o_j k + (k.wo) e_j) / |k|^2 - 4 (k.wo) m_j k / |k|^4.
    let dwx = (2.0 / kk) * (o.x * k + ko * vec3<f32>(1.0, 0.0, 0.0))
        - (4.0 * ko * m.x / (kk * kk)) * k;
    let dwy = (2.0 / kk) * (o.y * k + ko * vec3<f32>(0.0, 1.0, 0.0))
        - (4.0 * ko * m.y / (kk * kk)) * k;
    // m' = v.xy / v.z: dm' = (dv.xy - m' dv.z) / v.z.
    p.jx = (dwx.xy - p.mp * dwx.z) / vz;
    p.jy = (dwy.xy - p.mp * dwy.z) / vz;
    p.w = kk / ko;
    p.wz = w.z;
    p.dwz = vec2<f32>(dwx.z, dwy.z);
    return p;
}

// Standard normal cdf (Abramowitz & Stegun 7.1.26, |error| < 1.5e-7).
fn normal_cdf(x: f32) -> f32 {
    let z = abs(x) * 0.70710677;
    let t = 1.0 / (1.0 + 0.3275911 * z);
    let poly = t
        * (0.2548296 + t * (-0.28449674 + t * (1.4214137 + t * (-1.4531521 + t * 1.0614054))));
    let half_erfc = 0.5 * poly * exp(-z * z);
    return select(half_erfc, 1.0 - half_erfc, x >= 0.0);
}

// Specular radiance towards wo per unit of irradiance of a lobe of width beta2 about axis
// (where the light comes from) with hemispherical integral norm, on a surface of normal n
// and Ward roughness alpha; without rho_s.
fn lobe_specular(
    n: vec3<f32>,
    wo: vec3<f32>,
    axis: vec3<f32>,
    alpha: f32,
    beta2: f32,
    norm: f32,
) -> f32 {
    let f = frame_of(n);
    let o = vec3<f32>(dot(wo, f.t), dot(wo, f.b), dot(wo, n));
    let l = vec3<f32>(dot(axis, f.t), dot(axis, f.b), dot(axis, n));
    let lm = vec3<f32>(-l.x, -l.y, l.z);
    let h = o + l;
    if !(o.z > 0.0 && h.z > 0.0 && norm > 0.0) {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let b2 = beta2;
    var c = h.xy / h.z;
    var q = 0.0;
    var det = 1.0;
    // The product's covariance in m, (2M)^-1 with M^-1 = a^2 I - a^4 J^T S^-1 J: (xx, xy, yy).
    var cov = vec3<f32>(0.0);
    // The last linearisation, m' ~ b + J m: the nodes compare the light lobe with it.
    var b = vec2<f32>(0.0);
    var jx = vec2<f32>(0.0);
    var jy = vec2<f32>(0.0);
    for (var i = 0u; i < LINEARISATIONS; i++) {
        let p = slope_point(c, o, lm);
        if !p.ok {
            return 0.0;
        }
        // m' ~ b + J m about c; S = b^2 I + a^2 J J^T (rows of J: r0, r1).
        b = p.mp - (p.jx * c.x + p.jy * c.y);
        jx = p.jx;
        jy = p.jy;
        let r0 = vec2<f32>(p.jx.x, p.jy.x);
        let r1 = vec2<f32>(p.jx.y, p.jy.y);
        let s00 = b2 + a2 * dot(r0, r0);
        let s11 = b2 + a2 * dot(r1, r1);
        let s01 = a2 * dot(r0, r1);
        det = s00 * s11 - s01 * s01;
        let sb = vec2<f32>(s11 * b.x - s01 * b.y, s00 * b.y - s01 * b.x) / det;
        q = dot(b, sb);
        // The peak m* = -a^2 J^T S^-1 b.
        c = -a2 * vec2<f32>(dot(p.jx, sb), dot(p.jy, sb));
        // J^T S^-1 J, with S^-1 = [[s11, -s01], [-s01, s00]] / det.
        let sx = vec2<f32>(s11 * p.jx.x - s01 * p.jx.y, s00 * p.jx.y - s01 * p.jx.x) / det;
        let sy = vec2<f32>(s11 * p.jy.x - s01 * p.jy.y, s00 * p.jy.y - s01 * p.jy.x) / det;
        let jsj = vec3<f32>(dot(p.jx, sx), dot(p.jx, sy), dot(p.jy, sy));
        cov = 0.5 * (vec3<f32>(a2, 0.0, a2) - (a2 * a2) * jsj);
    }
    let p = slope_point(c, o, lm);
    if !p.ok {
        return 0.0;
    }
    // The share of the product with w above the horizon, w.n linear in m about the peak.
    let g = p.dwz;
    let v = g.x * g.x * cov.x + 2.0 * g.x * g.y * cov.y + g.y * g.y * cov.z;
    var above = select(0.0, 1.0, p.wz > 0.0);
    if v > 0.0 {
        above = normal_cdf(p.wz / sqrt(v));
    }
    // The mean of r(m) w(m) over the product's Gaussian N(c, cov), r the light lobe over
    // its linearisation, at nodes c + C x with C C^T = cov (Cholesky). Nodes below the
    // horizon or where w is undefined take the peak's w: the horizon is above's.
    let c00 = sqrt(max(cov.x, 0.0));
    let c10 = select(0.0, cov.y / c00, c00 > 0.0);
    let c11 = sqrt(max(cov.z - c10 * c10, 0.0));
    var mean = 0.0;
    for (var i = 0u; i < 3u; i++) {
        let xi = (f32(i) - 1.0) * HERMITE_NODE;
        for (var j = 0u; j < 3u; j++) {
            let xj = (f32(j) - 1.0) * HERMITE_NODE;
            let m = c + vec2<f32>(c00 * xi, c10 * xi + c11 * xj);
            let s = slope_point(m, o, lm);
            var value = p.w;
            if s.ok && s.wz > 0.0 {
                let lin = b + jx * m.x + jy * m.y;
                let r = exp((dot(lin, lin) - dot(s.mp, s.mp)) / b2);
                value = min(r, NODE_RATIO_MAX) * s.w;
            }
            mean += HERMITE_WEIGHTS[i] * HERMITE_WEIGHTS[j] * value;
        }
    }
    return above * mean * exp(-q) / (4.0 * PI * sqrt(det) * norm);
}
