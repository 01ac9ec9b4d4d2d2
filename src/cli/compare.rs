//! Image differences: the figures parity tests assert on and `lobelight compare` prints.
//! A pixel's relative difference is |a − b|₁ / max(|b|₁, floor) over RGB, against the
//! reference b; the floor (1e-3 of b's mean |b|₁) keeps black pixels from dividing by zero.
//!
//! The standard HDR metrics, over pixels and channels, against the reference b:
//! - relMSE = mean (a − b)² / (b² + ε), ε = (0.1 · mean b)² (the usual 0.01 for an image of
//!   mean 1, scaled so that it does not depend on the scene's units);
//! - SMAPE = mean |a − b| / (|a| + |b| + ε'), ε' = 0.01 · mean b, in [0, 1];
//! - PSNR = 10 log10(peak² / MSE), peak the largest channel value of b;
//! - FLIP (NVIDIA's perceptual difference, mean over pixels, in [0, 1]) on display images:
//!   HDR pairs are tone-mapped first, both with the reference's log-average luminance, so a
//!   change of brightness shows.
//!
//! Pixels that are not finite in either image are counted (`non_finite`) and left out of
//! every mean.

use std::path::Path;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::shared::tone::{log_luminance, srgb_byte, tone_map};
use crate::tone::ToneConfig;

#[derive(Clone, Debug, Serialize)]
pub struct Difference {
    pub pixels: usize,
    /// Mean of the per-pixel relative differences.
    pub mean_relative: f64,
    /// Fraction of pixels within 5 % of the reference.
    pub within_5_percent: f64,
    pub max_relative: f64,
    /// Root mean square of a − b over all channels.
    pub rmse: f64,
    /// Σ|a|₁ / Σ|b|₁ − 1: the images' difference in total energy.
    pub energy: f64,
    /// Relative mean squared error (module docs).
    pub rel_mse: f64,
    /// Peak signal-to-noise ratio in dB against the reference's peak; infinite for equal images.
    pub psnr: f64,
    /// Symmetric mean absolute percentage error, as a fraction.
    pub smape: f64,
    /// Mean FLIP error of the display images; none where an image is too small to filter.
    pub flip: Option<f64>,
    /// Pixels left out because either image is not finite there.
    pub non_finite: usize,
    /// The figures over each object's pixels (`--objects`); empty without an ID image.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectDifference>,
}

/// The difference over the pixels an object-ID image gives one surface (`crate::objects`).
#[derive(Clone, Debug, Serialize)]
pub struct ObjectDifference {
    /// Its ID in the image (surface index + 1).
    pub id: u16,
    /// Its name (`Scene::surfaces`), from the ID image's JSON sidecar; else "id N".
    pub name: String,
    pub pixels: usize,
    /// Mean of (R + G + B) / 3 over its pixels, in A and in the reference B.
    pub mean: f64,
    pub reference_mean: f64,
    /// mean / reference_mean − 1: how much brighter A shows the object.
    pub bias: f64,
    /// relMSE and SMAPE over its pixels alone (their ε from its own mean).
    pub rel_mse: f64,
    pub smape: f64,
}

fn l1(p: &[f32; 4]) -> f64 {
    (p[0].abs() + p[1].abs() + p[2].abs()) as f64
}

/// The relative difference of each pixel of `a` against the reference `b`.
pub fn relative(a: &[[f32; 4]], b: &[[f32; 4]]) -> Vec<f64> {
    let mean = b.iter().map(l1).sum::<f64>() / b.len().max(1) as f64;
    let floor = (1e-3 * mean).max(1e-30);
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            let d: f64 = (0..3).map(|c| (p[c] - q[c]).abs() as f64).sum();
            d / l1(q).max(floor)
        })
        .collect()
}

/// The HDR metrics' sums over the finite pixel pairs.
struct HdrMetrics {
    rel_mse: f64,
    psnr: f64,
    smape: f64,
    non_finite: usize,
}

fn finite(p: &[f32; 4]) -> bool {
    p[..3].iter().all(|v| v.is_finite())
}

fn hdr_metrics(a: &[[f32; 4]], b: &[[f32; 4]]) -> HdrMetrics {
    let pairs: Vec<(&[f32; 4], &[f32; 4])> = a
        .iter()
        .zip(b)
        .filter(|(p, q)| finite(p) && finite(q))
        .collect();
    let values = 3.0 * pairs.len().max(1) as f64;
    let mean_b = pairs.iter().map(|(_, q)| l1(q)).sum::<f64>() / values;
    let peak = pairs
        .iter()
        .flat_map(|(_, q)| q[..3].iter().map(|&v| v as f64))
        .fold(0.0, f64::max);
    let (eps_mse, eps_smape) = (
        (0.1 * mean_b).powi(2).max(1e-30),
        (0.01 * mean_b).max(1e-30),
    );
    let (mut rel_mse, mut smape, mut mse) = (0.0, 0.0, 0.0);
    for (p, q) in &pairs {
        for c in 0..3 {
            let (x, y) = (p[c] as f64, q[c] as f64);
            let d = x - y;
            rel_mse += d * d / (y * y + eps_mse);
            smape += d.abs() / (x.abs() + y.abs() + eps_smape);
            mse += d * d;
        }
    }
    let mse = mse / values;
    HdrMetrics {
        rel_mse: rel_mse / values,
        psnr: if mse > 0.0 {
            10.0 * (peak * peak / mse).log10()
        } else {
            f64::INFINITY
        },
        smape: smape / values,
        non_finite: a.len() - pairs.len(),
    }
}

