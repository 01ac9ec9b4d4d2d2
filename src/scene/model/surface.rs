//! A mesh's surface sampled at a spacing: coarse meshes (CAD, architecture: a wall of two
//! triangles) as well as dense scans become splats of about that spacing. Each triangle is cut
//! into k² similar sub-triangles; each gives one splat at its
//! centroid, facing along the triangle's normal, of the radius that covers the sub-triangle
//! (its farthest corner from the centroid), so the surface has no holes. Vertex colours are
//! interpolated at the centroid; each splat keeps its triangle's material. k is chosen for
//! about one splat per spacing² of area (k = ⌈√area / spacing⌉), but never so few that a
//! sub-triangle's longest edge exceeds two spacings (slivers).

use glam::Vec3;

use super::{Mesh, SplatSet, srgb_to_linear};
use crate::scene::shapes::Disk;

/// The splats of `mesh` at `spacing` (model units), with linear-RGB colours where the mesh has
/// vertex colours and material indices (`Mesh::materials`, `u32::MAX` for none) where its
/// faces have them. Degenerate triangles (no area) make no splat and are counted.
pub fn sample_surface(mesh: &Mesh, spacing: f32) -> SplatSet {
    let mut set = SplatSet {
        dropped: mesh.left_out.dropped(),
        ..Default::default()
    };
    let mut colors = mesh.colors.as_ref().map(|_| Vec::new());
    let mut materials = (!mesh.face_materials.is_empty()).then(Vec::new);
    for (f, face) in mesh.faces.iter().enumerate() {
        let [a, b, c] = face.map(|i| mesh.positions[i as usize]);
        let Some(k) = cuts(a, b, c, spacing) else {
            set.dropped += 1;
            continue;
        };
        let normal = (b - a).cross(c - a).normalize();
        let (du, dv) = ((b - a) / k as f32, (c - a) / k as f32);
        let corner = |i: u32, j: u32| a + i as f32 * du + j as f32 * dv;
        // Barycentric weights of a point a + s du + t dv, for colours.
        let weights = |s: f32, t: f32| {
            let (wb, wc) = (s / k as f32, t / k as f32);
            [1.0 - wb - wc, wb, wc]
        };
        for i in 0..k {
            for j in 0..k - i {
                // The sub-triangle pointing like the triangle, and (but on the last row) the
                // one pointing the other way.
                let up = [corner(i, j), corner(i + 1, j), corner(i, j + 1)];
                let mut subs = vec![(up, (i as f32 + 1.0 / 3.0, j as f32 + 1.0 / 3.0))];
                if i + j + 1 < k {
                    let down = [corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)];
                    subs.push((down, (i as f32 + 2.0 / 3.0, j as f32 + 2.0 / 3.0)));
                }
                for (tri, (s, t)) in subs {
                    let center = (tri[0] + tri[1] + tri[2]) / 3.0;
                    let radius = tri
                        .iter()
                        .map(|p| (*p - center).length())
                        .fold(0.0, f32::max);
                    set.disks.push(Disk {
                        center,
                        normal,
                        radius,
                    });
                    if let (Some(out), Some(src)) = (colors.as_mut(), mesh.colors.as_ref()) {
                        let w = weights(s, t);
                        let rgb = (0..3).map(|ch| {
                            let v: f32 = (0..3).map(|q| w[q] * src[face[q] as usize][ch]).sum();
                            srgb_to_linear(v)
                        });
                        let mut c = [0.0; 3];
                        c.iter_mut().zip(rgb).for_each(|(d, v)| *d = v);
                        out.push(c);
                    }
                    if let Some(m) = materials.as_mut() {
                        m.push(mesh.face_materials[f]);
                    }
                }
            }
        }
    }
    set.colors = colors;
    set.materials = materials;
    set
}

/// Splats `sample_surface` makes of `mesh` at `spacing`, counted before any is made (the
/// memory budget's estimate).
pub fn planned(mesh: &Mesh, spacing: f32) -> f64 {
    mesh.faces
        .iter()
        .filter_map(|face| {
            let [a, b, c] = face.map(|i| mesh.positions[i as usize]);
            cuts(a, b, c, spacing)
        })
        .map(|k| k as f64 * k as f64)
        .sum()
}

/// The cuts k of triangle abc's edges at `spacing` (k² sub-triangles), or none for a
/// degenerate triangle (no area, or not finite).
fn cuts(a: Vec3, b: Vec3, c: Vec3, spacing: f32) -> Option<u32> {
    let normal = (b - a).cross(c - a);
    if !normal.is_finite() || normal.length() <= 0.0 {
        return None;
    }
    let area = 0.5 * normal.length();
    let longest = (b - a).length().max((c - b).length()).max((a - c).length());
    let k = (area.sqrt() / spacing)
        .ceil()
        .max((longest / (2.0 * spacing)).ceil())
        .clamp(1.0, 4096.0);
    Some(k as u32)
}

/// The mean edge length of a mesh's triangles, in model units (0 without triangles).
pub fn mean_edge(mesh: &Mesh) -> f32 {
    let (sum, n) = mesh.faces.iter().fold((0.0f64, 0u64), |(s, n), f| {
        let [a, b, c] = f.map(|i| mesh.positions[i as usize]);
        let e = (b - a).length() + (c - b).length() + (a - c).length();
        (s + e as f64, n + 3)
    });
    if n == 0 { 0.0 } else { (sum / n as f64) as f32 }
}

/// The largest side of a mesh's bounding box.
pub fn extent(mesh: &Mesh) -> f32 {
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    (hi - lo).max_element().max(0.0)
}
