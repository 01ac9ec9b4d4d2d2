//! An environment light's map (docs/design.md §4, "Environment light"): the radiance arriving
//! from every direction, a latitude-longitude image or one constant radiance, with the tables
//! that sample it in proportion to its luminance times its texels' solid angle. The stages read
//! it packed into one array (`SkyTable`), through `shared::lights` and its WGSL twin.
//!
//! The map's frame is Mitsuba's: in the map's own axes, y up, the texel at (u, v) of the unit
//! square looks along `(sin θ sin φ, cos θ, −sin θ cos φ)`, `φ = 2π u`, `θ = π v`, so that an
//! EXR lights a scene here as Mitsuba's `envmap` lights it.

use std::path::Path;

use glam::Vec3;
use rayon::prelude::*;

use crate::shared::lights::{IRRADIANCE_H, IRRADIANCE_W};

/// Rows of the map a constant sky is made of: its texels' solid angles follow sin θ, which the
/// sampling tables weigh by each row's centre, so finer rows sample the sphere more evenly.
const CONSTANT_ROWS: u32 = 128;

/// Texels a map may have (16k × 8k), and so the most the packed table holds: 2 GiB.
pub const MAX_TEXELS: u64 = 1 << 27;

/// Texels along a map's side: the table's header holds both sides as f32, exact below 2²⁴.
pub const MAX_SIDE: u32 = 1 << 16;

/// An environment map in linear RGB radiance (W/m²/sr), row by row from the top (θ = 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Sky {
    pub width: u32,
    pub height: u32,
    pub radiance: Vec<[f32; 3]>,
}

/// A sky as the stages read it (`sky` in `wgsl/shared/trace.wgsl` and
/// `wgsl/shared/splat_shading.wgsl`), one `[f32; 4]` an entry:
/// - 0: the header: width and height (exact in f32: `MAX_SIDE` keeps each below 2²⁴), the sum
///   of the texels' sampling weights;
/// - 1 + y W + x: texel (x, y): its radiance, and the share of its row's weight up to and
///   including it (its row's cumulative distribution);
/// - 1 + W H + y: row y: the share of the map's weight up to and including it;
/// - 1 + W H + H + j W_E + i: the irradiance the whole map gives a surface whose normal looks
///   along φ = 2π i / W_E, θ = π j / (H_E − 1) (in the map's frame: a latitude-longitude grid
///   of `IRRADIANCE_SIZE` from pole to pole), which `shared::lights::sky_irradiance` reads
///   bilinearly.
///
/// A texel's weight is its luminance times the sine of its row's centre angle. A scene with no
/// environment light has the header alone, all zero.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyTable(pub Vec<[f32; 4]>);

impl Default for SkyTable {
    fn default() -> SkyTable {
        SkyTable(vec![[0.0; 4]])
    }
}

impl SkyTable {
    pub fn entries(&self) -> &[[f32; 4]] {
        &self.0
    }
}

/// Rec. 709 luminance (docs/design.md §2).
fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

impl Sky {
    /// One radiance from every direction.
    pub fn constant(radiance: [f32; 3]) -> Sky {
        Sky {
            width: 1,
            height: CONSTANT_ROWS,
            radiance: vec![radiance; CONSTANT_ROWS as usize],
        }
    }

