//! Text point clouds: `.xyz` and `.pts` (the scanners' plain exports, and the format of the
//! thesis's models). One point a line, numbers separated by spaces, tabs or commas; blank
//! lines and lines starting with `#` or `//` are skipped, and a `.pts` file may open with a line
//! holding only the point count. Which columns hold what is read from a header line where the
//! file has one (`//X Y Z R G B Nx Ny Nz`, CloudCompare's; `x,y,z,red,green,blue`), else from
//! the values of the first `SAMPLE_LINES` points, the same on every line:
//!
//! | columns | meaning |
//! | --- | --- |
//! | 3 | x y z |
//! | 4 | x y z intensity (ignored) |
//! | 6 | x y z, then a normal (unit length on every sampled point) or a colour |
//! | 7 | x y z intensity r g b (the Leica `.pts` layout) |
//! | 9 | x y z, then a normal and a colour in either order |
//!
//! Colours are sRGB, 8-bit integers (0–255) or, where no sampled value exceeds 1, fractions in
//! [0, 1]; without normals the splats' normals come from their neighbours
//! (`normals::pca_normals`), as for any cloud. A line that cannot be read (a word that is no
//! number, a count of numbers unlike the file's, a coordinate not finite or past f32's range, a
//! colour out of range) is skipped and counted, or with `--strict` an error naming its line.

use std::path::Path;

use super::reading::{Reading, point_f32};
use super::{LeftOut, Mesh};
use crate::error::{Error, Result};

/// Points whose values decide the columns where a file has no header.
const SAMPLE_LINES: usize = 1000;
/// How far from 1 a normal's length may be on a sampled point.
const UNIT_TOLERANCE: f64 = 0.02;

/// Which columns of a line hold what.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Layout {
    columns: usize,
    position: [usize; 3],
    normal: Option<[usize; 3]>,
    /// The colour's columns and the value of full intensity (255 or 1).
    color: Option<([usize; 3], f64)>,
}

/// A line with no point on it: blank, or a comment.
fn is_comment(line: &str) -> bool {
    line.is_empty() || line.starts_with('#') || line.starts_with("//")
}

fn words(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
}

fn numbers(line: &str) -> std::result::Result<Vec<f64>, String> {
    words(line)
        .map(|s| {
            s.parse::<f64>()
                .map_err(|_| format!("`{s}` is not a number"))
        })
        .collect()
}

/// The layout a header line names (`//X Y Z R G B Nx Ny Nz`, `x,y,z,red,green,blue`), where
/// it names x, y and z; the colour's scale is left to the values.
fn header_layout(line: &str) -> Option<Layout> {
    let line = line.trim_start_matches(['/', '#']);
    let names: Vec<String> = words(line).map(|w| w.to_ascii_lowercase()).collect();
    let find = |options: &[&str]| names.iter().position(|n| options.contains(&n.as_str()));
    let triple = |a: &[&str], b: &[&str], c: &[&str]| Some([find(a)?, find(b)?, find(c)?]);
    Some(Layout {
        columns: names.len(),
        position: triple(&["x"], &["y"], &["z"])?,
        normal: triple(
            &["nx", "normal_x", "normalx"],
            &["ny", "normal_y", "normaly"],
            &["nz", "normal_z", "normalz"],
        ),
        color: triple(&["r", "red"], &["g", "green"], &["b", "blue"]).map(|c| (c, 255.0)),
    })
}

