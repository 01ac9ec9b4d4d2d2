//! Image differences: the figures parity tests assert on and `lobelight compare` prints.
//! A pixel's relative difference is |a − b|₁ / max(|b|₁, floor) over RGB, against the
//! reference b; the floor (1e-3 of b's mean |b|₁) keeps black pixels from dividing by zero.

use std::path::Path;

use serde::Serialize;

use crate::error::{Error, Result};

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

pub fn difference(a: &[[f32; 4]], b: &[[f32; 4]]) -> Result<Difference> {
    if a.len() != b.len() || a.is_empty() {
        return Err(Error::Invalid(format!(
            "images differ in size ({} and {} pixels)",
            a.len(),
            b.len()
        )));
    }
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
    })
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
