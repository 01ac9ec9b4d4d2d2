//! Gaussian-splat captures in PLY (3D Gaussian Splatting and 2D Gaussian Splatting): each
//! Gaussian becomes one splat. Its position is the Gaussian's mean; its normal the rotation's
//! axis of least scale (3DGS: scales `scale_0..2`), or the surfel's normal, the rotation's third
//! axis (2DGS: `scale_0..1`); its radius twice the geometric mean of the two in-plane scales
//! (the ellipse's 2σ); its diffuse albedo the view-independent colour of the spherical
//! harmonics' DC term, 0.5 + C₀ f_dc. Gaussians whose opacity (a logit in the file) is under
//! `OPACITY_MIN` are left out. A captured colour carries the light of the capture: lit again by
//! the scene's lights it is an albedo only as far as the capture's light was even.
//! Gaussians' normals have no sign, so they are oriented as a point cloud's are
//! (`normals::orient_normals`).

// `!(x >= y)` is meant: a NaN opacity or rotation leaves the Gaussian out.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Quat, Vec3};

/// Opacities below this leave their Gaussian out: faint ones are the capture's haze and
/// floaters, not surfaces.
pub const OPACITY_MIN: f32 = 0.5;
/// The DC spherical-harmonic basis constant, 1 / (2 √π).
const SH_C0: f32 = 0.282_094_8;
/// The splat's radius in units of the Gaussian's in-plane scale.
const RADIUS_SIGMAS: f32 = 2.0;

/// The columns of a vertex element that make it a Gaussian: f_dc_0..2, opacity, scale_0..1
/// (and scale_2 for 3DGS), rot_0..3 (w, x, y, z).
#[derive(Clone, Copy, Debug)]
pub struct Columns {
    pub dc: [usize; 3],
    pub opacity: usize,
    pub scale: [usize; 2],
    pub scale_2: Option<usize>,
    pub rot: [usize; 4],
}

/// One Gaussian, read from `values` (a vertex's property values).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gaussian {
    pub normal: Vec3,
    pub radius: f32,
    /// sRGB in [0, 1].
    pub color: [f32; 3],
}

/// The rules that leave a Gaussian out, in the words `LeftOut` counts them by.
pub const FAINT: &str = "Gaussians fainter than opacity 0.5 (a logit below 0 in the file)";
pub const NO_ROTATION: &str =
    "Gaussians whose rotation is zero, too short to normalise or not finite";
pub const NO_RADIUS: &str =
    "Gaussians of zero radius (log scales below -87: exp() rounds them to 0)";
pub const HUGE: &str =
    "Gaussians whose scale overflows f32 (a log scale above 88) or is not a number";
pub const NO_COLOUR: &str = "Gaussians whose colour is not finite";

/// The splat of the Gaussian in `values`, or the rule that leaves it out (too faint, or
/// degenerate: a rotation of zero length, a scale or colour that is not finite).
pub fn read(c: &Columns, values: &[f64]) -> Result<Gaussian, &'static str> {
    let opacity = 1.0 / (1.0 + (-values[c.opacity]).exp());
    if !(opacity >= OPACITY_MIN as f64) {
        return Err(FAINT);
    }
    let [w, x, y, z] = c.rot.map(|i| values[i] as f32);
    let q = Quat::from_xyzw(x, y, z, w);
    if !(q.length() > 1e-12) || !q.is_finite() {
        return Err(NO_ROTATION);
    }
    let q = q.normalize();
    let axes = [q * Vec3::X, q * Vec3::Y, q * Vec3::Z];
    let scale = |i: usize| (values[i] as f32).exp();
    let scales = [
        scale(c.scale[0]),
        scale(c.scale[1]),
        c.scale_2.map_or(0.0, scale),
    ];
    // The axis of least scale is the normal (2DGS: the third, whose scale is zero).
    let k = (0..3)
        .min_by(|&a, &b| scales[a].total_cmp(&scales[b]))
        .unwrap_or(2);
    let in_plane: f32 = (0..3).filter(|&a| a != k).map(|a| scales[a]).product();
    let radius = RADIUS_SIGMAS * in_plane.sqrt();
    let color =
        c.dc.map(|i| (0.5 + SH_C0 * values[i] as f32).clamp(0.0, 1.0));
    // A rotation of denormal components normalises poorly: its axes are then not unit.
    let normal = axes[k];
    if !radius.is_finite() {
        return Err(HUGE);
    }
    if !(radius > 0.0) {
        return Err(NO_RADIUS);
    }
    if !color.iter().all(|x| x.is_finite()) {
        return Err(NO_COLOUR);
    }
    if !((normal.length() - 1.0).abs() < 1e-3) {
        return Err(NO_ROTATION);
    }
    Ok(Gaussian {
        normal,
        radius,
        color,
    })
}
