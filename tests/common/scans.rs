//! Models for the tests: a bumpy ball (a scanned model's stand-in) and what a scanner makes of
//! it from one viewpoint.

use glam::Vec3;

/// A bumpy ball, a scanned model's stand-in: a sphere of `radius` whose radius swells and dips
/// by up to 18 % in waves of 6 to 9 to a turn, on a latitude/longitude grid of `rings` rings
/// of `2 rings` vertices, as vertices and triangles (counted from 0, facing out). Its bumps
/// curve about as tightly as a bunny's ears and haunches against the gather radius, and its
/// vertices lie about as densely.
pub fn bumpy_ball(radius: f32, rings: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    use std::f32::consts::PI;
    let around = 2 * rings;
    let r_of = |th: f32, ph: f32| {
        radius
            * (1.0
                + 0.12 * (7.0 * th).sin() * (6.0 * ph).cos()
                + 0.06 * (9.0 * th + 4.0 * ph).cos())
    };
    let mut vertices = Vec::new();
    for i in 1..rings {
        let th = PI * i as f32 / rings as f32;
        for j in 0..around {
            let ph = 2.0 * PI * j as f32 / around as f32;
            let r = r_of(th, ph);
            vertices.push(r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
        }
    }
    let (top, bottom) = ((rings - 1) * around, (rings - 1) * around + 1);
    vertices.push(Vec3::new(0.0, r_of(0.0, 0.0), 0.0));
    vertices.push(Vec3::new(0.0, -r_of(PI, 0.0), 0.0));
    let at = |i: u32, j: u32| (i - 1) * around + j % around;
    let mut faces = Vec::new();
    for i in 1..rings - 1 {
        for j in 0..around {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
            faces.extend([[a, b, c], [a, c, d]]);
        }
    }
    for j in 0..around {
        faces.push([top, at(1, j + 1), at(1, j)]);
        faces.push([bottom, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    (vertices, faces)
}

/// A mesh as OBJ text (which counts vertices from 1).
pub fn obj_text((vertices, faces): &(Vec<Vec3>, Vec<[u32; 3]>)) -> String {
    use std::fmt::Write;
    let mut obj = String::new();
    for v in vertices {
        writeln!(obj, "v {} {} {}", v.x, v.y, v.z).unwrap();
    }
    for [a, b, c] in faces {
        writeln!(obj, "f {} {} {}", a + 1, b + 1, c + 1).unwrap();
    }
    obj
}

/// What a scanner makes of a model from one viewpoint.
#[derive(Clone, Copy, Debug)]
pub enum Scan {
    /// The faces the viewpoint sees: an open sheet with a ragged border.
    Sheet,
    /// That sheet with holes where the scanner saw nothing.
    Holes,
    /// That sheet with noise along the line of sight.
    Noisy,
}

/// The scan `kind` of mesh `(vertices, faces)` from direction `view`: the faces whose normal
/// n has n · view > 0.15 (as `benches/open_scans.py` makes of the shipped models), with
/// 16 holes of a tenth of the model's size, or each vertex moved along `view` by Gaussian
/// noise of 0.4 % of its size.
pub fn single_view_scan(
    (vertices, faces): &(Vec<Vec3>, Vec<[u32; 3]>),
    view: Vec3,
    kind: Scan,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let view = view.normalize();
    let (lo, hi) = vertices
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let size = (hi - lo).max_element();
    let mut rng = super::Rng(7);
    let seen: Vec<[u32; 3]> = faces
        .iter()
        .copied()
        .filter(|f| {
            let [a, b, c] = f.map(|i| vertices[i as usize]);
            (b - a).cross(c - a).normalize().dot(view) > 0.15
        })
        .collect();
    let holes: Vec<Vec3> = match kind {
        Scan::Holes => (0..16)
            .map(|_| vertices[seen[(rng.f32() * seen.len() as f32) as usize][0] as usize])
            .collect(),
        _ => Vec::new(),
    };
    let kept: Vec<[u32; 3]> = seen
        .into_iter()
        .filter(|f| {
            let centre = f.iter().map(|&i| vertices[i as usize]).sum::<Vec3>() / 3.0;
            holes.iter().all(|h| h.distance(centre) > 0.05 * size)
        })
        .collect();
    // Only the vertices the kept faces use, renumbered.
    let mut index = vec![u32::MAX; vertices.len()];
    let mut out = Vec::new();
    let faces = kept
        .iter()
        .map(|f| {
            f.map(|i| {
                if index[i as usize] == u32::MAX {
                    index[i as usize] = out.len() as u32;
                    out.push(vertices[i as usize]);
                }
                index[i as usize]
            })
        })
        .collect();
    if let Scan::Noisy = kind {
        for v in &mut out {
            // Box–Muller.
            let (u1, u2) = (rng.f32().max(1e-7), rng.f32());
            let g = (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos();
            *v += 0.004 * size * g * view;
        }
    }
    (out, faces)
}
