//! The table of light-lobe norms every frame's shading divides by (`shared::lobe_brdf`): the
//! hemispherical integral of a Ward-like lobe `exp(−tan²δ/β²) / (4πβ²)` at each node of
//! (cos θL, log2 β²), δ the angle between the normal and the half-vector of ω and the lobe's
//! mirrored axis. No closed form holds once the horizon cuts a broad or grazing lobe
//! (cos θL · κ(β²) is 14 % off at β² = 1 even at normal incidence), so the nodes are integrated
//! by quadrature in f64, once per process. The convolution study (`convolution`) builds its
//! reference integrals on the same quadrature.

use std::f64::consts::PI;
use std::sync::OnceLock;

use glam::DVec3;
use rayon::prelude::*;

use crate::shared::lobe_brdf::{NORM_B2_NODES, NORM_COS_NODES, norm_node};

/// Quadrature points per edge of the lobe's sample map (the reference tests use 32–64).
const NORM_QUADRATURE: usize = 64;

/// `NORM_COS_NODES × NORM_B2_NODES` norms, rows of constant β².
pub fn lobe_norms() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        (0..NORM_COS_NODES * NORM_B2_NODES)
            .into_par_iter()
            .map(|i| {
                let (cos_l, beta2) = norm_node(i % NORM_COS_NODES, i / NORM_COS_NODES);
                let mirror = mirrored_axis((cos_l as f64).acos());
                lobe_norm(mirror, beta2 as f64, NORM_QUADRATURE) as f32
            })
            .collect()
    })
}

/// The axis of a lobe at `angle` from the normal (+z), in the xz plane, mirrored about the
/// normal: the lobe's half-vectors are taken with it.
pub fn mirrored_axis(angle: f64) -> DVec3 {
    DVec3::new(-angle.sin(), 0.0, angle.cos())
}

/// ∫_H lobe dω of the lobe of width `beta2` about `mirror`, by `n²` points of the lobe's own
/// sample map: there lobe / pdf = cos³θh (h · mirror), smooth, so no weights are needed.
pub fn lobe_norm(mirror: DVec3, beta2: f64, n: usize) -> f64 {
    let sum: f64 = grid(n)
        .map(|(u1, u2)| {
            let h = half_vector(u1, u2, beta2);
            let w = reflect(mirror, h);
            if w.z > 0.0 {
                h.z.powi(3) * h.dot(mirror)
            } else {
                0.0
            }
        })
        .sum();
    sum / (n * n) as f64
}

/// tan² of the angle between the normal (+z) and `h` (any length, h.z > 0).
pub fn tan2(h: DVec3) -> f64 {
    (h.x * h.x + h.y * h.y) / (h.z * h.z)
}

/// A half-vector by Ward's map of the unit square: tan²θh = −w² ln(1 − u1), φ = 2π u2.
pub fn half_vector(u1: f64, u2: f64, width2: f64) -> DVec3 {
    let t2 = -width2 * (1.0 - u1).ln();
    let c = 1.0 / (1.0 + t2).sqrt();
    let s = t2.sqrt() * c;
    let phi = 2.0 * PI * u2;
    DVec3::new(s * phi.cos(), s * phi.sin(), c)
}

/// `h` reflects `about` to this direction.
pub fn reflect(about: DVec3, h: DVec3) -> DVec3 {
    2.0 * h.dot(about) * h - about
}

/// Midpoints of an n × n grid over the unit square.
pub fn grid(n: usize) -> impl Iterator<Item = (f64, f64)> {
    let step = 1.0 / n as f64;
    (0..n * n).map(move |k| (((k % n) as f64 + 0.5) * step, ((k / n) as f64 + 0.5) * step))
}
