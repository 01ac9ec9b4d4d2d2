//! PLY reader: ASCII and binary (little and big endian), any element layout. Reads vertex
//! positions, optional normals and colours, and face index lists; skips other elements and
//! properties. Header counts are checked against the data size and the memory budget before
//! anything is allocated, so a lying header cannot exhaust memory. Lines may end in LF, CRLF
//! or CR alone (old Mac tools), the same throughout. A cloud's vertex whose position is not
//! finite or cannot be read is skipped and counted (`Reading`; a mesh's is an error, as its
//! faces index the vertices); other errors name the file and line or element.

use std::path::Path;

use super::reading::{LeftOut, Reading, point_f32};
use super::{Mesh, gaussians, normals};
use crate::error::{Error, Result};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar(String, Scalar),
    List(String, Scalar, Scalar),
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the data, and the line number the data starts on (for ASCII errors).
    data_start: usize,
    data_line: usize,
    /// Whether lines end in CR alone.
    cr_only: bool,
}

/// The line ending the first line (`ply`) shows: LF, CRLF or CR alone.
fn line_end(bytes: &[u8]) -> &'static [u8] {
    match bytes.get(3..5) {
        Some([b'\r', b'\n']) => b"\r\n",
        Some([b'\r', _]) | Some([b'\r']) => b"\r",
        _ => b"\n",
    }
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    let err = |line: usize, msg: String| Error::at_line(path, line, msg);
    if !bytes.starts_with(b"ply") {
        return Err(Error::parse(
            path,
            "line 1",
            "not a PLY file (it does not start with `ply`)",
        ));
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0;
    let mut line_no = 0;
    let eol = line_end(bytes);
    loop {
        let end = bytes[pos..]
            .windows(eol.len())
            .position(|w| w == eol)
            .ok_or_else(|| {
                err(
                    line_no + 1,
                    "the header ends before `end_header` (no line `end_header` followed by a \
                     line end)"
                        .into(),
                )
            })?;
        let line = std::str::from_utf8(&bytes[pos..pos + end])
            .map_err(|_| err(line_no + 1, "header is not text".into()))?
            .trim_end_matches('\r');
        pos += end + eol.len();
        line_no += 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["ply"] if line_no == 1 => {}
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    other => return Err(err(line_no, format!("unknown format `{other}`"))),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name @ ("vertex" | "face"), _]
                if elements.iter().any(|e| e.name == *name) =>
            {
                return Err(err(
                    line_no,
                    format!("a second `element {name}`: a PLY file holds one of each"),
                ));
            }
            ["element", name, count] => {
                let count = count.parse::<usize>().map_err(|_| {
                    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
                    let why = match count.strip_prefix('-') {
                        _ if digits(count) => "is too large (more than 2^64)",
                        Some(rest) if digits(rest) => "is negative",
                        _ => "is not a whole number",
                    };
                    err(line_no, format!("element count `{count}` {why}"))
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                });
            }
            ["property", "list", count_ty, item_ty, name] => {
                let (c, i) = (Scalar::parse(count_ty), Scalar::parse(item_ty));
                let (Some(c), Some(i)) = (c, i) else {
                    return Err(err(line_no, format!("unknown type in `{line}`")));
                };
                if !c.is_integer() {
                    return Err(err(
                        line_no,
                        "a list count must have an integer type".into(),
                    ));
                }
                let e = elements
                    .last_mut()
                    .ok_or_else(|| err(line_no, "property before any element".into()))?;
                e.properties.push(Property::List(name.to_string(), c, i));
            }
            ["property", ty, name] => {
                let t = Scalar::parse(ty)
                    .ok_or_else(|| err(line_no, format!("unknown property type `{ty}`")))?;
                let e = elements
                    .last_mut()
                    .ok_or_else(|| err(line_no, "property before any element".into()))?;
                e.properties.push(Property::Scalar(name.to_string(), t));
            }
            ["end_header"] => break,
            _ => return Err(err(line_no, format!("unexpected header line `{line}`"))),
        }
    }
    let format = format.ok_or_else(|| err(line_no, "no `format` line in the header".into()))?;
    Ok(Header {
        format,
        elements,
        data_start: pos,
        data_line: line_no + 1,
        cr_only: eol == b"\r",
    })
}

/// Reads values element by element from ASCII or binary data.
trait Source {
    /// Called before each element (ASCII starts its line).
    fn begin_element(&mut self) -> std::result::Result<(), String> {
        Ok(())
    }
    fn scalar(&mut self, t: Scalar) -> std::result::Result<f64, String>;
    /// Called after each element (ASCII checks the line ended).
    fn end_element(&mut self) -> std::result::Result<(), String> {
        Ok(())
    }
    fn line(&self) -> Option<usize> {
        None
    }
}

struct Binary<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl Source for Binary<'_> {
    fn scalar(&mut self, t: Scalar) -> std::result::Result<f64, String> {
        let n = t.size();
        let b = self
            .data
            .get(self.pos..self.pos + n)
            .ok_or_else(|| "file is truncated".to_string())?;
        self.pos += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(b);
        if self.big_endian {
            a[..n].reverse();
        }
        Ok(match t {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }
}

/// ASCII data: one element a line.
struct Ascii<'a> {
    lines: Box<dyn Iterator<Item = &'a str> + 'a>,
    tokens: Vec<&'a str>,
    next: usize,
    line: usize,
}

