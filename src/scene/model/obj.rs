//! Wavefront OBJ reader: `v x y z [r g b]` (the common vertex-colour extension, colours in
//! [0, 1]) and `f` polygons (`i`, `i/t`, `i/t/n`, `i//n`, negative indices relative to the end),
//! each face with the material `usemtl` last named; `mtllib` files are read by `materials`.
//! Other known statements are skipped; anything else is an error naming the line, so a file
//! that is not OBJ at all is caught instead of loading as an empty model.

use std::path::Path;

use super::{Mesh, MeshMaterial, reading};
use crate::error::{Error, Result};

/// Statements that carry nothing splats use.
const IGNORED: &[&str] = &[
    "vt",
    "vn",
    "vp",
    "g",
    "o",
    "s",
    "l",
    "p",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "mg",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
];

pub fn parse(path: &Path, bytes: &[u8]) -> Result<Mesh> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1;
        Error::at_line(path, line, "not a text file (invalid UTF-8)")
    })?;
    // A byte-order mark some tools write first is no statement.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut mesh = Mesh::default();
    let mut colored = None;
    let mut idx = Vec::new();
    let mut material: Option<u32> = None;
    for (n, raw) in text.lines().enumerate() {
        let err = |msg: String| Error::at_line(path, n + 1, msg);
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => {
                // Read as f64, so that 1e300 is out of f32's range rather than infinite.
                let vals: Vec<f32> = words
                    .map(|w| {
                        let v = (w.parse::<f64>())
                            .map_err(|_| err(format!("`{w}` is not a number")))?;
                        reading::to_f32(v).map_err(|m| err(format!("vertex coordinate {m}")))
                    })
                    .collect::<Result<_>>()?;
                let has_color = match vals.len() {
                    3 | 4 => false,
                    6 => true,
                    k => return Err(err(format!("a vertex needs 3, 4 or 6 numbers, got {k}"))),
                };
                if !vals.iter().all(|v| v.is_finite()) {
                    return Err(err(format!("vertex {vals:?} is not finite")));
                }
                // Colours only count when every vertex has them.
                if *colored.get_or_insert(has_color) != has_color {
                    return Err(err("some vertices have colours and others do not".into()));
                }
                mesh.positions.push([vals[0], vals[1], vals[2]].into());
                if has_color {
                    mesh.colors
                        .get_or_insert_with(Vec::new)
                        .push([vals[3], vals[4], vals[5]]);
                }
            }
            "f" => {
                idx.clear();
                let count = mesh.positions.len() as i64;
                for w in words {
                    let first = w.split('/').next().unwrap_or("");
                    let i: i64 = first
                        .parse()
                        .map_err(|_| err(format!("`{w}` is not a vertex reference")))?;
                    // 1-based; negative counts back from the last vertex read so far.
                    let resolved = if i > 0 { i - 1 } else { count + i };
                    if i == 0 || resolved < 0 || resolved >= count {
                        return Err(err(format!(
                            "vertex reference {i} is out of range (1..={count})"
                        )));
                    }
                    idx.push(resolved as u32);
                }
                if idx.len() < 3 {
                    return Err(err(format!(
                        "a face needs at least 3 vertices, got {}",
                        idx.len()
                    )));
                }
                let before = mesh.faces.len();
                mesh.push_polygon(&idx);
                if let Some(k) = material {
                    // Faces before the first `usemtl` get no material of the file's.
                    mesh.face_materials.resize(before, u32::MAX);
                    mesh.face_materials.resize(mesh.faces.len(), k);
                }
            }
            "usemtl" => {
                let name = line["usemtl".len()..].trim().to_string();
                let k = match mesh.materials.iter().position(|m| m.name == name) {
                    Some(k) => k,
                    None => {
                        mesh.materials.push(MeshMaterial {
                            name,
                            ..Default::default()
                        });
                        mesh.materials.len() - 1
                    }
                };
                material = Some(k as u32);
            }
            "mtllib" => mesh.material_libraries.extend(words.map(str::to_string)),
            k if IGNORED.contains(&k) => {}
            k => {
                let shown: String = k.chars().take(20).collect();
                return Err(err(format!(
                    "unknown statement `{shown}`: is this an OBJ file?"
                )));
            }
        }
    }
    if !mesh.face_materials.is_empty() {
        mesh.face_materials.resize(mesh.faces.len(), u32::MAX);
    }
    Ok(mesh)
}

/// Reads the MTL files an OBJ names (beside it) into its materials: `Kd`, `Ks` and `Ns` of each
/// `newmtl` it uses. A library that cannot be read, or a material it does not define, leaves
/// that material undefined (`MeshMaterial::defined`): the scene may name a material instead.
/// A malformed line is an error naming the MTL file and line.
pub fn materials(obj: &Path, mesh: &mut Mesh) -> Result<()> {
    let dir = obj.parent().unwrap_or(Path::new("."));
    for lib in mesh.material_libraries.clone() {
        let path = dir.join(&lib);
        let Ok(bytes) = Error::read_regular_file(&path) else {
            continue;
        };
        let text = String::from_utf8_lossy(&bytes);
        let mut current: Option<usize> = None;
        for (n, raw) in text.lines().enumerate() {
            let err = |msg: String| Error::at_line(&path, n + 1, msg);
            let line = raw.split('#').next().unwrap_or("").trim();
            let mut words = line.split_whitespace();
            let Some(keyword) = words.next() else {
                continue;
            };
            let numbers = |words: std::str::SplitWhitespace| -> Result<Vec<f32>> {
                words
                    .map(|w| {
                        w.parse::<f32>()
                            .ok()
                            .filter(|v| v.is_finite())
                            .ok_or_else(|| err(format!("`{w}` is not a finite number")))
                    })
                    .collect()
            };
            match keyword {
                "newmtl" => {
                    let name = line["newmtl".len()..].trim();
                    current = mesh.materials.iter().position(|m| m.name == name);
                    if let Some(k) = current {
                        mesh.materials[k].defined = true;
                    }
                }
                "Kd" | "Ks" | "Ns" => {
                    let Some(k) = current else { continue };
                    let v = numbers(words)?;
                    let m = &mut mesh.materials[k];
                    match (keyword, v.as_slice()) {
                        ("Ns", [ns]) => m.ns = *ns,
                        ("Kd", [r, g, b]) => m.kd = [*r, *g, *b],
                        ("Ks", [r, g, b]) => m.ks = [*r, *g, *b],
                        ("Kd" | "Ks", [x]) => {
                            let c = [*x; 3];
                            if keyword == "Kd" { m.kd = c } else { m.ks = c }
                        }
                        _ => return Err(err(format!("`{keyword}` needs 1 or 3 numbers"))),
                    }
                }
                _ => {}
            }
        }
    }
    Ok(())
}
