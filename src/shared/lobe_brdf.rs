//! Twin of `wgsl/shared/lobe_brdf.wgsl`: the specular radiance one light lobe reflects
//! towards a view, `I(ωo) = ∫ f_s(ω, ωo) p(ω) dω` (docs/design.md §7), in closed form.
//!
//! Both factors are Gaussians of half-vector slopes: the Ward lobe of the slope m of
//! h(ω, ωo), exactly, and the light lobe of the slope m' of h(ω, L'), L' the mirrored
//! axis. Over m, with dω = 4 (h·ωo) cos³θh dm,
//!
//! ```text
//! I = 1/(4 N) ∫ P_α(m) P_β(m'(m)) / ((h·ωo) cos θh) dm,   P_s(m) = exp(−|m|²/s²) / (π s²)
//! ```
//!
//! with N the light lobe's hemispherical integral. Linearised about the peak of the product,
//! m' ≈ b + J m, the two Gaussians convolve in closed form: `exp(−bᵀS⁻¹b) / (π √det S)`
//! with `S = β² I + α² J Jᵀ`, the view-dependent stretch of the half-vector warp. The peak
//! is found by re-linearising there (`LINEARISATIONS`). The product's share above the
//! horizon (ω·n > 0, linear in m about the peak) is a normal cdf. What the Gaussian leaves
//! out, `1/((h·ωo) cos θh)` and the light lobe's departure from its linearisation, varies
//! across the product for rough surfaces and grazing lobes: its mean over the product's
//! Gaussian is taken at 3 × 3 Gauss–Hermite nodes. `src/convolution/` measures the whole
//! against quadrature.

use glam::{Vec2, Vec3};

use super::sampling::{PI, frame_of};

/// Linearisations of the slope map: the first at the light's mirror configuration, each
/// next one at the peak the previous one found.
pub const LINEARISATIONS: u32 = 2;

/// Gauss–Hermite nodes for a standard normal, exact for polynomials up to degree 5:
/// 0 and ±√3, weights 2/3 and 1/6.
pub const HERMITE_NODE: f32 = 1.732_050_8;
pub const HERMITE_WEIGHTS: [f32; 3] = [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0];

/// The most a node's exact-over-linearised light-lobe ratio may weigh: far out in a broad
/// product the linearised Gaussian's tail can be orders of magnitude below the lobe, and one
/// node must not carry the mean (the study's errors are the same for any bound in 3–16).
pub const NODE_RATIO_MAX: f32 = 8.0;

/// The lobe-norm table: `N(β², cos θL)` at `NORM_COS_NODES` cosines evenly over [0, 1]
/// and `NORM_B2_NODES` values of log2 β² evenly over [`NORM_LOG2_B2_MIN`, 0].
pub const NORM_COS_NODES: u32 = 33;
pub const NORM_B2_NODES: u32 = 33;
pub const NORM_LOG2_B2_MIN: f32 = -16.0;

/// Where a lobe's norm sits in the table: the corner node and the bilinear fractions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormLookup {
    pub index: u32,
    pub fx: f32,
    pub fy: f32,
}

/// x follows cos θL, y follows log2 β²; the node (x, y) is entry `y * NORM_COS_NODES + x`.
pub fn norm_lookup(cos_l: f32, beta2: f32) -> NormLookup {
    let x = cos_l.clamp(0.0, 1.0) * (NORM_COS_NODES - 1) as f32;
    let span = -NORM_LOG2_B2_MIN;
    let y = ((beta2.max(1e-30).log2() - NORM_LOG2_B2_MIN) / span).clamp(0.0, 1.0)
        * (NORM_B2_NODES - 1) as f32;
    let (ix, iy) = (
        (x as u32).min(NORM_COS_NODES - 2),
        (y as u32).min(NORM_B2_NODES - 2),
    );
    NormLookup {
        index: iy * NORM_COS_NODES + ix,
        fx: x - ix as f32,
        fy: y - iy as f32,
    }
}

pub fn norm_at(table: &[f32], l: NormLookup) -> f32 {
    let i = l.index as usize;
    let row = NORM_COS_NODES as usize;
    let lo = table[i] + l.fx * (table[i + 1] - table[i]);
    let hi = table[i + row] + l.fx * (table[i + row + 1] - table[i + row]);
    lo + l.fy * (hi - lo)
}