impl Source for Ascii<'_> {
    fn begin_element(&mut self) -> std::result::Result<(), String> {
        self.tokens.clear();
        self.next = 0;
        while self.tokens.is_empty() {
            let l = self
                .lines
                .next()
                .ok_or_else(|| "file is truncated".to_string())?;
            self.line += 1;
            self.tokens = l.split_whitespace().collect();
        }
        Ok(())
    }

    fn scalar(&mut self, t: Scalar) -> std::result::Result<f64, String> {
        let tok = *self
            .tokens
            .get(self.next)
            .ok_or_else(|| format!("the line ends after {} values", self.tokens.len()))?;
        self.next += 1;
        let v: f64 = tok
            .parse()
            .map_err(|_| format!("`{tok}` is not a number"))?;
        if t.is_integer() && v.fract() != 0.0 {
            return Err(format!("`{tok}` is not an integer"));
        }
        Ok(v)
    }

    fn end_element(&mut self) -> std::result::Result<(), String> {
        if self.next < self.tokens.len() {
            return Err(format!(
                "{} extra value(s) on the line",
                self.tokens.len() - self.next
            ));
        }
        Ok(())
    }

    fn line(&self) -> Option<usize> {
        Some(self.line)
    }
}

/// Smallest number of bytes one element can take, to bound header counts by the file size.
fn min_element_bytes(e: &Element, format: Format) -> usize {
    e.properties
        .iter()
        .map(|p| match (p, format) {
            // A number and a separator.
            (_, Format::Ascii) => 2,
            (Property::Scalar(_, t), _) => t.size(),
            (Property::List(_, c, _), _) => c.size(),
        })
        .sum::<usize>()
        .max(1)
}

pub fn parse(path: &Path, bytes: &[u8], reading: &Reading) -> Result<Mesh> {
    let header = parse_header(path, bytes)?;
    let data = &bytes[header.data_start..];
    let mut budget = data.len();
    for e in &header.elements {
        let need = e.count.saturating_mul(min_element_bytes(e, header.format));
        if need > budget {
            return Err(Error::parse(
                path,
                format!("element {}", e.name),
                format!(
                    "the header declares {} elements, more than the {} bytes of data can hold",
                    e.count,
                    data.len()
                ),
            ));
        }
        budget -= need;
        if e.name == "vertex" {
            reading.check_points(path, "element vertex", e.count as u64)?;
        }
    }
    let mut source: Box<dyn Source> = match header.format {
        Format::Ascii => {
            let text = std::str::from_utf8(data)
                .map_err(|_| Error::parse(path, "data", "ASCII data is not text"))?;
            let lines: Box<dyn Iterator<Item = &str>> = match header.cr_only {
                true => Box::new(text.split('\r')),
                false => Box::new(text.lines()),
            };
            Box::new(Ascii {
                lines,
                tokens: Vec::new(),
                next: 0,
                line: header.data_line - 1,
            })
        }
        f => Box::new(Binary {
            data,
            pos: 0,
            big_endian: f == Format::BinaryBe,
        }),
    };
    let mut mesh = Mesh::default();
    let mut left_out = LeftOut::default();
    // A mesh's faces index its vertices: a skipped vertex would shift them, so a mesh's bad
    // vertex is an error, as with --strict.
    let has_faces = (header.elements.iter()).any(|e| e.name == "face" && e.count > 0);
    let reading = &Reading {
        strict: reading.strict || has_faces,
        ..*reading
    };
    for e in &header.elements {
        read_element(
            path,
            e,
            source.as_mut(),
            &mut mesh,
            (reading, &mut left_out),
        )?;
    }
    mesh.left_out = left_out;
    // Gaussians' normals have no sign: turn them to one side, as a cloud's PCA normals are.
    if mesh.radii.is_some()
        && let Some(n) = mesh.normals.as_mut()
    {
        normals::orient_normals(&mesh.positions, n);
    }
    Ok(mesh)
}

/// The columns of a Gaussian-splat vertex (`gaussians::Columns`), where the element has them.
fn gaussian_columns(find: &dyn Fn(&[&str]) -> Option<usize>) -> Option<gaussians::Columns> {
    let one = |n: &str| find(&[n]);
    Some(gaussians::Columns {
        dc: [one("f_dc_0")?, one("f_dc_1")?, one("f_dc_2")?],
        opacity: one("opacity")?,
        scale: [one("scale_0")?, one("scale_1")?],
        scale_2: one("scale_2"),
        rot: [one("rot_0")?, one("rot_1")?, one("rot_2")?, one("rot_3")?],
    })
}

