//! The lobe × BRDF convolution study (DESIGN.md §7, thesis §4.1): how far a closed-form
//! shading formula is from the integral it stands for.
//!
//! A splat's lobes fit the directions of the photons it gathered, weighted by power, so a lobe
//! `p(ω)` (unit integral over the hemisphere) is a density of *irradiance*: the cosine of the
//! incident direction is already in it. The specular radiance that one unit of lobe
//! irradiance reflects towards `ωo` is then
//!
//! ```text
//! I(ωo) = ∫_H f_s(ω, ωo) p(ω) dω
//! ```
//!
//! with `f_s` the renderer's Ward specular lobe (the bounded-albedo form of `shared::ward`,
//! without ρs). `I` is computed here by quadrature in f64: both factors are sharp lobes, so
//! the integral is split between two sample maps, one following the light lobe and one the
//! BRDF around `ωo`, combined by the balance heuristic; each map is a midpoint grid in its
//! unit square, so the result is deterministic and converges as the grid is refined.
//!
//! The frame is local: the normal is +z, a lobe's axis lies in the xz plane at `angle` from
//! the normal. Errors of a formula per lobe are relative L2 norms over view directions up to
//! a view angle (60° and 85°) and the error of the reflected energy over the hemisphere.
//! `ward`, `half_vector` and `reflected_pdf` are f64 twins of `shared::ward`'s
//! `ward_specular`, `ward_half_vector` and `ward_pdf`: the reference needs the precision.

use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// One light lobe of the thesis's (Ward-like) family on a surface of roughness `alpha`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Case {
    pub alpha: f64,
    /// The lobe's width β² (`1 / sharpness` of a stored Ward-like lobe).
    pub beta2: f64,
    /// Angle between the lobe's axis and the normal, radians.
    pub angle: f64,
}

impl Case {
    /// The axis `L` the light comes from.
    pub fn axis(&self) -> DVec3 {
        DVec3::new(self.angle.sin(), 0.0, self.angle.cos())
    }

    /// The axis mirrored about the normal: the lobe's half-vectors are taken with it, and
    /// it is where a mirror would send the light.
    pub fn mirror(&self) -> DVec3 {
        DVec3::new(-self.angle.sin(), 0.0, self.angle.cos())
    }
}

/// tan² of the angle between the normal (+z) and `h` (any length, h.z > 0).
fn tan2(h: DVec3) -> f64 {
    (h.x * h.x + h.y * h.y) / (h.z * h.z)
}

/// The renderer's Ward specular lobe without ρs (`shared::ward::ward_specular` in f64).
pub fn ward(wi: DVec3, wo: DVec3, alpha: f64) -> f64 {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return 0.0;
    }
    let h = (wi + wo).normalize();
    let a2 = alpha * alpha;
    let hi = h.dot(wi);
    (-tan2(h) / a2).exp() / (4.0 * PI * a2 * hi * hi * h.z.powi(4))
}

/// The thesis's lobe before normalisation: `exp(−tan²δ/β²) / (4πβ²)`, δ the angle between
/// the normal and the half-vector of ω and the mirrored axis.
pub fn lobe_shape(case: &Case, w: DVec3) -> f64 {
    shape_about(case.mirror(), case.beta2, w)
}

/// `lobe_shape` with the mirrored axis already computed (the quadrature's inner loop).
fn shape_about(mirror: DVec3, beta2: f64, w: DVec3) -> f64 {
    let h = w + mirror;
    if w.z <= 0.0 || h.z <= 0.0 {
        return 0.0;
    }
    (-tan2(h) / beta2).exp() / (4.0 * PI * beta2)
}

/// A half-vector by Ward's map of the unit square: tan²θh = −w² ln(1 − u1), φ = 2π u2.
fn half_vector(u1: f64, u2: f64, width2: f64) -> DVec3 {
    let t2 = -width2 * (1.0 - u1).ln();
    let c = 1.0 / (1.0 + t2).sqrt();
    let s = t2.sqrt() * c;
    let phi = 2.0 * PI * u2;
    DVec3::new(s * phi.cos(), s * phi.sin(), c)
}

/// Density over directions of `reflect(about, h)` with `h` from `half_vector(·, ·, width2)`.
fn reflected_pdf(w: DVec3, about: DVec3, width2: f64) -> f64 {
    let h = (w + about).normalize();
    let hd = h.dot(about);
    if h.z <= 0.0 || hd <= 0.0 {
        return 0.0;
    }
    (-tan2(h) / width2).exp() / (PI * width2 * h.z.powi(3) * 4.0 * hd)
}

fn reflect(about: DVec3, h: DVec3) -> DVec3 {
    2.0 * h.dot(about) * h - about
}

