//! Twin of `wgsl/shared/ward.wgsl`: the isotropic Ward BRDF (Dür normalisation) and its
//! importance sampling (Ward 1992, pdf from Walter 2005). Directions point away from the
//! surface; `wi` is where light comes from.

use glam::Vec3;

use super::sampling::{Frame, PI, polar, to_world};

/// Specular part without ρs: `exp(−tan²θh/α²) / (4π α² cosθi cosθo)`.
pub fn ward_specular(n: Vec3, wi: Vec3, wo: Vec3, alpha: f32) -> f32 {
    let ci = n.dot(wi);
    let co = n.dot(wo);
    if ci <= 0.0 || co <= 0.0 {
        return 0.0;
    }
    let h = (wi + wo).normalize();
    let ch = n.dot(h);
    let a2 = alpha * alpha;
    let tan2 = (1.0 - ch * ch).max(0.0) / (ch * ch);
    (-tan2 / a2).exp() / (4.0 * PI * a2 * ci * co)
}

/// Half-vector in the local frame (z = normal): tan²θh = −α² ln(1 − u1), φ = 2π u2.
pub fn ward_half_vector(u1: f32, u2: f32, alpha: f32) -> Vec3 {
    let tan2 = -alpha * alpha * (1.0 - u1).ln();
    polar(1.0 / (1.0 + tan2).sqrt(), u2)
}

/// Walter's pdf of `wo = reflect(wi, h)`: `exp(−tan²θh/α²) / (4π α² (h·wi) cos³θh)`.
pub fn ward_pdf(n: Vec3, wi: Vec3, wo: Vec3, alpha: f32) -> f32 {
    let h = (wi + wo).normalize();
    let ch = n.dot(h);
    let hi = h.dot(wi);
    if ch <= 0.0 || hi <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let tan2 = (1.0 - ch * ch).max(0.0) / (ch * ch);
    (-tan2 / a2).exp() / (4.0 * PI * a2 * hi * ch * ch * ch)
}

#[derive(Clone, Copy, Debug)]
pub struct WardSample {
    pub wo: Vec3,
    /// `f_s cosθo / pdf` without ρs: `(h·wi) cos³θh / cosθi`; 0 when `wo` is below the surface.
    pub weight: f32,
}

pub fn ward_sample(f: &Frame, wi: Vec3, u1: f32, u2: f32, alpha: f32) -> WardSample {
    let h = to_world(f, ward_half_vector(u1, u2, alpha));
    let hi = h.dot(wi);
    let wo = 2.0 * hi * h - wi;
    let ci = f.n.dot(wi);
    let co = f.n.dot(wo);
    let ch = f.n.dot(h);
    let ok = co > 0.0 && hi > 0.0 && ci > 0.0;
    WardSample {
        wo,
        weight: if ok { hi * ch * ch * ch / ci } else { 0.0 },
    }
}
