//! Procedural shapes as splats: every flat face is a parallelogram sampled on a regular grid,
//! each sample a disk whose radius is half the sample cell's diagonal (so disks cover the
//! face without holes) with a small overlap; spheres use a Fibonacci lattice.

use glam::{Affine3A, Mat3, Vec3};

use crate::types::SurfaceClip;

/// A splat before material assignment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    pub center: Vec3,
    pub normal: Vec3,
    pub radius: f32,
}

/// Disks overlap their sample cell's circumcircle by this factor, so that float rounding
/// and the tilt of neighbouring disks leave no pinholes.
const OVERLAP: f32 = 1.05;

/// Samples the parallelogram `corner + s·u + t·v` (s, t in [0, 1]) with `normal`.
pub fn parallelogram(
    corner: Vec3,
    u: Vec3,
    v: Vec3,
    normal: Vec3,
    spacing: f32,
    out: &mut Vec<Disk>,
) {
    let nu = ((u.length() / spacing).round() as u32).max(1);
    let nv = ((v.length() / spacing).round() as u32).max(1);
    let (du, dv) = (u / nu as f32, v / nv as f32);
    // Circumradius of a parallelogram cell: half its longer diagonal.
    let radius = 0.5 * (du + dv).length().max((du - dv).length()) * OVERLAP;
    for j in 0..nv {
        for i in 0..nu {
            let center = corner + du * (i as f32 + 0.5) + dv * (j as f32 + 0.5);
            out.push(Disk {
                center,
                normal,
                radius,
            });
        }
    }
}