/// Midpoints of an n × n grid over the unit square.
fn grid(n: usize) -> impl Iterator<Item = (f64, f64)> {
    let step = 1.0 / n as f64;
    (0..n * n).map(move |k| (((k % n) as f64 + 0.5) * step, ((k / n) as f64 + 0.5) * step))
}

/// The reference integral of one case with `n²` points per sample map.
pub struct Reference {
    case: Case,
    mirror: DVec3,
    n: usize,
    /// ∫_H lobe_shape dω: the lobe's density is `lobe_shape / norm`.
    pub norm: f64,
}

impl Reference {
    pub fn new(case: Case, n: usize) -> Reference {
        // Under the lobe's own map lobe_shape / pdf = cos³θh (h·L'): smooth, no weights.
        let mirror = case.mirror();
        let sum: f64 = grid(n)
            .map(|(u1, u2)| {
                let h = half_vector(u1, u2, case.beta2);
                let w = reflect(mirror, h);
                if w.z > 0.0 {
                    h.z.powi(3) * h.dot(mirror)
                } else {
                    0.0
                }
            })
            .sum();
        Reference {
            case,
            mirror,
            n,
            norm: sum / (n * n) as f64,
        }
    }

    /// The lobe's unit-integral density.
    pub fn density(&self, w: DVec3) -> f64 {
        shape_about(self.mirror, self.case.beta2, w) / self.norm
    }

    /// `I(ωo)`: the radiance towards `wo` per unit of the lobe's irradiance.
    pub fn radiance(&self, wo: DVec3) -> f64 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        let (mirror, alpha) = (self.mirror, self.case.alpha);
        let (b2, a2) = (self.case.beta2, alpha * alpha);
        let term = |w: DVec3| {
            if w.z <= 0.0 {
                return 0.0;
            }
            let pdf = reflected_pdf(w, mirror, b2) + reflected_pdf(w, wo, a2);
            if pdf > 0.0 {
                ward(w, wo, alpha) * self.density(w) / pdf
            } else {
                0.0
            }
        };
        let sum: f64 = grid(self.n)
            .map(|(u1, u2)| {
                term(reflect(mirror, half_vector(u1, u2, b2)))
                    + term(reflect(wo, half_vector(u1, u2, a2)))
            })
            .sum();
        sum / (self.n * self.n) as f64
    }
}

/// A closed form of `I(ωo)` to measure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Formula {
    /// The thesis's widened lobe `exp(−tan²δ/(α²+β²)) / (4π(α²+β²))` divided by `scale`
    /// (the thesis used 1.81), δ the angle between the normal and the half-vector of ωo and L.
    Thesis { scale: f64 },
}

impl Formula {
    pub fn radiance(&self, case: &Case, wo: DVec3) -> f64 {
        match *self {
            Formula::Thesis { scale } => {
                let h = wo + case.axis();
                if wo.z <= 0.0 || h.z <= 0.0 {
                    return 0.0;
                }
                let s2 = case.alpha * case.alpha + case.beta2;
                (-tan2(h) / s2).exp() / (4.0 * PI * s2 * scale)
            }
        }
    }
}

/// View directions for the errors of one case: a polar grid around the mirror direction,
/// radii growing geometrically from a fraction of the response's width out to π, so sharp
/// and broad responses are both resolved. Each point has its solid angle.
pub struct ViewGrid {
    pub points: Vec<(DVec3, f64)>,
}

