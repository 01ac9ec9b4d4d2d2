//! Small line charts as PNG for the benchmarks (`bench sweep`): panels side by side, each with
//! log or linear axes, one coloured series per knob, points joined in order and labelled.
//! Drawing goes through `imageproc`; text through `ab_glyph` with a system TrueType font
//! (DejaVu or Liberation, or the file `LOBELIGHT_FONT` names). Without a font the charts are
//! drawn without text and `draw` says so.

use std::path::Path;

use ab_glyph::{FontVec, PxScale};
use image::{Rgb, RgbImage};
use imageproc::drawing::{
    draw_filled_circle_mut, draw_filled_rect_mut, draw_line_segment_mut, draw_text_mut, text_size,
};
use imageproc::rect::Rect;

use crate::error::{Error, Result};

pub struct Series {
    pub name: String,
    /// (x, y) in order; points that a log axis cannot show are skipped.
    pub points: Vec<(f64, f64)>,
    /// A short label per point (the knob's value), or none.
    pub labels: Vec<String>,
}

pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
}

const PANEL: (u32, u32) = (620, 460);
/// Plot area margins: left, right, top, bottom.
const MARGIN: (f32, f32, f32, f32) = (78.0, 150.0, 40.0, 56.0);
const PALETTE: [[u8; 3]; 8] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [23, 190, 207],
];
const INK: Rgb<u8> = Rgb([40, 40, 40]);
const GRID: Rgb<u8> = Rgb([225, 225, 225]);

const FONT_PATHS: [&str; 5] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
];

fn find_font() -> Option<FontVec> {
    let from_env = std::env::var("LOBELIGHT_FONT").ok();
    from_env
        .iter()
        .map(String::as_str)
        .chain(FONT_PATHS)
        .find_map(|p| FontVec::try_from_vec(std::fs::read(p).ok()?).ok())
}

/// One axis: the data range mapped onto a pixel span, linear or in log10.
struct Axis {
    log: bool,
    lo: f64,
    hi: f64,
}

impl Axis {
    fn new(values: impl Iterator<Item = f64>, log: bool) -> Axis {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
            let v = if log { v.log10() } else { v };
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if !lo.is_finite() {
            (lo, hi) = (0.0, 1.0);
        }
        let pad = ((hi - lo) * 0.06).max(if log { 0.1 } else { 1e-9 * hi.abs().max(1.0) });
        Axis {
            log,
            lo: lo - pad,
            hi: hi + pad,
        }
    }

    /// Where `v` falls in [0, 1], or none off a log axis.
    fn unit(&self, v: f64) -> Option<f64> {
        let v = if self.log {
            (v > 0.0).then(|| v.log10())?
        } else {
            v
        };
        v.is_finite().then(|| (v - self.lo) / (self.hi - self.lo))
    }

    /// Tick values: powers of ten (and 2, 5 between when there are few) on a log axis, steps
    /// of 1, 2 or 5 times a power of ten on a linear one.
    fn ticks(&self) -> Vec<f64> {
        if self.log {
            let decades = (self.lo.floor() as i32)..=(self.hi.ceil() as i32);
            let mults: &[f64] = if self.hi - self.lo < 2.5 {
                &[1.0, 2.0, 5.0]
            } else {
                &[1.0]
            };
            decades
                .flat_map(|e| mults.iter().map(move |m| m * 10f64.powi(e)))
                .filter(|v| (self.lo..=self.hi).contains(&v.log10()))
                .collect()
        } else {
            let raw = (self.hi - self.lo) / 6.0;
            let p = 10f64.powf(raw.log10().floor());
            let step = [1.0, 2.0, 5.0, 10.0]
                .iter()
                .map(|m| m * p)
                .find(|s| *s >= raw)
                .unwrap_or(10.0 * p);
            let first = (self.lo / step).ceil() as i64;
            let last = (self.hi / step).floor() as i64;
            (first..=last).map(|k| k as f64 * step).collect()
        }
    }
}