/// A face of [-1, 1]³ in local space: corner, two edges; the outward normal is u × v.
const CUBE_FACES: [([f32; 3], [f32; 3], [f32; 3]); 6] = [
    ([1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]), // +x
    ([-1.0, -1.0, -1.0], [0.0, 0.0, 2.0], [0.0, 2.0, 0.0]), // -x
    ([-1.0, 1.0, -1.0], [0.0, 0.0, 2.0], [2.0, 0.0, 0.0]), // +y
    ([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]), // -y
    ([-1.0, -1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]), // +z
    ([-1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [2.0, 0.0, 0.0]), // -z
];

/// Transforms a local face and samples it; the normal follows the transformed edges, flipped
/// if the transform mirrors (negative determinant).
fn face(
    m: &Affine3A,
    (c, u, v): ([f32; 3], [f32; 3], [f32; 3]),
    flip: bool,
    spacing: f32,
    out: &mut Vec<Disk>,
) {
    let corner = m.transform_point3(c.into());
    let (u, v) = (m.transform_vector3(u.into()), m.transform_vector3(v.into()));
    let mut n = u.cross(v).normalize_or_zero();
    if flip ^ (m.matrix3.determinant() < 0.0) {
        n = -n;
    }
    parallelogram(corner, u, v, n, spacing, out);
}

/// The cube [-1, 1]³ with outward normals.
pub fn cube(m: &Affine3A, spacing: f32, out: &mut Vec<Disk>) {
    for f in CUBE_FACES {
        face(m, f, false, spacing, out);
    }
}

/// Walls of the Cornell box in the order (floor, ceiling, back, left, right), normals inward;
/// the +z face is open. Returns the number of disks of each wall.
pub fn cornell_walls(m: &Affine3A, spacing: f32, out: &mut Vec<Disk>) -> [usize; 5] {
    // -y, +y, -z, -x, +x faces of the cube, flipped inwards.
    let walls = [
        CUBE_FACES[3],
        CUBE_FACES[2],
        CUBE_FACES[5],
        CUBE_FACES[1],
        CUBE_FACES[0],
    ];
    let mut counts = [0; 5];
    for (k, f) in walls.into_iter().enumerate() {
        let before = out.len();
        face(m, f, true, spacing, out);
        counts[k] = out.len() - before;
    }
    counts
}

/// A `w × h` rectangle in the local xy plane, centred, normal +z.
pub fn quad(m: &Affine3A, size: [f32; 2], spacing: f32, out: &mut Vec<Disk>) {
    let (w, h) = (size[0], size[1]);
    face(
        m,
        ([-w / 2.0, -h / 2.0, 0.0], [w, 0.0, 0.0], [0.0, h, 0.0]),
        false,
        spacing,
        out,
    );
}

/// Where `quad`'s disks end: its rectangle, built from the transformed edges and normal so that
/// a transform that flattens local z (the quad's own normal) still clips.
pub fn quad_clip(m: &Affine3A, size: [f32; 2], spacing: f32) -> SurfaceClip {
    let u = m.transform_vector3(Vec3::new(size[0] / 2.0, 0.0, 0.0));
    let v = m.transform_vector3(Vec3::new(0.0, size[1] / 2.0, 0.0));
    let n = u.cross(v).normalize_or_zero();
    let rect = Affine3A::from_cols(u.into(), v.into(), n.into(), m.translation);
    SurfaceClip::of_cube(&rect, CLIP_SLACK * spacing)
}

/// Where `cube`'s (or `cornell_walls`') disks end: the cube.
pub fn cube_clip(m: &Affine3A, spacing: f32) -> SurfaceClip {
    SurfaceClip::of_cube(m, CLIP_SLACK * spacing)
}

/// How far past its shape a clipped surface's hit still counts, in splat spacings: far above
/// a hit point's rounding, far below the disks' overhang (a third of a spacing).
pub const CLIP_SLACK: f32 = 1e-3;

/// A sphere of `radius` (local units) with a Fibonacci lattice at about `spacing` (world units).
pub fn sphere(m: &Affine3A, radius: f32, spacing: f32, out: &mut Vec<Disk>) {
    let world_radius = radius * max_scale(m);
    let area = 4.0 * std::f32::consts::PI * world_radius * world_radius;
    let n = ((area / (spacing * spacing)).round() as u32).max(12);
    // A Fibonacci lattice's largest empty circle is about 1.3 times the radius of a disk of the
    // per-point area; 1.4 leaves a margin.
    let disk = 1.4 * (area / n as f32 / std::f32::consts::PI).sqrt();
    let normal_matrix = normal_matrix(m);
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    for k in 0..n {
        let z = 1.0 - (2.0 * k as f32 + 1.0) / n as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = golden * k as f32;
        let p = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        out.push(Disk {
            center: m.transform_point3(p * radius),
            normal: (normal_matrix * p).normalize_or_zero(),
            radius: disk,
        });
    }
}

/// Disks `parallelogram` makes of edges `u`, `v`, counted in f64 so that no spacing overflows.
fn grid_count(u: Vec3, v: Vec3, spacing: f32) -> f64 {
    let n = |e: Vec3| (e.length() as f64 / spacing as f64).round().max(1.0);
    n(u) * n(v)
}

fn faces_count(m: &Affine3A, faces: &[([f32; 3], [f32; 3], [f32; 3])], spacing: f32) -> f64 {
    faces
        .iter()
        .map(|&(_, u, v)| {
            let (u, v) = (m.transform_vector3(u.into()), m.transform_vector3(v.into()));
            grid_count(u, v, spacing)
        })
        .sum()
}

/// How many disks `cube` makes (NaN or infinite for a transform that is).
pub fn cube_count(m: &Affine3A, spacing: f32) -> f64 {
    faces_count(m, &CUBE_FACES, spacing)
}

/// How many disks `cornell_walls` makes.
pub fn cornell_count(m: &Affine3A, spacing: f32) -> f64 {
    faces_count(m, &CUBE_FACES[..5], spacing)
}

/// How many disks `quad` makes.
pub fn quad_count(m: &Affine3A, size: [f32; 2], spacing: f32) -> f64 {
    let (u, v) = (Vec3::new(size[0], 0.0, 0.0), Vec3::new(0.0, size[1], 0.0));
    grid_count(m.transform_vector3(u), m.transform_vector3(v), spacing)
}

/// How many disks `sphere` makes.
pub fn sphere_count(m: &Affine3A, radius: f32, spacing: f32) -> f64 {
    let r = radius as f64 * max_scale(m) as f64;
    (4.0 * std::f64::consts::PI * r * r / (spacing as f64 * spacing as f64))
        .round()
        .max(12.0)
}

/// Largest stretch the linear part applies to any direction (bounds a disk radius' growth).
pub fn max_scale(m: &Affine3A) -> f32 {
    let c = m.matrix3;
    c.x_axis
        .length()
        .max(c.y_axis.length())
        .max(c.z_axis.length())
}

/// Inverse transpose of the linear part: transforms normals.
pub fn normal_matrix(m: &Affine3A) -> Mat3 {
    Mat3::from(m.matrix3).inverse().transpose()
}
