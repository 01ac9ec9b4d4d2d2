//! The lobe × BRDF convolution study (docs/design.md §7, thesis §4.1): how far a closed-form
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

use crate::lobe_norms::{grid, half_vector, lobe_norm, lobe_norms, mirrored_axis, reflect, tan2};
use crate::shared::lobe_brdf::{lobe_specular, norm_at, norm_lookup};
use std::f64::consts::PI;

pub mod errors;

pub use errors::{
    CaseError, Quality, Summary, ViewGrid, case_error, errors, study_grid, summary, thesis_grid,
};

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
        mirrored_axis(self.angle)
    }
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

/// Dür's Ward specular lobe without ρs, `exp(−tan²θh/α²) / (4π α² cos θi cos θo)`, which
/// the thesis integrated against (`shared::ward::ward_specular_dur` in f64).
pub fn ward_dur(wi: DVec3, wo: DVec3, alpha: f64) -> f64 {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return 0.0;
    }
    let h = (wi + wo).normalize();
    let a2 = alpha * alpha;
    (-tan2(h) / a2).exp() / (4.0 * PI * a2 * wi.z * wo.z)
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

/// Density over directions of `reflect(about, h)` with `h` from `half_vector(·, ·, width2)`.
fn reflected_pdf(w: DVec3, about: DVec3, width2: f64) -> f64 {
    let h = (w + about).normalize();
    let hd = h.dot(about);
    if h.z <= 0.0 || hd <= 0.0 {
        return 0.0;
    }
    (-tan2(h) / width2).exp() / (PI * width2 * h.z.powi(3) * 4.0 * hd)
}

/// What the integral stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Convention {
    /// The renderer's: the lobe is a unit-integral density of irradiance and `f_s` the
    /// bounded-albedo Ward, `I = ∫ f_s p dω`.
    Renderer,
    /// The thesis's §4.1: the lobe as it stands (its integral is about cos θL), Dür's Ward
    /// and the cosine, `I = ∫ lobe_shape · f_Dür · cos θ dω`.
    Thesis,
}

/// The reference integral of one case with `n²` points per sample map.
pub struct Reference {
    case: Case,
    convention: Convention,
    mirror: DVec3,
    n: usize,
    /// ∫_H lobe_shape dω: the lobe's density is `lobe_shape / norm`.
    pub norm: f64,
}

impl Reference {
    pub fn new(case: Case, n: usize) -> Reference {
        Reference::with(case, Convention::Renderer, n)
    }

    pub fn with(case: Case, convention: Convention, n: usize) -> Reference {
        let mirror = case.mirror();
        Reference {
            case,
            convention,
            mirror,
            n,
            norm: lobe_norm(mirror, case.beta2, n),
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
            if pdf <= 0.0 {
                return 0.0;
            }
            match self.convention {
                Convention::Renderer => ward(w, wo, alpha) * self.density(w) / pdf,
                Convention::Thesis => {
                    ward_dur(w, wo, alpha) * w.z * shape_about(mirror, b2, w) / pdf
                }
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
    /// The renderer's shading, `shared::lobe_brdf::lobe_specular` (f32) with the norm from
    /// `lobe_norms`: what the GPU and CPU frames compute.
    Ours,
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
            Formula::Ours => {
                let (n, axis) = (glam::Vec3::Z, case.axis().as_vec3());
                let beta2 = case.beta2 as f32;
                let norm = norm_at(lobe_norms(), norm_lookup(axis.z, beta2));
                let (wo, alpha) = (wo.as_vec3(), case.alpha as f32);
                lobe_specular(n, wo, axis, alpha, beta2, norm) as f64
            }
        }
    }
}