/// How the images' values are to be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Values {
    /// Linear radiance (EXR): FLIP compares them tone-mapped.
    Radiance,
    /// Display values in [0, 1] (PNG): FLIP compares them as they are.
    Display,
}

/// 8-bit sRGB of each pixel as FLIP reads it.
fn display_bytes(img: &[[f32; 4]], values: Values, log_sum: glam::Vec2) -> Vec<u8> {
    let params = ToneConfig::default().params(img.len() as u32, 0);
    img.iter()
        .flat_map(|p| {
            let c = glam::Vec3::new(p[0], p[1], p[2]);
            match values {
                Values::Radiance => {
                    let d = tone_map(c, log_sum, &params);
                    [srgb_byte(d.x), srgb_byte(d.y), srgb_byte(d.z)].map(|v| v as u8)
                }
                Values::Display => c
                    .to_array()
                    .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8),
            }
        })
        .collect()
}

/// FLIP's smallest image: its filters span several pixels at the default viewing distance.
const FLIP_MIN_SIZE: u32 = 8;

/// The mean FLIP error of `a` against the reference `b`, both `width × height`.
pub fn flip(
    a: &[[f32; 4]],
    b: &[[f32; 4]],
    width: u32,
    height: u32,
    values: Values,
) -> Option<f64> {
    if width < FLIP_MIN_SIZE || height < FLIP_MIN_SIZE || a.len() != b.len() {
        return None;
    }
    let log_sum = b.iter().fold(glam::Vec2::ZERO, |s, p| {
        s + log_luminance(glam::Vec3::new(p[0], p[1], p[2]), crate::tone::LOG_EPSILON)
    });
    let image = |img| {
        nv_flip::FlipImageRgb8::with_data(width, height, &display_bytes(img, values, log_sum))
    };
    let map = nv_flip::flip(image(b), image(a), nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    Some(nv_flip::FlipPool::from_image(&map).mean() as f64)
}

/// Every figure of `a` against the reference `b` (`width × height` pixels each).
pub fn difference_of(
    a: &[[f32; 4]],
    b: &[[f32; 4]],
    width: u32,
    height: u32,
    values: Values,
) -> Result<Difference> {
    let mut d = difference(a, b)?;
    d.flip = flip(a, b, width, height, values);
    Ok(d)
}

/// The figures of `a` against the reference `b` but FLIP, which needs the image's shape.
pub fn difference(a: &[[f32; 4]], b: &[[f32; 4]]) -> Result<Difference> {
    if a.len() != b.len() || a.is_empty() {
        return Err(Error::Invalid(format!(
            "images differ in size ({} and {} pixels)",
            a.len(),
            b.len()
        )));
    }
    let hdr = hdr_metrics(a, b);
    let rel = relative(a, b);
    let n = rel.len() as f64;
    let sq: f64 = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| ((p[c] - q[c]) as f64).powi(2)))
        .sum();
    Ok(Difference {
        pixels: rel.len(),
        mean_relative: rel.iter().sum::<f64>() / n,
        within_5_percent: rel.iter().filter(|&&r| r <= 0.05).count() as f64 / n,
        max_relative: rel.iter().copied().fold(0.0, f64::max),
        rmse: (sq / (3.0 * n)).sqrt(),
        energy: a.iter().map(l1).sum::<f64>() / b.iter().map(l1).sum::<f64>().max(1e-300) - 1.0,
        rel_mse: hdr.rel_mse,
        psnr: hdr.psnr,
        smape: hdr.smape,
        flip: None,
        non_finite: hdr.non_finite,
        objects: Vec::new(),
    })
}

