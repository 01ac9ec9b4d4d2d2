//! Models: PLY and OBJ files, text point clouds (.xyz, .pts; gzip too), LAS/LAZ lidar and E57
//! scans read into a `Mesh`, then turned into splats.
//! A mesh gives one splat per vertex with the area-weighted normal of its faces and a radius
//! that covers its triangles; a point cloud uses its normals if it has them, PCA normals
//! otherwise, and radii from the neighbour spacing (`normals`).

pub mod gaussians;
pub mod lidar;
pub mod normals;
pub mod obj;
pub mod ply;
pub mod reading;
pub mod scan;
pub mod surface;
pub mod text;

use std::io::Read;
use std::path::Path;

use crate::budget;
pub use reading::{LeftOut, Reading};

use glam::{Affine3A, Vec3};

use crate::error::{Error, Result};
use crate::scene::file::Anchor;
use crate::scene::shapes::{Disk, max_scale, normal_matrix};

/// Vertices, optional per-vertex normals and colours (as stored: sRGB in [0, 1]), triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub colors: Option<Vec<[f32; 3]>>,
    pub faces: Vec<[u32; 3]>,
    /// Per-vertex splat radii where the file gives them (Gaussian splats); a cloud without
    /// them takes radii from its neighbour spacing.
    pub radii: Option<Vec<f32>>,
    /// Points the reader skipped (unreadable, not finite) or left out by a rule (Gaussians
    /// too faint to be a surface).
    pub left_out: LeftOut,
    /// The file's materials (OBJ `usemtl`, defined by its `mtllib` files) and each face's
    /// index into them (`u32::MAX`: none); empty where the file names none.
    pub materials: Vec<MeshMaterial>,
    pub face_materials: Vec<u32>,
    /// The OBJ's `mtllib` files, relative to it.
    pub material_libraries: Vec<String>,
}

/// A material a mesh file names: MTL `Kd` (diffuse), `Ks` (specular) and `Ns` (Phong exponent).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshMaterial {
    pub name: String,
    /// Whether a material library defined it.
    pub defined: bool,
    pub kd: [f32; 3],
    pub ks: [f32; 3],
    pub ns: f32,
}

impl Default for MeshMaterial {
    /// MTL's defaults: grey diffuse, no specular.
    fn default() -> Self {
        MeshMaterial {
            name: String::new(),
            defined: false,
            kd: [0.8; 3],
            ks: [0.0; 3],
            ns: 0.0,
        }
    }
}

impl Mesh {
    /// Adds a polygon as a triangle fan.
    pub fn push_polygon(&mut self, idx: &[u32]) {
        for k in 1..idx.len().saturating_sub(1) {
            self.faces.push([idx[0], idx[k], idx[k + 1]]);
        }
    }
}

/// Largest decompressed model accepted, so a small gzip bomb cannot exhaust memory.
const MAX_MODEL_BYTES: u64 = 4 << 30;

/// Reads a model file with the reading in force (`Reading::current`).
pub fn load(path: &Path) -> Result<Mesh> {
    load_with(path, &Reading::current())
}

/// `load` with `reading`: its budget bounds what the file may announce, and a gzip file
/// inflates to at most `MAX_MODEL_BYTES` and to the budget's share for the file (a quarter:
/// its parse and splats take the rest), else it is refused, never cut short.
pub fn load_with(path: &Path, reading: &Reading) -> Result<Mesh> {
    let budget = &reading.budget;
    let raw = budget.read_file(path)?;
    let bytes = if raw.starts_with(&[0x1f, 0x8b]) {
        let limit = MAX_MODEL_BYTES.min(budget.bytes / 4);
        let mut out = Vec::new();
        flate2::read::GzDecoder::new(&raw[..])
            .take(limit + 1)
            .read_to_end(&mut out)
            .map_err(|e| Error::parse(path, "gzip", format!("cannot decompress: {e}")))?;
        if out.len() as u64 > limit {
            return Err(Error::parse(
                path,
                "gzip",
                format!(
                    "it inflates to more than {} (a quarter of the memory budget of {}, 4 GiB \
                     at most): subsample its points, or raise --max-memory",
                    budget::human(limit),
                    budget::human(budget.bytes)
                ),
            ));
        }
        out
    } else {
        raw
    };
    let name = path.to_string_lossy().to_ascii_lowercase();
    let name = name.strip_suffix(".gz").unwrap_or(&name);
    let mesh = if name.ends_with(".ply") {
        ply::parse(path, &bytes, reading)?
    } else if name.ends_with(".obj") {
        let mut mesh = obj::parse(path, &bytes)?;
        obj::materials(path, &mut mesh)?;
        mesh
    } else if name.ends_with(".xyz") || name.ends_with(".pts") {
        text::parse(path, &bytes, reading)?
    } else if name.ends_with(".las") || name.ends_with(".laz") {
        lidar::parse(path, bytes, reading)?
    } else if name.ends_with(".e57") {
        scan::parse(path, bytes, reading)?
    } else {
        return Err(Error::parse(
            path,
            "name",
            "unknown model format: expected .ply, .obj, .xyz, .pts (each also gzipped, .gz), \
             .las, .laz or .e57",
        ));
    };
    validate(path, &mesh)?;
    Ok(mesh)
}