fn tick_label(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.0e}")
    } else if a >= 10.0 {
        format!("{v:.0}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

struct Canvas<'a> {
    img: RgbImage,
    font: Option<&'a FontVec>,
}

impl Canvas<'_> {
    fn text(&mut self, x: f32, y: f32, size: f32, colour: Rgb<u8>, s: &str, centred: bool) {
        let Some(font) = self.font else { return };
        let scale = PxScale::from(size);
        let (w, h) = text_size(scale, font, s);
        let x = if centred { x - w as f32 / 2.0 } else { x };
        draw_text_mut(
            &mut self.img,
            colour,
            x as i32,
            (y - h as f32 / 2.0) as i32,
            scale,
            font,
            s,
        );
    }

    fn text_width(&self, size: f32, s: &str) -> f32 {
        self.font
            .map_or(0.0, |f| text_size(PxScale::from(size), f, s).0 as f32)
    }

    fn panel(&mut self, chart: &Chart, x0: f32) {
        let (w, h) = (PANEL.0 as f32, PANEL.1 as f32);
        let (left, right, top, bottom) = (x0 + MARGIN.0, x0 + w - MARGIN.1, MARGIN.2, h - MARGIN.3);
        let all = || chart.series.iter().flat_map(|s| s.points.iter());
        let ax = Axis::new(all().map(|p| p.0), chart.log_x);
        let ay = Axis::new(all().map(|p| p.1), chart.log_y);
        let px = |v: f64| ax.unit(v).map(|u| left + u as f32 * (right - left));
        let py = |v: f64| ay.unit(v).map(|u| bottom - u as f32 * (bottom - top));
        for t in ax.ticks() {
            if let Some(x) = px(t) {
                draw_line_segment_mut(&mut self.img, (x, top), (x, bottom), GRID);
                self.text(x, bottom + 14.0, 13.0, INK, &tick_label(t), true);
            }
        }
        for t in ay.ticks() {
            if let Some(y) = py(t) {
                draw_line_segment_mut(&mut self.img, (left, y), (right, y), GRID);
                let label = tick_label(t);
                let tw = self.text_width(13.0, &label);
                self.text(left - 6.0 - tw, y, 13.0, INK, &label, false);
            }
        }
        for (a, b) in [
            ((left, top), (left, bottom)),
            ((left, bottom), (right, bottom)),
            ((right, top), (right, bottom)),
            ((left, top), (right, top)),
        ] {
            draw_line_segment_mut(&mut self.img, a, b, INK);
        }
        self.text(
            (left + right) / 2.0,
            top - 22.0,
            16.0,
            INK,
            &chart.title,
            true,
        );
        self.text(
            (left + right) / 2.0,
            bottom + 36.0,
            14.0,
            INK,
            &chart.x_label,
            true,
        );
        self.text(x0 + 8.0, top - 22.0 + 2.0, 13.0, INK, &chart.y_label, false);
        for (k, s) in chart.series.iter().enumerate() {
            let colour = Rgb(PALETTE[k % PALETTE.len()]);
            let points: Vec<(f32, f32, Option<&String>)> = s
                .points
                .iter()
                .enumerate()
                .filter_map(|(i, &(x, y))| Some((px(x)?, py(y)?, s.labels.get(i))))
                .collect();
            for pair in points.windows(2) {
                draw_line_segment_mut(
                    &mut self.img,
                    (pair[0].0, pair[0].1),
                    (pair[1].0, pair[1].1),
                    colour,
                );
            }
            for &(x, y, label) in &points {
                draw_filled_circle_mut(&mut self.img, (x as i32, y as i32), 4, colour);
                if let Some(l) = label {
                    self.text(x + 6.0, y - 9.0, 11.0, colour, l, false);
                }
            }
            // Legend on the right.
            let ly = top + 10.0 + 22.0 * k as f32;
            let rect = Rect::at((right + 14.0) as i32, (ly - 5.0) as i32).of_size(18, 10);
            draw_filled_rect_mut(&mut self.img, rect, colour);
            self.text(right + 38.0, ly, 13.0, INK, &s.name, false);
        }
    }
}

/// Draws the charts side by side into a PNG; false when no font was found (no text).
pub fn draw(charts: &[Chart], path: &Path) -> Result<bool> {
    let font = find_font();
    let width = PANEL.0 * charts.len().max(1) as u32;
    let mut canvas = Canvas {
        img: RgbImage::from_pixel(width, PANEL.1, Rgb([255, 255, 255])),
        font: font.as_ref(),
    };
    for (i, chart) in charts.iter().enumerate() {
        canvas.panel(chart, (i as u32 * PANEL.0) as f32);
    }
    canvas
        .img
        .save(path)
        .map_err(|e| Error::Invalid(format!("{}: cannot write image: {e}", path.display())))?;
    Ok(font.is_some())
}
