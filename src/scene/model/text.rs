//! Text point clouds: `.xyz` and `.pts` (the scanners' plain exports, and the format of the
//! thesis's models). One point a line, numbers separated by spaces, tabs or commas; blank
//! lines and lines starting with `#` or `//` are skipped, and a `.pts` file may open with a line
//! holding only the point count. Columns, the same on every line:
//!
//! | columns | meaning |
//! | --- | --- |
//! | 3 | x y z |
//! | 4 | x y z intensity (ignored) |
//! | 6 | x y z, then a normal or an 8-bit colour (integers 0–255), told apart by the first line |
//! | 7 | x y z intensity r g b (the Leica `.pts` layout) |
//! | 9 | x y z, then a normal and an 8-bit colour in either order |
//!
//! Colours are 8-bit sRGB; without normals the splats' normals come from their neighbours
//! (`normals::pca_normals`), as for any cloud. A malformed line is an error naming its number.

use std::path::Path;

use glam::Vec3;

use super::Mesh;
use crate::error::{Error, Result};

/// What a triple of columns after the position holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Triple {
    Normal,
    Color,
}

/// The layout of a file's lines: which columns hold a normal and a colour.
#[derive(Clone, Copy, Debug, Default)]
struct Layout {
    columns: usize,
    normal: Option<usize>,
    color: Option<usize>,
}

/// A triple of 8-bit integers is a colour; anything else a normal (checked for length later).
fn triple_kind(v: &[f64]) -> Triple {
    let byte = |x: f64| x.fract() == 0.0 && (0.0..=255.0).contains(&x);
    if v.iter().all(|&x| byte(x)) && v.iter().any(|&x| x > 1.0) {
        Triple::Color
    } else {
        Triple::Normal
    }
}

fn layout_of(first: &[f64]) -> std::result::Result<Layout, String> {
    let columns = first.len();
    let at = |k: usize| triple_kind(&first[k..k + 3]);
    let mut layout = Layout {
        columns,
        ..Default::default()
    };
    match columns {
        3 | 4 => {}
        6 => match at(3) {
            Triple::Normal => layout.normal = Some(3),
            Triple::Color => layout.color = Some(3),
        },
        7 => layout.color = Some(4),
        9 => match (at(3), at(6)) {
            (Triple::Color, _) => (layout.color, layout.normal) = (Some(3), Some(6)),
            _ => (layout.normal, layout.color) = (Some(3), Some(6)),
        },
        n => {
            return Err(format!(
                "{n} numbers on a line: expected 3 (x y z), 4 (x y z intensity), 6 (x y z and a \
                 normal or an RGB colour), 7 (x y z intensity r g b) or 9 (x y z, normal, RGB)"
            ));
        }
    }
    Ok(layout)
}

fn numbers(line: &str) -> std::result::Result<Vec<f64>, String> {
    line.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<f64>()
                .map_err(|_| format!("`{s}` is not a number"))
        })
        .collect()
}

/// Parses an `.xyz` or `.pts` file (`pts`: its first line may be the point count).
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| Error::parse(path, "text", format!("not UTF-8 text: {e}")))?;
    // A byte-order mark some tools write first is no statement.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut mesh = Mesh::default();
    let mut layout: Option<Layout> = None;
    let mut first_data = true;
    for (k, line) in text.lines().enumerate() {
        let at = |msg: String| Error::parse(path, format!("line {}", k + 1), msg);
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with("//") {
            continue;
        }
        let v = numbers(line).map_err(at)?;
        // A leading count line: one whole number before any point.
        if first_data && v.len() == 1 && v[0].fract() == 0.0 && v[0] >= 0.0 {
            first_data = false;
            continue;
        }
        first_data = false;
        let l = match layout {
            Some(l) => l,
            None => *layout.insert(layout_of(&v).map_err(at)?),
        };
        if v.len() != l.columns {
            return Err(at(format!(
                "{} numbers, but the first point has {}",
                v.len(),
                l.columns
            )));
        }
        let p = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
        if !p.is_finite() {
            return Err(at(format!("position {p} is not finite")));
        }
        mesh.positions.push(p);
        if let Some(c) = l.normal {
            let n = Vec3::new(v[c] as f32, v[c + 1] as f32, v[c + 2] as f32);
            if !n.is_finite() {
                return Err(at(format!("normal {n} is not finite")));
            }
            mesh.normals.get_or_insert_with(Vec::new).push(n);
        }
        if let Some(c) = l.color {
            let rgb = [v[c], v[c + 1], v[c + 2]];
            if !rgb.iter().all(|x| (0.0..=255.0).contains(x)) {
                return Err(at(format!("colour {rgb:?} is not 8-bit (0–255)")));
            }
            mesh.colors
                .get_or_insert_with(Vec::new)
                .push(rgb.map(|x| (x / 255.0) as f32));
        }
    }
    if mesh.positions.is_empty() {
        return Err(Error::parse(path, "points", "the file holds no point"));
    }
    Ok(mesh)
}