/// Checks a mesh handed over in memory (`scene::Arrays`) as a loader checks its file, and
/// what a loader skips instead: a point, normal or radius that is not finite, a radius not
/// above 0. `name` names it in errors.
pub fn check_array(name: &Path, m: &Mesh) -> Result<()> {
    validate(name, m)?;
    let bad = |what: &str, k: usize, v: String| Err(Error::parse(name, format!("{what} #{k}"), v));
    if let Some(k) = m.positions.iter().position(|p| !p.is_finite()) {
        return bad("point", k, format!("not finite: {}", m.positions[k]));
    }
    if let Some(n) = &m.normals
        && let Some(k) = n.iter().position(|v| !v.is_finite())
    {
        return bad("normal", k, format!("not finite: {}", n[k]));
    }
    if let Some(c) = &m.colors
        && let Some(k) = c.iter().position(|v| !v.iter().all(|x| x.is_finite()))
    {
        return bad("colour", k, format!("not finite: {:?}", c[k]));
    }
    if let Some(r) = &m.radii
        && let Some(k) = r.iter().position(|&v| !(v.is_finite() && v > 0.0))
    {
        return bad(
            "radius",
            k,
            format!("must be finite and above 0, got {}", r[k]),
        );
    }
    Ok(())
}

fn validate(path: &Path, m: &Mesh) -> Result<()> {
    if m.positions.is_empty() {
        let why = match m.left_out.skipped + m.left_out.dropped() {
            0 => "the model has no vertices or points".to_string(),
            _ => format!("no point of the file is kept: {}", m.left_out.why_none()),
        };
        return Err(Error::parse(path, "points", why));
    }
    let materials = m.materials.len() as u32;
    let bad_material = !m.face_materials.is_empty() && m.face_materials.len() != m.faces.len()
        || m.face_materials
            .iter()
            .any(|&k| k != u32::MAX && k >= materials);
    if bad_material {
        return Err(Error::parse(
            path,
            "materials",
            "face materials do not match the faces",
        ));
    }
    let n = m.positions.len() as u32;
    if let Some(k) = m.faces.iter().position(|f| f.iter().any(|&i| i >= n)) {
        return Err(Error::parse(
            path,
            format!("face #{k}"),
            format!(
                "vertex index out of range: {:?} with {n} vertices",
                m.faces[k]
            ),
        ));
    }
    for (what, len) in [
        ("normals", m.normals.as_ref().map(Vec::len)),
        ("colors", m.colors.as_ref().map(Vec::len)),
        ("radii", m.radii.as_ref().map(Vec::len)),
    ] {
        if let Some(len) = len.filter(|&l| l != m.positions.len()) {
            return Err(Error::parse(
                path,
                what,
                format!("{len} {what} for {n} vertices"),
            ));
        }
    }
    Ok(())
}

/// Splats of a model in its own coordinates, with linear-RGB colours when it has colours.
#[derive(Clone, Debug, Default)]
pub struct SplatSet {
    pub disks: Vec<Disk>,
    pub colors: Option<Vec<[f32; 3]>>,
    /// Per disk, its index into the mesh's materials (`u32::MAX`: none), where the mesh has
    /// face materials and its surface was sampled.
    pub materials: Option<Vec<u32>>,
    /// Vertices no (non-degenerate) face uses (they have no normal or extent), and those the
    /// reader left out (`Mesh::dropped`).
    pub dropped: usize,
}

