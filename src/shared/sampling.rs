//! Twin of `wgsl/shared/sampling.wgsl`: frames and direction sampling.

use glam::{Vec2, Vec3};

pub const PI: f32 = std::f32::consts::PI;

/// Orthonormal tangents (t, b) with t × b = n for a unit n (Duff et al. 2017, branch-free).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub t: Vec3,
    pub b: Vec3,
    pub n: Vec3,
}

pub fn frame_of(n: Vec3) -> Frame {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    Frame {
        t: Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        b: Vec3::new(b, s + n.y * n.y * a, -n.y),
        n,
    }
}

pub fn to_world(f: &Frame, v: Vec3) -> Vec3 {
    f.t * v.x + f.b * v.y + f.n * v.z
}

/// Direction at polar cosine `c` and azimuth 2πu about +z.
pub fn polar(c: f32, u: f32) -> Vec3 {
    let s = (1.0 - c * c).max(0.0).sqrt();
    let phi = 2.0 * PI * u;
    Vec3::new(s * phi.cos(), s * phi.sin(), c)
}

/// Cosine-weighted hemisphere about +z (pdf cos θ / π).
pub fn sample_cosine(u1: f32, u2: f32) -> Vec3 {
    polar((1.0 - u1).sqrt(), u2)
}

pub fn sample_sphere(u1: f32, u2: f32) -> Vec3 {
    polar(1.0 - 2.0 * u1, u2)
}

/// Uniform in the cone cos θ ≥ `cos_max` about +z.
pub fn sample_cone(u1: f32, u2: f32, cos_max: f32) -> Vec3 {
    polar(1.0 - u1 * (1.0 - cos_max), u2)
}

/// Uniform in the unit disk.
pub fn sample_disk(u1: f32, u2: f32) -> Vec2 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// WGSL's `smoothstep` (edge0 < edge1).
pub fn smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The power heuristic's weight of a strategy of pdf `a` against one of pdf `b` (each pdf
/// times its sample count).
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    if a2 > 0.0 { a2 / (a2 + b * b) } else { 0.0 }
}