fn read_element(
    path: &Path,
    e: &Element,
    src: &mut dyn Source,
    mesh: &mut Mesh,
    (reading, left_out): (&Reading, &mut LeftOut),
) -> Result<()> {
    let find = |names: &[&str]| {
        e.properties
            .iter()
            .position(|p| matches!(p, Property::Scalar(n, _) if names.contains(&n.as_str())))
    };
    let is_vertex = e.name == "vertex";
    let is_face = e.name == "face";
    let pos = [find(&["x"]), find(&["y"]), find(&["z"])];
    let nrm = [find(&["nx"]), find(&["ny"]), find(&["nz"])];
    let col = [
        find(&["red", "r", "diffuse_red"]),
        find(&["green", "g", "diffuse_green"]),
        find(&["blue", "b", "diffuse_blue"]),
    ];
    let idx_list = e.properties.iter().position(
        |p| matches!(p, Property::List(n, _, _) if n == "vertex_indices" || n == "vertex_index"),
    );
    if is_vertex && pos.iter().any(Option::is_none) {
        return Err(Error::parse(
            path,
            "element vertex",
            "vertices need x, y and z properties",
        ));
    }
    let gaussian = if is_vertex {
        gaussian_columns(&find)
    } else {
        None
    };
    let has_normals = is_vertex && nrm.iter().all(Option::is_some) && gaussian.is_none();
    let has_colors = is_vertex && col.iter().all(Option::is_some);
    let color_scale = match col[0].map(|i| &e.properties[i]) {
        Some(Property::Scalar(_, t)) if t.is_integer() => 1.0 / 255.0,
        _ => 1.0,
    };
    if has_normals {
        mesh.normals.get_or_insert_with(Vec::new);
    }
    if has_colors {
        mesh.colors.get_or_insert_with(Vec::new);
    }
    let mut values = vec![0f64; e.properties.len()];
    let mut list: Vec<f64> = Vec::new();
    for k in 0..e.count {
        let at = |msg: String, line: Option<usize>| {
            let place = match line {
                Some(l) => format!("element {} #{k} (line {l})", e.name),
                None => format!("element {} #{k}", e.name),
            };
            Error::parse(path, place, msg)
        };
        src.begin_element().map_err(|m| at(m, src.line()))?;
        // An ASCII vertex that cannot be read is one bad point: its line is skipped.
        let mut unread = None;
        for (j, p) in e.properties.iter().enumerate() {
            match p {
                Property::Scalar(_, t) => match src.scalar(*t) {
                    Ok(v) => values[j] = v,
                    Err(m) if is_vertex && src.line().is_some() => {
                        unread = Some(m);
                        break;
                    }
                    Err(m) => return Err(at(m, src.line())),
                },
                Property::List(_, c, t) => {
                    let n = src.scalar(*c).map_err(|m| at(m, src.line()))?;
                    if !(0.0..=1e6).contains(&n) {
                        return Err(at(format!("list length {n} is out of range"), src.line()));
                    }
                    let keep = Some(j) == idx_list && is_face;
                    if keep {
                        list.clear();
                    }
                    for _ in 0..n as usize {
                        let v = src.scalar(*t).map_err(|m| at(m, src.line()))?;
                        if keep {
                            list.push(v);
                        }
                    }
                }
            }
        }
        let ended = match unread {
            Some(m) => Err(m),
            None => src.end_element(),
        };
        if let Err(m) = ended {
            if !is_vertex {
                return Err(at(m, src.line()));
            }
            left_out.skip(reading, at(m, src.line()))?;
            continue;
        }
        let position = match is_vertex {
            true => match point_f32("position", pos.map(|i| values[i.unwrap_or(0)])) {
                Ok(p) => p,
                Err(m) => {
                    left_out.skip(reading, at(m, src.line()))?;
                    continue;
                }
            },
            false => glam::Vec3::ZERO,
        };
        if let Some(c) = &gaussian {
            match gaussians::read(c, &values) {
                Ok(g) => {
                    mesh.positions.push(position);
                    mesh.normals.get_or_insert_with(Vec::new).push(g.normal);
                    mesh.radii.get_or_insert_with(Vec::new).push(g.radius);
                    mesh.colors.get_or_insert_with(Vec::new).push(g.color);
                }
                Err(rule) => left_out.drop_by(rule),
            }
        } else if is_vertex {
            mesh.positions.push(position);
            if let Some(normals) = mesh.normals.as_mut().filter(|_| has_normals) {
                normals.push(nrm.map(|i| values[i.unwrap_or(0)] as f32).into());
            }
            if let Some(colors) = mesh.colors.as_mut().filter(|_| has_colors) {
                colors.push(col.map(|i| (values[i.unwrap_or(0)] * color_scale) as f32));
            }
        } else if is_face && idx_list.is_some() {
            if list.len() < 3 {
                return Err(at(
                    format!("a face needs at least 3 vertices, got {}", list.len()),
                    src.line(),
                ));
            }
            let idx: Vec<u32> = list
                .iter()
                .map(|&v| {
                    if v >= 0.0 && v < u32::MAX as f64 && v.fract() == 0.0 {
                        Ok(v as u32)
                    } else {
                        Err(at(format!("vertex index {v} is invalid"), src.line()))
                    }
                })
                .collect::<Result<_>>()?;
            mesh.push_polygon(&idx);
        }
    }
    Ok(())
}