/// The node values of the table's axes: (cos θL, β²) of node (x, y).
pub fn norm_node(x: u32, y: u32) -> (f32, f32) {
    let c = x as f32 / (NORM_COS_NODES - 1) as f32;
    let t = y as f32 / (NORM_B2_NODES - 1) as f32;
    (c, (NORM_LOG2_B2_MIN * (1.0 - t)).exp2())
}

/// The slope map at the Ward half-vector slope `m`, for the local view `o` and mirrored
/// lobe axis `lm` (normal +z).
#[derive(Clone, Copy, Debug)]
pub struct SlopePoint {
    /// The light lobe's half-vector slope m'.
    pub mp: Vec2,
    /// ∂m'/∂m as columns: ∂m'/∂mx and ∂m'/∂my.
    pub jx: Vec2,
    pub jy: Vec2,
    /// 1 / ((h·ωo) cos θh) = |k|² / (k·ωo) with k = (m, 1).
    pub w: f32,
    /// The incident direction's cosine ω·n and its gradient in m.
    pub wz: f32,
    pub dwz: Vec2,
    /// False where ω is undefined (h·ωo ≤ 0) or the light lobe's half-vector is.
    pub ok: bool,
}

pub fn slope_point(m: Vec2, o: Vec3, lm: Vec3) -> SlopePoint {
    let k = Vec3::new(m.x, m.y, 1.0);
    let kk = k.dot(k);
    let ko = k.dot(o);
    let w = (2.0 * ko / kk) * k - o;
    let v = w + lm;
    let ok = ko > 0.0 && v.z > 0.0;
    let vz = if ok { v.z } else { 1.0 };
    let mp = Vec2::new(v.x, v.y) / vz;
    // ∂ω/∂m_j = 2 (o_j k + (k·ωo) e_j) / |k|² − 4 (k·ωo) m_j k / |k|⁴.
    let dwx = (2.0 / kk) * (o.x * k + ko * Vec3::X) - (4.0 * ko * m.x / (kk * kk)) * k;
    let dwy = (2.0 / kk) * (o.y * k + ko * Vec3::Y) - (4.0 * ko * m.y / (kk * kk)) * k;
    // m' = v.xy / v.z: ∂m' = (∂v.xy − m' ∂v.z) / v.z.
    SlopePoint {
        mp,
        jx: (Vec2::new(dwx.x, dwx.y) - mp * dwx.z) / vz,
        jy: (Vec2::new(dwy.x, dwy.y) - mp * dwy.z) / vz,
        w: kk / ko,
        wz: w.z,
        dwz: Vec2::new(dwx.z, dwy.z),
        ok,
    }
}

/// Standard normal cdf (Abramowitz & Stegun 7.1.26, |error| < 1.5e-7).
pub fn normal_cdf(x: f32) -> f32 {
    let z = x.abs() * std::f32::consts::FRAC_1_SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * z);
    let poly = t
        * (0.254_829_6
            + t * (-0.284_496_74 + t * (1.421_413_7 + t * (-1.453_152_1 + t * 1.061_405_4))));
    let half_erfc = 0.5 * poly * (-z * z).exp();
    if x >= 0.0 { 1.0 - half_erfc } else { half_erfc }
}