/// The figures of `a` against the reference `b` over each surface of the object-ID image
/// `ids` (one ID a pixel; edge and empty pixels left out), named by `names[surface]`, in ID
/// order. Pixels that are not finite in either image are left out too.
pub fn per_object(
    a: &[[f32; 4]],
    b: &[[f32; 4]],
    ids: &[u16],
    names: &[String],
) -> Result<Vec<ObjectDifference>> {
    if ids.len() != a.len() || a.len() != b.len() {
        return Err(Error::Invalid(format!(
            "the object-ID image has {} pixels, the images {} and {}",
            ids.len(),
            a.len(),
            b.len()
        )));
    }
    // Each object's pixels: (in a, in b).
    type Pixels = (Vec<[f32; 4]>, Vec<[f32; 4]>);
    let mut by_id: std::collections::BTreeMap<u16, Pixels> = Default::default();
    for ((&id, p), q) in ids.iter().zip(a).zip(b) {
        if crate::objects::surface_of(id).is_some() && finite(p) && finite(q) {
            let entry = by_id.entry(id).or_default();
            entry.0.push(*p);
            entry.1.push(*q);
        }
    }
    Ok(by_id
        .into_iter()
        .map(|(id, (pa, pb))| {
            let mean = |v: &[[f32; 4]]| v.iter().map(l1).sum::<f64>() / (3 * v.len()) as f64;
            let (ma, mb) = (mean(&pa), mean(&pb));
            let hdr = hdr_metrics(&pa, &pb);
            let surface = crate::objects::surface_of(id).unwrap_or_default() as usize;
            ObjectDifference {
                id,
                name: names
                    .get(surface)
                    .cloned()
                    .unwrap_or_else(|| format!("id {id}")),
                pixels: pa.len(),
                mean: ma,
                reference_mean: mb,
                bias: if mb > 0.0 { ma / mb - 1.0 } else { 0.0 },
                rel_mse: hdr.rel_mse,
                smape: hdr.smape,
            }
        })
        .collect())
}

/// The sidecar of an object-ID image: the names of its surfaces (`ids.png` → `ids.json`).
pub fn names_path(ids: &Path) -> std::path::PathBuf {
    ids.with_extension("json")
}

#[derive(serde::Deserialize, Serialize)]
struct IdNames {
    /// `Scene::surfaces`: the name of ID k + 1 is entry k.
    surfaces: Vec<String>,
}

/// Writes an object-ID image (`crate::objects`) as a 16-bit grey PNG, and its surfaces'
/// names beside it (`names_path`).
pub fn write_object_ids(
    path: &Path,
    ids: &[u16],
    width: u32,
    height: u32,
    names: &[String],
) -> Result<()> {
    check_ids_path(path)?;
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(width, height, ids.to_vec())
        .ok_or_else(|| Error::Invalid("object-ID image has the wrong size".into()))?
        .save(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot write image: {e}", path.display())))?;
    let sidecar = names_path(path);
    let json = serde_json::to_string_pretty(&IdNames {
        surfaces: names.to_vec(),
    })
    .map_err(|e| Error::Invalid(format!("cannot encode surface names: {e}")))?;
    std::fs::write(&sidecar, json + "\n")
        .map_err(|e| Error::Invalid(format!("{}: cannot write: {e}", sidecar.display())))
}

/// Refuses an object-ID image path that does not name a PNG (checked before a render).
pub fn check_ids_path(path: &Path) -> Result<()> {
    let is_png = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if is_png {
        Ok(())
    } else {
        Err(Error::Invalid(format!(
            "{}: an object-ID image is written as PNG (16-bit grey): name it .png",
            path.display()
        )))
    }
}

/// Reads an object-ID image with its size, and its surfaces' names where the sidecar exists.
pub fn read_object_ids(path: &Path) -> Result<(Vec<u16>, u32, u32, Vec<String>)> {
    let img = image::open(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot read image: {e}", path.display())))?;
    if !matches!(img, image::DynamicImage::ImageLuma16(_)) {
        return Err(Error::Invalid(format!(
            "{}: not an object-ID image (16-bit grey PNG, as render --object-ids writes)",
            path.display()
        )));
    }
    let img = img.into_luma16();
    let (w, h) = img.dimensions();
    let sidecar = names_path(path);
    let names = match std::fs::read_to_string(&sidecar) {
        Ok(text) => {
            serde_json::from_str::<IdNames>(&text)
                .map_err(|e| Error::Invalid(format!("{}: {e}", sidecar.display())))?
                .surfaces
        }
        Err(_) => Vec::new(),
    };
    Ok((img.into_raw(), w, h, names))
}

/// How a file's values read: EXR holds radiance, anything else display values.
pub fn values_of(path: &Path) -> Values {
    let exr = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if exr {
        Values::Radiance
    } else {
        Values::Display
    }
}

/// Reads an image (EXR keeps linear values; 8-bit formats come as [0, 1]) with its size.
pub fn read_image(path: &Path) -> Result<(Vec<[f32; 4]>, u32, u32)> {
    let img = image::open(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot read image: {e}", path.display())))?
        .into_rgba32f();
    let (w, h) = img.dimensions();
    let px = img.pixels().map(|p| p.0).collect();
    Ok((px, w, h))
}

/// A heat map of the relative differences: black 0, red 5 %, yellow 25 % and above.
pub fn heatmap(rel: &[f64], width: u32, height: u32, path: &Path) -> Result<()> {
    let bytes: Vec<u8> = rel
        .iter()
        .flat_map(|&r| {
            let red = (r / 0.05).min(1.0);
            let yellow = ((r - 0.05) / 0.2).clamp(0.0, 1.0);
            [(255.0 * red) as u8, (255.0 * yellow) as u8, 0]
        })
        .collect();
    image::RgbImage::from_raw(width, height, bytes)
        .ok_or_else(|| Error::Invalid("heat map has the wrong size".into()))?
        .save(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot write image: {e}", path.display())))
}