pub fn srgb_to_linear(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// `v` scaled to unit length, or zero where it has no direction f32 can normalise (zero,
/// not finite, or so short that its squared length is denormal).
fn unit_or_zero(v: Vec3) -> Vec3 {
    if v.is_finite() && v.length_squared() >= f32::MIN_POSITIVE {
        v.normalize()
    } else {
        Vec3::ZERO
    }
}

pub fn to_splats(mesh: &Mesh, path: &Path) -> Result<SplatSet> {
    // `load` validated already; a mesh built elsewhere is checked here, not trusted.
    validate(path, mesh)?;
    let (normals, radii) = if mesh.faces.is_empty() {
        let radii = match &mesh.radii {
            Some(r) => r.clone(),
            None => normals::spacing_radii(&mesh.positions),
        };
        let normals = match &mesh.normals {
            Some(n) => n.iter().map(|&v| unit_or_zero(v)).collect(),
            None => normals::pca_normals(&mesh.positions),
        };
        (normals, radii)
    } else {
        mesh_normals_and_radii(mesh)
    };
    let mut set = SplatSet {
        dropped: mesh.left_out.dropped(),
        ..Default::default()
    };
    let mut colors = mesh.colors.as_ref().map(|_| Vec::new());
    for (i, p) in mesh.positions.iter().enumerate() {
        let (n, r) = (normals[i], radii[i]);
        if n == Vec3::ZERO || !(r > 0.0 && r.is_finite()) {
            set.dropped += 1;
            continue;
        }
        set.disks.push(Disk {
            center: *p,
            normal: n,
            radius: r,
        });
        if let (Some(out), Some(src)) = (colors.as_mut(), mesh.colors.as_ref()) {
            out.push(src[i].map(srgb_to_linear));
        }
    }
    if set.disks.is_empty() {
        return Err(Error::parse(path, "points", no_usable_point(mesh)));
    }
    set.colors = colors;
    Ok(set)
}

/// Why `mesh` made no splat: a mesh's faces have no area; a cloud's points have no
/// neighbours apart from them to take a normal and a radius from.
fn no_usable_point(mesh: &Mesh) -> String {
    let n = mesh.positions.len();
    if !mesh.faces.is_empty() {
        return format!(
            "no usable vertex: every face of the {} is degenerate (no area)",
            mesh.faces.len()
        );
    }
    let first = mesh.positions[0];
    if mesh.positions.iter().all(|&p| p == first) {
        return format!(
            "all {n} points are the one point {first}: a cloud needs points spread over a surface"
        );
    }
    let (lo, hi) = bounds(mesh.positions.iter().copied());
    // Neighbour searches and normals square distances: past 1.8e19 they overflow f32.
    if !(hi - lo).length_squared().is_finite() {
        let at = |p: Vec3| format!("[{:.2e}, {:.2e}, {:.2e}]", p.x, p.y, p.z);
        return format!(
            "its {n} points span {} to {}, too far for f32 to square their distances (past \
             1.8e19 apart): scale the cloud down",
            at(lo),
            at(hi)
        );
    }
    format!(
        "none of its {n} points has a normal and a radius: they lie on a line, or are too few \
         (under 3) to span a surface"
    )
}

/// Area-weighted vertex normals, and per-vertex radii that cover every incident triangle:
/// the largest over its triangles of the distance from a vertex to the point of the triangle
/// farthest from all three vertices (the circumcentre when acute, else the longest edge's
/// midpoint).
fn mesh_normals_and_radii(mesh: &Mesh) -> (Vec<Vec3>, Vec<f32>) {
    let n = mesh.positions.len();
    let mut normals = vec![Vec3::ZERO; n];
    let mut radii = vec![0f32; n];
    for f in &mesh.faces {
        let [a, b, c] = f.map(|i| mesh.positions[i as usize]);
        let cross = (b - a).cross(c - a);
        if cross.length_squared() <= f32::MIN_POSITIVE || !cross.is_finite() {
            continue;
        }
        let cover = triangle_cover_radius(a, b, c);
        for &i in f {
            normals[i as usize] += cross;
            radii[i as usize] = radii[i as usize].max(cover);
        }
    }
    let normals = match &mesh.normals {
        // File normals where valid, computed ones elsewhere.
        Some(file) => file
            .iter()
            .zip(&normals)
            .map(|(f, c)| {
                if f.is_finite() && f.length() > 1e-12 {
                    f.normalize()
                } else {
                    c.normalize_or_zero()
                }
            })
            .collect(),
        None => normals.iter().map(|v| v.normalize_or_zero()).collect(),
    };
    (normals, radii)
}

/// Radius around each vertex that covers a triangle (see `mesh_normals_and_radii`).
pub fn triangle_cover_radius(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let (ab, bc, ca) = ((b - a).length(), (c - b).length(), (a - c).length());
    let longest = ab.max(bc).max(ca);
    let (x, y, z) = (
        (b - a).length_squared(),
        (c - b).length_squared(),
        (a - c).length_squared(),
    );
    let max_sq = x.max(y).max(z);
    if max_sq >= x + y + z - max_sq {
        // Right or obtuse: the longest edge's midpoint is the farthest point.
        return 0.5 * longest;
    }
    let area2 = (b - a).cross(c - a).length();
    // Circumradius R = abc / (4 · area) = abc / (2 · |cross|).
    ab * bc * ca / (2.0 * area2)
}

/// The least and greatest corner of `points` (infinite, inverted, where there is none).
fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    })
}

/// Moves model splats into the scene: optional fit to a size and anchor, then the transform.
pub fn place(disks: &[Disk], fit: Option<f32>, anchor: Anchor, m: &Affine3A) -> Vec<Disk> {
    let (lo, hi) = bounds(disks.iter().map(|d| d.center));
    let (offset, scale) = match fit {
        Some(size) => {
            let extent = (hi - lo).max_element().max(f32::MIN_POSITIVE);
            let center = 0.5 * (lo + hi);
            let anchor_point = match anchor {
                Anchor::Center => center,
                Anchor::Bottom => Vec3::new(center.x, lo.y, center.z),
            };
            (anchor_point, size / extent)
        }
        None => (Vec3::ZERO, 1.0),
    };
    let nm = normal_matrix(m);
    let stretch = max_scale(m);
    disks
        .iter()
        .map(|d| Disk {
            center: m.transform_point3((d.center - offset) * scale),
            normal: (nm * d.normal).normalize_or_zero(),
            radius: d.radius * scale * stretch,
        })
        .collect()
}