    /// A latitude-longitude HDR image (OpenEXR or Radiance `.hdr`) times `scale`, checked:
    /// finite, non-negative, not all zero. The error is one line naming the file.
    pub fn load(path: &Path, scale: f32) -> Result<Sky, String> {
        let shown = path.display();
        let reader = image::ImageReader::open(path)
            .map_err(|e| format!("{shown}: {e}"))?
            .with_guessed_format()
            .map_err(|e| format!("{shown}: {e}"))?;
        let (width, height) = reader
            .into_dimensions()
            .map_err(|e| format!("{shown}: not an image this reads (EXR or .hdr): {e}"))?;
        if u64::from(width) * u64::from(height) > MAX_TEXELS || width.max(height) > MAX_SIDE {
            return Err(format!(
                "{shown}: {width} × {height} texels, more than a map may have ({MAX_TEXELS} in \
                 all, {MAX_SIDE} a side)"
            ));
        }
        let image = image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| format!("{shown}: {e}"))?
            .decode()
            .map_err(|e| format!("{shown}: not an image this reads (EXR or .hdr): {e}"))?
            .into_rgb32f();
        let radiance = image
            .pixels()
            .map(|p| p.0.map(|c| c * scale))
            .collect::<Vec<_>>();
        let sky = Sky {
            width,
            height,
            radiance,
        };
        sky.check().map_err(|m| format!("{shown}: {m}"))?;
        Ok(sky)
    }

    /// Finite, non-negative texels, not all zero, at least one texel.
    pub fn check(&self) -> Result<(), String> {
        if self.width == 0 || self.height == 0 {
            return Err("the map has no texels".into());
        }
        let width = self.width as usize;
        if let Some(k) = (self.radiance.iter()).position(|c| !c.iter().all(|x| x.is_finite())) {
            return Err(format!(
                "texel ({}, {}) is not finite: {:?}",
                k % width,
                k / width,
                self.radiance[k]
            ));
        }
        if let Some(k) = self
            .radiance
            .iter()
            .position(|c| c.iter().any(|&x| x < 0.0))
        {
            return Err(format!(
                "texel ({}, {}) is negative: {:?}",
                k % width,
                k / width,
                self.radiance[k]
            ));
        }
        if self.radiance.iter().all(|c| luminance(*c) <= 0.0) {
            return Err("the map is black (no texel has a positive luminance)".into());
        }
        Ok(())
    }

    /// `∫ L(ω) dω` over the sphere, per channel: what a surface facing every way would gather,
    /// and, times the emitting disk's area, the power the light's photons share.
    pub fn integral(&self) -> [f32; 3] {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut sum = [0.0f64; 3];
        for y in 0..h {
            // The exact solid angle of a texel of row y.
            let (t0, t1) = (
                std::f64::consts::PI * y as f64 / h as f64,
                std::f64::consts::PI * (y + 1) as f64 / h as f64,
            );
            let omega = 2.0 * std::f64::consts::PI / w as f64 * (t0.cos() - t1.cos());
            for c in &self.radiance[y * w..(y + 1) * w] {
                for (s, x) in sum.iter_mut().zip(c) {
                    *s += omega * f64::from(*x);
                }
            }
        }
        sum.map(|x| x as f32)
    }

    /// The packed table the stages sample and look the map up in (`SkyTable`).
    pub fn table(&self) -> SkyTable {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut out = vec![[0.0f32; 4]; 1 + w * h + h];
        let mut row_sums = vec![0.0f64; h];
        for y in 0..h {
            let sin = (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin();
            let row = &self.radiance[y * w..(y + 1) * w];
            let weights: Vec<f64> = row.iter().map(|c| f64::from(luminance(*c)) * sin).collect();
            let sum: f64 = weights.iter().sum();
            row_sums[y] = sum;
            let mut acc = 0.0;
            for (x, (c, wt)) in row.iter().zip(&weights).enumerate() {
                acc += wt;
                // A row of no weight is never picked; its shares still rise to 1.
                let share = if sum > 0.0 {
                    acc / sum
                } else {
                    (x + 1) as f64 / w as f64
                };
                out[1 + y * w + x] = [c[0], c[1], c[2], share as f32];
            }
            out[1 + y * w + w - 1][3] = 1.0;
        }
        let total: f64 = row_sums.iter().sum();
        let mut acc = 0.0;
        for (y, s) in row_sums.iter().enumerate() {
            acc += s;
            out[1 + w * h + y][0] = (acc / total) as f32;
        }
        out[w * h + h][0] = 1.0;
        out[0] = [self.width as f32, self.height as f32, total as f32, 0.0];
        out.extend(self.irradiance());
        SkyTable(out)
    }

    /// The unshadowed irradiance `∫ L(ω) max(0, n·ω) dω` on the normals of a latitude-
    /// longitude grid of `IRRADIANCE_SIZE` (its rows from pole to pole), in the map's frame:
    /// what the direct bake takes the blocked share of (design §8). The map is first averaged
    /// into `IRRADIANCE_MAP` texels, 2.8° across, over which the cosine is nearly linear (a
    /// finer map would cost its texels times the grid's), each a direction and its radiance
    /// times its solid angle.
    pub fn irradiance(&self) -> Vec<[f32; 4]> {
        let (w, h) = (self.width as usize, self.height as usize);
        let (cw, ch) = IRRADIANCE_MAP;
        // Each coarse texel: the mean of the texels whose centres fall in it, weighed by their
        // solid angles (sin θ), or, where the map is coarser along an axis, the texel its
        // centre lies in.
        let mut sum = vec![[0.0f64; 4]; cw * ch];
        for y in 0..h {
            let sin = (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin();
            let sy = (2 * y + 1) * ch / (2 * h);
            for x in 0..w {
                let cell = &mut sum[sy * cw + (2 * x + 1) * cw / (2 * w)];
                for (k, c) in self.radiance[y * w + x].iter().enumerate() {
                    cell[k] += f64::from(*c) * sin;
                }
                cell[3] += sin;
            }
        }
        let texel = |x: usize, y: usize| -> [f64; 3] {
            let c = sum[y * cw + x];
            if c[3] > 0.0 {
                [c[0] / c[3], c[1] / c[3], c[2] / c[3]]
            } else {
                let (fx, fy) = ((2 * x + 1) * w / (2 * cw), (2 * y + 1) * h / (2 * ch));
                self.radiance[fy * w + fx].map(f64::from)
            }
        };
        let dir = |u: f64, v: f64| {
            let (phi, theta) = (2.0 * std::f64::consts::PI * u, std::f64::consts::PI * v);
            [
                theta.sin() * phi.sin(),
                theta.cos(),
                -theta.sin() * phi.cos(),
            ]
        };
        let mut sources = Vec::with_capacity(cw * ch);
        for y in 0..ch {
            let (t0, t1) = (
                std::f64::consts::PI * y as f64 / ch as f64,
                std::f64::consts::PI * (y + 1) as f64 / ch as f64,
            );
            let omega = 2.0 * std::f64::consts::PI / cw as f64 * (t0.cos() - t1.cos());
            for x in 0..cw {
                let d = dir((x as f64 + 0.5) / cw as f64, (y as f64 + 0.5) / ch as f64);
                sources.push((d, texel(x, y).map(|c| c * omega)));
            }
        }
        let (ew, eh) = IRRADIANCE_SIZE;
        (0..ew * eh)
            .into_par_iter()
            .map(|k| {
                let n = dir(
                    (k % ew) as f64 / ew as f64,
                    (k / ew) as f64 / (eh - 1) as f64,
                );
                let mut e = [0.0f64; 3];
                for (d, c) in &sources {
                    let cos = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
                    if cos > 0.0 {
                        for i in 0..3 {
                            e[i] += c[i] * cos;
                        }
                    }
                }
                [e[0] as f32, e[1] as f32, e[2] as f32, 0.0]
            })
            .collect()
    }
}

/// The grid of normals the sky's irradiance is tabled on (`Sky::irradiance`;
/// `shared::lights::IRRADIANCE_W` × `IRRADIANCE_H`): 2.8° a step.
pub const IRRADIANCE_SIZE: (usize, usize) = (IRRADIANCE_W as usize, IRRADIANCE_H as usize);

/// The texels a map is averaged into before its irradiance is tabled.
const IRRADIANCE_MAP: (usize, usize) = (128, 64);

/// Texels of a sky model's map: 512 × 256, a texel 0.7° across, finer than the sky's
/// gradients (its brightest, round the sun, spans tens of degrees).
const MODEL_SIZE: (u32, u32) = (512, 256);

/// The clear sky of the Hosek–Wilkie model (Hosek & Wilkie 2012, "An Analytic Model for Full
/// Spectral Sky-Dome Radiance"; its RGB coefficients, from the `hw-skymodel` crate) for a sun
/// at `elevation` and `azimuth` (degrees; the azimuth in the map's frame: 0 along −z, 90 along
/// +x), `turbidity` (1–10) and the ground's `albedo` (0–1), times `scale`, as a map: the sky
/// above the horizon, and below it the ground the model assumes, a plane of that albedo lit by
/// the sky (`albedo E / π`, E the sky's irradiance on it; `scene::load` adds the scene's suns'
/// with `light_ground`), so that a scene's own ground meets a horizon. The sun's disk is not in
/// it: a `sun` light is the sun.
pub fn hosek_wilkie(
    (elevation, azimuth): (f32, f32),
    turbidity: f32,
    albedo: f32,
    scale: f32,
) -> Result<Sky, String> {
    use hw_skymodel::rgb::{Channel, SkyParams, SkyState};
    if !(0.0..=90.0).contains(&elevation) {
        return Err(format!(
            "sun_elevation must be in [0, 90] degrees, got {elevation}"
        ));
    }
    if !azimuth.is_finite() {
        return Err(format!("sun_azimuth must be finite, got {azimuth}"));
    }
    let state = SkyState::new(&SkyParams {
        elevation: elevation.to_radians(),
        turbidity,
        albedo: [albedo; 3],
    })
    .map_err(|e| e.to_string())?;
    let (e, a) = (elevation.to_radians(), azimuth.to_radians());
    let sun = Vec3::new(e.cos() * a.sin(), e.sin(), -e.cos() * a.cos());
    let (w, h) = MODEL_SIZE;
    let mut radiance = Vec::with_capacity((w * h) as usize);
    // The sky's irradiance on the ground, to light the ground below the horizon.
    let mut ground = [0.0f64; 3];
    for y in 0..h {
        let theta = std::f32::consts::PI * (y as f32 + 0.5) / h as f32;
        let below = theta >= std::f32::consts::FRAC_PI_2;
        let solid_angle = 2.0 * std::f64::consts::PI / f64::from(w)
            * (std::f64::consts::PI / f64::from(h))
            * f64::from(theta.sin());
        for x in 0..w {
            if below {
                radiance.push([0.0; 3]);
                continue;
            }
            let phi = 2.0 * std::f32::consts::PI * (x as f32 + 0.5) / w as f32;
            let d = Vec3::new(
                theta.sin() * phi.sin(),
                theta.cos(),
                -theta.sin() * phi.cos(),
            );
            let gamma = d.dot(sun).clamp(-1.0, 1.0).acos();
            let c = [Channel::R, Channel::G, Channel::B]
                .map(|c| (state.radiance(theta, gamma, c) * scale).max(0.0));
            for (e, l) in ground.iter_mut().zip(c) {
                *e += f64::from(l) * f64::from(theta.cos()) * solid_angle;
            }
            radiance.push(c);
        }
    }
    let below = ground.map(|e| (f64::from(albedo) * e / std::f64::consts::PI) as f32);
    for c in radiance[(w * h / 2) as usize..].iter_mut() {
        *c = below;
    }
    let sky = Sky {
        width: w,
        height: h,
        radiance,
    };
    sky.check()?;
    Ok(sky)
}

impl Sky {
    /// Adds `radiance` below the horizon (the lower half of the rows): a sky model's ground,
    /// lit by a sun of the scene.
    pub fn light_ground(&mut self, radiance: [f32; 3]) {
        let half = (self.width * self.height / 2) as usize;
        for c in self.radiance[half..].iter_mut() {
            for (x, r) in c.iter_mut().zip(radiance) {
                *x += r;
            }
        }
    }
}

/// The map's frame in the scene: its up axis (the map's y) and the axes its x and z point
/// along, turned by `rotation` degrees about up (counter-clockwise seen from above).
pub fn frame(up: Vec3, rotation_deg: f32) -> [Vec3; 3] {
    // The map's x for a y-up scene is +x; for z up, the map's y is +z and its z is −y.
    let (x, z) = if up.z.abs() > up.y.abs() {
        (Vec3::X, -Vec3::Y * up.z.signum())
    } else {
        (Vec3::X, Vec3::Z * up.y.signum())
    };
    let (s, c) = rotation_deg.to_radians().sin_cos();
    [c * x - s * z, up, s * x + c * z]
}
