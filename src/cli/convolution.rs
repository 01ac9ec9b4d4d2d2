//! `lobelight bench convolution`: the thesis's form and ours against the reference on the
//! study grid, the thesis's own grid under its own definitions, and heat maps of the errors.

use std::fmt;
use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::convolution::errors::{STUDY_ALPHAS, STUDY_ANGLES, STUDY_BETAS};
use crate::convolution::{
    CaseError, Convention, Formula, Quality, Summary, errors, study_grid, summary,
};
use crate::error::{Error, Result};

/// The thesis's empirical factor (§4.1): its form divided by 1.81.
pub const THESIS_FACTOR: f64 = 1.81;

/// The errors of the thesis's form on its own grid (α = 0.065, β 0.01–0.5, lobe angle
/// 0–90°) against its own definition of the integral (`Convention::Thesis`).
#[derive(Clone, Debug, Serialize)]
pub struct StudyGrid {
    pub cases: usize,
    /// Divided by 1.81, as the thesis rendered.
    pub with_factor: Summary,
    /// As it stands.
    pub without_factor: Summary,
}

#[derive(Clone, Debug, Serialize)]
pub struct ConvolutionBench {
    /// Cases of the study grid (α × β × lobe angle).
    pub cases: usize,
    /// Cases whose response lies outside the 60° view cap (under 1 % of its squared norm):
    /// left out of `median`, `p95` and `max`.
    pub outside_60: usize,
    /// The thesis's form with its factor 1/1.81, against the renderer's integral.
    pub thesis: Summary,
    /// The thesis's form without the factor.
    pub thesis_unscaled: Summary,
    /// The renderer's shading (`shared::lobe_brdf`).
    pub ours: Summary,
    /// The thesis's form on the thesis's grid under the thesis's definitions.
    pub thesis_grid: StudyGrid,
    /// Heat maps of the per-lobe errors over views up to 60°, one per formula.
    pub heatmaps: Vec<String>,
    pub ms: f64,
}

fn column(errors: &[Vec<CaseError>], k: usize) -> Vec<CaseError> {
    errors.iter().map(|e| e[k]).collect()
}

pub fn convolution_bench(out_dir: &Path, q: Quality) -> Result<ConvolutionBench> {
    let start = Instant::now();
    let formulas = [
        Formula::Thesis {
            scale: THESIS_FACTOR,
        },
        Formula::Thesis { scale: 1.0 },
        Formula::Ours,
    ];
    let cases = study_grid();
    let study = errors(&cases, Convention::Renderer, &formulas, q);
    let thesis_cases = crate::convolution::thesis_grid();
    let own = errors(&thesis_cases, Convention::Thesis, &formulas[..2], q);
    std::fs::create_dir_all(out_dir)
        .map_err(|e| Error::Invalid(format!("{}: {e}", out_dir.display())))?;
    let mut heatmaps = Vec::new();
    for (name, k) in [("thesis", 0), ("ours", 2)] {
        let path = out_dir.join(format!("convolution_{name}.png"));
        heatmap(&column(&study, k), &path)?;
        heatmaps.push(path.display().to_string());
    }
    Ok(ConvolutionBench {
        cases: cases.len(),
        outside_60: study.iter().filter(|e| e[2].l2_60.is_none()).count(),
        thesis: summary(&column(&study, 0)),
        thesis_unscaled: summary(&column(&study, 1)),
        ours: summary(&column(&study, 2)),
        thesis_grid: StudyGrid {
            cases: thesis_cases.len(),
            with_factor: summary(&column(&own, 0)),
            without_factor: summary(&column(&own, 1)),
        },
        heatmaps,
        ms: crate::timing::ms_since(start),
    })
}

/// Colour of a relative error on a log scale: black at 0.1 %, through blue (1 %) and red
/// (10 %) to yellow at 100 % and above; grey where the response lies outside the cap.
fn colour(e: Option<f64>) -> [u8; 3] {
    let Some(e) = e else {
        return [96, 96, 96];
    };
    let t = ((e.max(1e-12).log10() + 3.0) / 3.0).clamp(0.0, 1.0);
    let ramp = |a: f64, b: f64, x: f64| (255.0 * (a + (b - a) * x)) as u8;
    match t {
        t if t < 1.0 / 3.0 => [0, 0, ramp(0.0, 1.0, 3.0 * t)],
        t if t < 2.0 / 3.0 => {
            let x = 3.0 * t - 1.0;
            [ramp(0.0, 1.0, x), 0, ramp(1.0, 0.0, x)]
        }
        t => [255, ramp(0.0, 1.0, 3.0 * t - 2.0), 0],
    }
}

/// One panel per α, left to right; in each, β grows downwards and the lobe angle rightwards.
fn heatmap(errors: &[CaseError], path: &Path) -> Result<()> {
    const CELL: usize = 12;
    const GAP: usize = 6;
    let panel_w = STUDY_ANGLES * CELL;
    let (w, h) = (
        STUDY_ALPHAS.len() * (panel_w + GAP) - GAP,
        STUDY_BETAS * CELL,
    );
    let mut img = image::RgbImage::from_pixel(w as u32, h as u32, image::Rgb([255, 255, 255]));
    for (i, e) in errors.iter().enumerate() {
        let angle = i % STUDY_ANGLES;
        let beta = (i / STUDY_ANGLES) % STUDY_BETAS;
        let alpha = i / (STUDY_ANGLES * STUDY_BETAS);
        let c = image::Rgb(colour(e.l2_60));
        for y in 0..CELL {
            for x in 0..CELL {
                let px = alpha * (panel_w + GAP) + angle * CELL + x;
                img.put_pixel(px as u32, (beta * CELL + y) as u32, c);
            }
        }
    }
    img.save(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot write image: {e}", path.display())))
}

impl fmt::Display for ConvolutionBench {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let pct = |x: f64| format!("{:.2} %", 100.0 * x);
        writeln!(
            f,
            "lobe × BRDF convolution: {} cases ({} with no response within 60°), {:.0} ms",
            self.cases, self.outside_60, self.ms
        )?;
        writeln!(
            f,
            "{:<22} {:>9} {:>9} {:>9} {:>10} {:>9} {:>9}",
            "relative L2 error", "median", "p95", "max", "max ≤85°", "energy", "energy95"
        )?;
        let row = |f: &mut fmt::Formatter<'_>, name: &str, s: &Summary| {
            writeln!(
                f,
                "{:<22} {:>9} {:>9} {:>9} {:>10} {:>9} {:>9}",
                name,
                pct(s.median),
                pct(s.p95),
                pct(s.max),
                pct(s.max_to_85),
                pct(s.energy_error),
                pct(s.energy_error_p95)
            )
        };
        row(f, "thesis (1/1.81)", &self.thesis)?;
        row(f, "thesis (unscaled)", &self.thesis_unscaled)?;
        row(f, "ours", &self.ours)?;
        writeln!(
            f,
            "thesis grid under the thesis's definitions ({} cases):",
            self.thesis_grid.cases
        )?;
        row(f, "  with 1/1.81", &self.thesis_grid.with_factor)?;
        row(f, "  without", &self.thesis_grid.without_factor)?;
        write!(f, "heat maps: {}", self.heatmaps.join(", "))
    }
}