/// What the values of a triple of columns are on every sampled point.
fn kind_of(rows: &[Vec<f64>], at: usize) -> Option<Kind> {
    let all = |f: &dyn Fn(&[f64]) -> bool| rows.iter().all(|r| f(&r[at..at + 3]));
    let unit = |v: &[f64]| {
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        (len - 1.0).abs() < UNIT_TOLERANCE
    };
    let byte = |v: &[f64]| {
        v.iter()
            .all(|&x| x.fract() == 0.0 && (0.0..=255.0).contains(&x))
    };
    let fraction = |v: &[f64]| v.iter().all(|x| (0.0..=1.0).contains(x));
    if all(&unit) {
        Some(Kind::Normal)
    } else if all(&fraction) {
        Some(Kind::Color(1.0))
    } else if all(&byte) {
        Some(Kind::Color(255.0))
    } else {
        None
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Normal,
    /// A colour, with the value of full intensity.
    Color(f64),
}

/// The layout the sampled points' values show: their most common count of numbers, and for
/// each triple after the position whether it is a normal or a colour.
fn value_layout(rows: &[Vec<f64>]) -> std::result::Result<Layout, String> {
    let columns = usual_columns(rows).unwrap_or(3);
    let rows: Vec<Vec<f64>> = rows
        .iter()
        .filter(|r| r.len() == columns)
        .cloned()
        .collect();
    let mut layout = Layout {
        columns,
        position: [0, 1, 2],
        ..Default::default()
    };
    let neither = |at: usize| {
        format!(
            "columns {}–{} hold neither a normal (unit length) nor a colour (0–255, or 0–1) on \
             every point (the first {} lines read): name the columns in a header line such as \
             `//X Y Z R G B`",
            at + 1,
            at + 3,
            rows.len()
        )
    };
    let triple = |at: usize| [at, at + 1, at + 2];
    match columns {
        3 | 4 => {}
        6 => match kind_of(&rows, 3).ok_or_else(|| neither(3))? {
            Kind::Normal => layout.normal = Some(triple(3)),
            Kind::Color(full) => layout.color = Some((triple(3), full)),
        },
        7 => {
            let full = match kind_of(&rows, 4) {
                Some(Kind::Color(full)) => full,
                _ => 255.0,
            };
            layout.color = Some((triple(4), full));
        }
        9 => match (kind_of(&rows, 3), kind_of(&rows, 6)) {
            (Some(Kind::Normal), Some(Kind::Color(full))) => {
                (layout.normal, layout.color) = (Some(triple(3)), Some((triple(6), full)))
            }
            (Some(Kind::Color(full)), Some(Kind::Normal)) => {
                (layout.color, layout.normal) = (Some((triple(3), full)), Some(triple(6)))
            }
            (Some(Kind::Normal), _) => return Err(neither(6)),
            _ => return Err(neither(3)),
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

/// The most common count of numbers on the sampled points' lines (the first of equals).
fn usual_columns(rows: &[Vec<f64>]) -> Option<usize> {
    let mut counts = std::collections::BTreeMap::new();
    for r in rows {
        *counts.entry(r.len()).or_insert(0usize) += 1;
    }
    let most = counts.values().copied().max()?;
    counts.into_iter().find(|&(_, n)| n == most).map(|(c, _)| c)
}

/// The file's layout, from its header line if it has one, else from its first points' values,
/// and the line its points start after (the header's, or the `.pts` count's).
fn layout_of(text: &str) -> std::result::Result<(Layout, usize), (usize, String)> {
    let mut lines = text.lines().enumerate().map(|(k, l)| (k, l.trim()));
    let mut skip = 0;
    let mut header = None;
    let mut rows = Vec::new();
    let mut first_point = true;
    for (k, line) in lines.by_ref() {
        if line.is_empty() {
            continue;
        }
        let numeric = numbers(line);
        // A header: a comment or a line of words before the first point, naming x, y and z.
        if rows.is_empty()
            && header.is_none()
            && numeric.is_err()
            && let Some(l) = header_layout(line)
        {
            header = Some(l);
            skip = k + 1;
            continue;
        }
        if is_comment(line) {
            continue;
        }
        // A `.pts` count: one whole number before any point.
        if std::mem::take(&mut first_point)
            && let Ok([n]) = numeric.as_deref()
            && n.fract() == 0.0
            && *n >= 0.0
        {
            skip = k + 1;
            continue;
        }
        if let Some(v) = numeric.ok().filter(|v| v.iter().all(|x| x.is_finite())) {
            rows.push(v);
        }
        if rows.len() == SAMPLE_LINES {
            break;
        }
    }
    // A header that names fewer or more columns than the points have is not trusted.
    let named = |l: &Layout| rows.is_empty() || usual_columns(&rows) == Some(l.columns);
    let layout = match header.filter(named) {
        Some(mut l) => {
            // The colour's scale from the values: fractions where none exceeds 1.
            let columns = l.columns;
            if let Some((c, full)) = l.color.as_mut() {
                let fits = |r: &&Vec<f64>| r.len() == columns;
                let fraction = (rows.iter().filter(|r| fits(r)))
                    .all(|r| c.iter().all(|&i| (0.0..=1.0).contains(&r[i])));
                *full = if fraction { 1.0 } else { 255.0 };
            }
            l
        }
        None => value_layout(&rows).map_err(|m| (skip + 1, m))?,
    };
    Ok((layout, skip))
}

/// Parses an `.xyz` or `.pts` file (`pts`: its first line may be the point count).
pub fn parse(path: &Path, bytes: &[u8], reading: &Reading) -> Result<Mesh> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| Error::parse(path, "text", format!("not UTF-8 text: {e}")))?;
    // A byte-order mark some tools write first is no statement.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // A point a line at most: counted before any is read.
    let lines = bytes.iter().filter(|&&b| b == b'\n').count() as u64 + 1;
    reading.check_points(path, "lines", lines)?;
    let (layout, start) = layout_of(text).map_err(|(line, m)| Error::at_line(path, line, m))?;
    let mut mesh = Mesh::default();
    let mut left_out = LeftOut::default();
    for (k, line) in text.lines().enumerate().skip(start) {
        let line = line.trim();
        if is_comment(line) {
            continue;
        }
        let at = |msg: String| Error::at_line(path, k + 1, msg);
        match point(&layout, line) {
            Ok((p, n, c)) => {
                mesh.positions.push(p);
                if let Some(n) = n {
                    mesh.normals.get_or_insert_with(Vec::new).push(n);
                }
                if let Some(c) = c {
                    mesh.colors.get_or_insert_with(Vec::new).push(c);
                }
            }
            Err(m) => left_out.skip(reading, at(m))?,
        }
    }
    mesh.left_out = left_out;
    Ok(mesh)
}

type Point = (glam::Vec3, Option<glam::Vec3>, Option<[f32; 3]>);

/// The point on `line`, or why it cannot be read.
fn point(l: &Layout, line: &str) -> std::result::Result<Point, String> {
    let v = numbers(line)?;
    if v.len() != l.columns {
        return Err(format!(
            "{} numbers, but the file's points have {}",
            v.len(),
            l.columns
        ));
    }
    let p = point_f32("position", l.position.map(|i| v[i]))?;
    let n = (l.normal)
        .map(|c| point_f32("normal", c.map(|i| v[i])))
        .transpose()?;
    let c = match l.color {
        Some((c, full)) => {
            let rgb = c.map(|i| v[i]);
            if !rgb.iter().all(|x| (0.0..=full).contains(x)) {
                let range = if full == 1.0 {
                    "0–1"
                } else {
                    "8-bit, 0–255"
                };
                return Err(format!("colour {rgb:?} is not {range}"));
            }
            Some(rgb.map(|x| (x / full) as f32))
        }
        None => None,
    };
    Ok((p, n, c))
}