/// Specular radiance towards `wo` per unit of irradiance of a lobe of width `beta2` about
/// `axis` (where the light comes from) with hemispherical integral `norm`, on a surface of
/// normal `n` and Ward roughness `alpha`; without ρs.
pub fn lobe_specular(n: Vec3, wo: Vec3, axis: Vec3, alpha: f32, beta2: f32, norm: f32) -> f32 {
    let f = frame_of(n);
    let o = Vec3::new(wo.dot(f.t), wo.dot(f.b), wo.dot(n));
    let l = Vec3::new(axis.dot(f.t), axis.dot(f.b), axis.dot(n));
    let lm = Vec3::new(-l.x, -l.y, l.z);
    let h = o + l;
    if !(o.z > 0.0 && h.z > 0.0 && norm > 0.0) {
        return 0.0;
    }
    let (a2, b2) = (alpha * alpha, beta2);
    let mut c = Vec2::new(h.x, h.y) / h.z;
    let mut q = 0.0;
    let mut det = 1.0;
    // The product's covariance in m, (2M)⁻¹ with M⁻¹ = α² I − α⁴ Jᵀ S⁻¹ J: (xx, xy, yy).
    let mut cov = Vec3::ZERO;
    // The last linearisation, m' ≈ b + J m: the nodes compare the light lobe with it.
    let (mut b, mut jx, mut jy) = (Vec2::ZERO, Vec2::ZERO, Vec2::ZERO);
    for _ in 0..LINEARISATIONS {
        let p = slope_point(c, o, lm);
        if !p.ok {
            return 0.0;
        }
        // m' ≈ b + J m about c; S = β² I + α² J Jᵀ (rows of J: r0, r1).
        b = p.mp - (p.jx * c.x + p.jy * c.y);
        (jx, jy) = (p.jx, p.jy);
        let r0 = Vec2::new(p.jx.x, p.jy.x);
        let r1 = Vec2::new(p.jx.y, p.jy.y);
        let s00 = b2 + a2 * r0.dot(r0);
        let s11 = b2 + a2 * r1.dot(r1);
        let s01 = a2 * r0.dot(r1);
        det = s00 * s11 - s01 * s01;
        let sb = Vec2::new(s11 * b.x - s01 * b.y, s00 * b.y - s01 * b.x) / det;
        q = b.dot(sb);
        // The peak m* = −α² Jᵀ S⁻¹ b.
        c = -a2 * Vec2::new(p.jx.dot(sb), p.jy.dot(sb));
        // Jᵀ S⁻¹ J, with S⁻¹ = [[s11, −s01], [−s01, s00]] / det.
        let sx = Vec2::new(s11 * p.jx.x - s01 * p.jx.y, s00 * p.jx.y - s01 * p.jx.x) / det;
        let sy = Vec2::new(s11 * p.jy.x - s01 * p.jy.y, s00 * p.jy.y - s01 * p.jy.x) / det;
        let jsj = Vec3::new(p.jx.dot(sx), p.jx.dot(sy), p.jy.dot(sy));
        cov = 0.5 * (Vec3::new(a2, 0.0, a2) - (a2 * a2) * jsj);
    }
    let p = slope_point(c, o, lm);
    if !p.ok {
        return 0.0;
    }
    // The share of the product with ω above the horizon, ω·n linear in m about the peak.
    let g = p.dwz;
    let var = g.x * g.x * cov.x + 2.0 * g.x * g.y * cov.y + g.y * g.y * cov.z;
    let above = if var > 0.0 {
        normal_cdf(p.wz / var.sqrt())
    } else if p.wz > 0.0 {
        1.0
    } else {
        0.0
    };
    // The mean of r(m) w(m) over the product's Gaussian N(c, cov), r the light lobe over
    // its linearisation, at nodes c + C x with C C^T = cov (Cholesky). Nodes below the
    // horizon or where ω is undefined take the peak's w: the horizon is `above`'s.
    let c00 = cov.x.max(0.0).sqrt();
    let c10 = if c00 > 0.0 { cov.y / c00 } else { 0.0 };
    let c11 = (cov.z - c10 * c10).max(0.0).sqrt();
    let mut mean = 0.0;
    for (i, wi) in HERMITE_WEIGHTS.iter().enumerate() {
        let xi = (i as f32 - 1.0) * HERMITE_NODE;
        for (j, wj) in HERMITE_WEIGHTS.iter().enumerate() {
            let xj = (j as f32 - 1.0) * HERMITE_NODE;
            let m = c + Vec2::new(c00 * xi, c10 * xi + c11 * xj);
            let s = slope_point(m, o, lm);
            let value = if s.ok && s.wz > 0.0 {
                let lin = b + jx * m.x + jy * m.y;
                let r = ((lin.length_squared() - s.mp.length_squared()) / b2).exp();
                r.min(NODE_RATIO_MAX) * s.w
            } else {
                p.w
            };
            mean += wi * wj * value;
        }
    }
    above * mean * (-q).exp() / (4.0 * PI * det.sqrt() * norm)
}
