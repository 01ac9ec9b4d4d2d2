//! Errors of a formula against the reference: views, per-case relative L2 and energy
//! errors, their quantiles, and the grids of cases the study runs over.

use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

use super::{Case, Convention, Formula, Reference};

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
    /// Relative L2 error over view angles up to 60°; none where the response lies outside.
    pub l2_60: Option<f64>,
    /// Relative L2 error over view angles up to 85°.
    pub l2_85: Option<f64>,
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

pub fn case_error(
    case: &Case,
    convention: Convention,
    formulas: &[Formula],
    q: Quality,
) -> Vec<CaseError> {
    let reference = Reference::with(*case, convention, q.inner);
    let views = ViewGrid::new(case, q.radial, q.around);
    let exact: Vec<f64> = views
        .points
        .iter()
        .map(|(w, _)| reference.radiance(*w))
        .collect();
    let in_cap = |w: DVec3, cap: f64| w.z >= cap.to_radians().cos();
    let energy_of = |values: &[f64]| -> f64 {
        views
            .points
            .iter()
            .zip(values)
            .filter(|((w, _), _)| w.z > 0.0)
            .map(|((w, dw), v)| v * w.z * dw)
            .sum()
    };
    let exact_energy = energy_of(&exact);
    let total: f64 = views
        .points
        .iter()
        .zip(&exact)
        .filter(|((w, _), _)| w.z > 0.0)
        .map(|((_, dw), e)| e * e * dw)
        .sum();
    formulas
        .iter()
        .map(|f| {
            let approx: Vec<f64> = views
                .points
                .iter()
                .map(|(w, _)| f.radiance(case, *w))
                .collect();
            let energy = energy_of(&approx);
            // ‖formula − exact‖ / ‖exact‖ over the views within `cap` degrees; none where
            // the cap holds under 1 % of the response's squared norm.
            let l2 = |cap: f64| -> Option<f64> {
                let (mut d, mut e2) = (0.0, 0.0);
                for (((w, dw), a), e) in views.points.iter().zip(&approx).zip(&exact) {
                    if w.z > 0.0 && in_cap(*w, cap) {
                        d += (a - e) * (a - e) * dw;
                        e2 += e * e * dw;
                    }
                }
                (e2 > 0.01 * total).then(|| (d / e2).sqrt())
            };
            CaseError {
                l2_60: l2(60.0),
                l2_85: l2(85.0),
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
pub fn errors(
    cases: &[Case],
    convention: Convention,
    formulas: &[Formula],
    q: Quality,
) -> Vec<Vec<CaseError>> {
    cases
        .par_iter()
        .map(|c| case_error(c, convention, formulas, q))
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
    let mut l2: Vec<f64> = errors.iter().filter_map(|e| e.l2_60).collect();
    let mut l2_85: Vec<f64> = errors.iter().filter_map(|e| e.l2_85).collect();
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

/// The study's grid (docs/design.md §7): α ∈ {0.02, 0.065, 0.15, 0.3}, 12 values of β spaced
/// evenly in log from 0.01 to 1, lobe angles 0–85° in steps of 5°.
pub fn study_grid() -> Vec<Case> {
    let mut cases = Vec::new();
    for alpha in STUDY_ALPHAS {
        for i in 0..STUDY_BETAS {
            let beta = 0.01 * 100f64.powf(i as f64 / (STUDY_BETAS - 1) as f64);
            for j in 0..STUDY_ANGLES {
                cases.push(Case {
                    alpha,
                    beta2: beta * beta,
                    angle: (5.0 * j as f64).to_radians(),
                });
            }
        }
    }
    cases
}

pub const STUDY_ALPHAS: [f64; 4] = [0.02, 0.065, 0.15, 0.3];
pub const STUDY_BETAS: usize = 12;
pub const STUDY_ANGLES: usize = 18;