impl ViewGrid {
    pub fn new(case: &Case, radial: usize, around: usize) -> ViewGrid {
        let width = 2.0 * (case.alpha * case.alpha + case.beta2).sqrt();
        // r(x) = π (e^{kx} − 1) / (e^k − 1) over x in [0, 1]; its first step is about a
        // tenth of the width (k found by bisection; k → 0 is the uniform grid).
        let first = (width * 0.1).min(PI / radial as f64);
        let radius = |k: f64, x: f64| PI * ((k * x).exp() - 1.0) / (k.exp() - 1.0);
        let (mut lo, mut hi) = (1e-6, 200.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if radius(mid, 1.0 / radial as f64) > first {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let k = 0.5 * (lo + hi);
        let r_of = |x: f64| radius(k, x);
        let centre = case.mirror();
        let t = DVec3::new(centre.z, 0.0, -centre.x);
        let b = DVec3::Y;
        let mut points = Vec::with_capacity(radial * around);
        for i in 0..radial {
            let (r0, r1) = (
                r_of(i as f64 / radial as f64),
                r_of((i + 1) as f64 / radial as f64),
            );
            let r = 0.5 * (r0 + r1);
            // Solid angle of the ring, split evenly: 2π (cos r0 − cos r1) / around.
            let ring = 2.0 * PI * (r0.cos() - r1.cos()) / around as f64;
            for j in 0..around {
                let phi = 2.0 * PI * (j as f64 + 0.5) / around as f64;
                let w = r.cos() * centre + r.sin() * (phi.cos() * t + phi.sin() * b);
                points.push((w, ring));
            }
        }
        ViewGrid { points }
    }
}

/// The errors of a formula on one case.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct CaseError {
    /// Relative L2 error over view angles up to 60°.
    pub l2_60: f64,
    /// Relative L2 error over view angles up to 85°.
    pub l2_85: f64,
    /// |reflected energy of the formula − of the integral| / that of the integral.
    pub energy: f64,
}

/// Quadrature sizes: points per sample map edge, view rings and points per ring.
#[derive(Clone, Copy, Debug)]
pub struct Quality {
    pub inner: usize,
    pub radial: usize,
    pub around: usize,
}

impl Default for Quality {
    fn default() -> Quality {
        Quality {
            inner: 32,
            radial: 48,
            around: 32,
        }
    }
}

pub fn case_error(case: &Case, formulas: &[Formula], q: Quality) -> Vec<CaseError> {
    let reference = Reference::new(*case, q.inner);
    let views = ViewGrid::new(case, q.radial, q.around);
    let exact: Vec<f64> = views
        .points
        .iter()
        .map(|(w, _)| reference.radiance(*w))
        .collect();
    let cos60 = (60f64).to_radians().cos();
    let cos85 = (85f64).to_radians().cos();
    formulas
        .iter()
        .map(|f| {
            // (∫ (formula − exact)², ∫ exact²) within each view cap; reflected energies.
            let (mut cap60, mut cap85) = ([0.0f64; 2], [0.0f64; 2]);
            let (mut energy, mut exact_energy) = (0.0f64, 0.0f64);
            for ((w, dw), &e) in views.points.iter().zip(&exact) {
                if w.z <= 0.0 {
                    continue;
                }
                let a = f.radiance(case, *w);
                let sq = [(a - e) * (a - e) * dw, e * e * dw];
                for (cap, cos_cap) in [(&mut cap60, cos60), (&mut cap85, cos85)] {
                    if w.z >= cos_cap {
                        cap[0] += sq[0];
                        cap[1] += sq[1];
                    }
                }
                energy += a * w.z * dw;
                exact_energy += e * w.z * dw;
            }
            let ratio = |[d, e]: [f64; 2]| if e > 0.0 { (d / e).sqrt() } else { 0.0 };
            CaseError {
                l2_60: ratio(cap60),
                l2_85: ratio(cap85),
                energy: if exact_energy > 0.0 {
                    (energy - exact_energy).abs() / exact_energy
                } else {
                    0.0
                },
            }
        })
        .collect()
}

/// Errors over many cases, in parallel; `out[c][f]` is case c under formula f.
pub fn errors(cases: &[Case], formulas: &[Formula], q: Quality) -> Vec<Vec<CaseError>> {
    cases
        .par_iter()
        .map(|c| case_error(c, formulas, q))
        .collect()
}

/// What `bench convolution` prints per formula: quantiles of the per-lobe errors.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Summary {
    pub median: f64,
    pub p95: f64,
    pub max: f64,
    pub max_to_85: f64,
    pub energy_error: f64,
    pub energy_error_p95: f64,
}

fn quantile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let i = ((values.len() - 1) as f64 * q).round() as usize;
    values[i]
}

pub fn summary(errors: &[CaseError]) -> Summary {
    let mut l2: Vec<f64> = errors.iter().map(|e| e.l2_60).collect();
    let mut l2_85: Vec<f64> = errors.iter().map(|e| e.l2_85).collect();
    let mut energy: Vec<f64> = errors.iter().map(|e| e.energy).collect();
    Summary {
        median: quantile(&mut l2, 0.5),
        p95: quantile(&mut l2, 0.95),
        max: quantile(&mut l2, 1.0),
        max_to_85: quantile(&mut l2_85, 1.0),
        energy_error: quantile(&mut energy, 0.5),
        energy_error_p95: quantile(&mut energy, 0.95),
    }
}

/// The thesis's grid (§4.1): α = 0.065, β from 0.01 to 0.5 in 21 steps, lobe angles 0–90°
/// in 19 steps (90° itself lies in the surface and reflects nothing, so it stops at 89.9°).
pub fn thesis_grid() -> Vec<Case> {
    let mut cases = Vec::new();
    for i in 0..21 {
        let beta = 0.01 + 0.49 * i as f64 / 20.0;
        for j in 0..19 {
            let angle = (5.0 * j as f64).min(89.9).to_radians();
            cases.push(Case {
                alpha: 0.065,
                beta2: beta * beta,
                angle,
            });
        }
    }
    cases
}
