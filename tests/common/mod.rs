//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod scans;

use lobelight::gpu::{BackendChoice, Gpu};
use lobelight::types::Splat;

/// The test device. Tests that need a GPU fail (never skip) when there is none: CI installs
/// lavapipe, so a missing adapter is a broken setup, not a reason to pass.
pub fn gpu() -> Gpu {
    match Gpu::new(BackendChoice::Auto) {
        Ok(gpu) => {
            eprintln!("adapter: {} ({:?})", gpu.info.name, gpu.info.backend);
            gpu
        }
        Err(e) => panic!("this test needs a GPU adapter: {e}"),
    }
}

/// Whether `gpu` rounds f32 arithmetic as the mirror does, in every pipeline alike: a software
/// rasterizer (lavapipe, llvmpipe) compiles each multiply and add as written, so parity there is
/// bit for bit where the formulas are the same. A GPU's compiler may fuse multiply-adds, and
/// fuse them differently in two pipelines of the same formula (an H100's did): tests that
/// assert equality there assert a named tolerance on other devices.
pub fn rounds_like_the_mirror(gpu: &Gpu) -> bool {
    gpu.is_software()
}

/// Small deterministic generator for test data (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    pub fn unit_vector(&mut self) -> [f32; 3] {
        loop {
            let v = [
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            ];
            let l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if l2 > 1e-4 && l2 <= 1.0 {
                let l = l2.sqrt();
                return [v[0] / l, v[1] / l, v[2] / l];
            }
        }
    }
}

/// `n` random disks in the cube [-1, 1]³ with radii in [rmin, rmax].
pub fn random_splats(n: usize, rmin: f32, rmax: f32, seed: u64) -> Vec<Splat> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| Splat {
            center: [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ],
            radius: rng.range(rmin, rmax),
            normal: rng.unit_vector(),
            material: 0,
            diffuse: [0.5; 3],
            object: 0,
        })
        .collect()
}

/// The scene's splat grid built by the CPU mirror.
pub fn host_grid(scene: &lobelight::scene::Scene) -> lobelight::grid::SplatGrid {
    lobelight::cpu::scene_grid(scene).unwrap()
}

/// The cube [−0.3, 0.3]³ at spacing 0.025 (its faces' disks reach 6 mm past its edges), lit by
/// a point light at `light` of power `power`, after the scene file's lines `head` (a camera).
pub fn lit_box(head: &str, light: [f32; 3], power: f32) -> lobelight::scene::Scene {
    let toml = format!(
        "{head}\n[[light]]\ntype = \"point\"\nposition = {light:?}\npower = {power:?}\n\
         [[object]]\nshape = \"box\"\nscale = 0.3\nspacing = 0.025\n"
    );
    lobelight::scene::parse(std::path::Path::new("box.toml"), &toml).unwrap()
}

/// The unit sphere's Fibonacci lattice of `n` points.
pub fn fibonacci_sphere(n: u32) -> Vec<glam::Vec3> {
    (0..n)
        .map(|k| {
            let z = 1.0 - (2 * k + 1) as f32 / n as f32;
            let (r, phi) = ((1.0 - z * z).sqrt(), k as f32 * 2.399_963);
            glam::Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// A LAS file written by the `las` crate: `points` at 1 mm resolution, 16-bit colours where
/// `colours`, LAZ-compressed where `laz`.
pub fn write_las(
    points: &[glam::Vec3],
    colours: Option<&dyn Fn(usize) -> [u16; 3]>,
    laz: bool,
) -> Vec<u8> {
    let mut builder = las::Builder::from((1, 2));
    let mut format = las::point::Format::new(if colours.is_some() { 2 } else { 0 }).unwrap();
    format.is_compressed = laz;
    builder.point_format = format;
    let t = las::Transform {
        scale: 0.001,
        offset: 0.0,
    };
    builder.transforms = las::Vector { x: t, y: t, z: t };
    let header = builder.into_header().unwrap();
    let mut writer = las::Writer::new(std::io::Cursor::new(Vec::new()), header).unwrap();
    for (k, p) in points.iter().enumerate() {
        writer
            .write_point(las::Point {
                x: p.x as f64,
                y: p.y as f64,
                z: p.z as f64,
                color: colours.map(|c| {
                    let [r, g, b] = c(k);
                    las::Color::new(r, g, b)
                }),
                ..Default::default()
            })
            .unwrap();
    }
    writer.into_inner().unwrap().into_inner()
}

/// A Gaussian-splat PLY as 3D Gaussian Splatting writes it (binary little endian floats: x y z,
/// nx ny nz, f_dc_0..2, 45 f_rest, opacity, scale_0..2, rot_0..3), or as 2D Gaussian Splatting
/// writes its surfels (two scales). One Gaussian per point: flat along the sphere's normal,
/// in-plane scale 0.05, half of them turned upside down (a Gaussian's normal has no sign),
/// every fifth one faint (opacity logit −3), coloured `colour(k)`.
pub fn gaussian_ply(
    pts: &[glam::Vec3],
    two_d: bool,
    colour: &dyn Fn(usize) -> [f32; 3],
) -> Vec<u8> {
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n",
        pts.len()
    );
    let mut names: Vec<String> = [
        "x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2",
    ]
    .map(String::from)
    .to_vec();
    names.extend((0..45).map(|k| format!("f_rest_{k}")));
    names.push("opacity".into());
    names.extend((0..if two_d { 2 } else { 3 }).map(|k| format!("scale_{k}")));
    names.extend((0..4).map(|k| format!("rot_{k}")));
    for n in &names {
        header += &format!("property float {n}\n");
    }
    header += "end_header\n";
    let mut bytes = header.into_bytes();
    for (k, p) in pts.iter().enumerate() {
        let up = if k % 2 == 0 { *p } else { -*p };
        let q = glam::Quat::from_rotation_arc(glam::Vec3::Z, up);
        let dc = colour(k).map(|c| (c - 0.5) / 0.282_094_8);
        let mut v = vec![p.x, p.y, p.z, 0.0, 0.0, 0.0, dc[0], dc[1], dc[2]];
        v.extend([0.0; 45]);
        v.push(if k % 5 == 4 { -3.0 } else { 3.0 });
        v.extend([0.05f32.ln(), 0.05f32.ln()]);
        if !two_d {
            v.push(0.001f32.ln());
        }
        v.extend([q.w, q.x, q.y, q.z]);
        for x in v {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
    bytes
}

/// An E57 file written by the `e57` crate: one scan per entry of `scans` (its points in the
/// scan's own frame, and the pose's translation that moves them into the file's frame), with
/// 8-bit colours `colour(k)` and every point after the last marked invalid where `invalid`.
pub fn write_e57(
    scans: &[(Vec<glam::Vec3>, [f64; 3])],
    colour: &dyn Fn(usize) -> [u8; 3],
) -> Vec<u8> {
    use e57::{Record, RecordValue};
    let path = std::env::temp_dir().join(format!(
        "lobelight-e57-{}-{:?}.e57",
        std::process::id(),
        std::thread::current().id()
    ));
    {
        let mut writer = e57::E57Writer::from_file(&path, "file-guid").unwrap();
        for (s, (points, t)) in scans.iter().enumerate() {
            let prototype = vec![
                Record::CARTESIAN_X_F32,
                Record::CARTESIAN_Y_F32,
                Record::CARTESIAN_Z_F32,
                Record::CARTESIAN_INVALID_STATE,
                Record::COLOR_RED_U8,
                Record::COLOR_GREEN_U8,
                Record::COLOR_BLUE_U8,
            ];
            let mut pc = writer
                .add_pointcloud(&format!("scan-{s}"), prototype)
                .unwrap();
            pc.set_transform(Some(e57::Transform {
                rotation: e57::Quaternion {
                    w: 1.0,
                    x: 0.0,
                    y: 0.0,
                    z: 0.0,
                },
                translation: e57::Translation {
                    x: t[0],
                    y: t[1],
                    z: t[2],
                },
            }));
            for (k, p) in points.iter().enumerate() {
                let [r, g, b] = colour(k);
                pc.add_point(vec![
                    RecordValue::Single(p.x),
                    RecordValue::Single(p.y),
                    RecordValue::Single(p.z),
                    RecordValue::Integer(0),
                    RecordValue::Integer(r as i64),
                    RecordValue::Integer(g as i64),
                    RecordValue::Integer(b as i64),
                ])
                .unwrap();
            }
            // One return that did not come back.
            pc.add_point(vec![
                RecordValue::Single(0.0),
                RecordValue::Single(0.0),
                RecordValue::Single(0.0),
                RecordValue::Integer(2),
                RecordValue::Integer(0),
                RecordValue::Integer(0),
                RecordValue::Integer(0),
            ])
            .unwrap();
            pc.finalize().unwrap();
        }
        writer.finalize().unwrap();
    }
    let bytes = std::fs::read(&path).unwrap();
    std::fs::remove_file(&path).ok();
    bytes
}

/// How far apart two lists of floats are, relatively (1e-6 near zero): the share of elements
/// within 1e-6, 1e-5, 1e-4 and 1e-3 and the largest difference, as one line for a failure's
/// message or a test's log.
pub fn apart(a: &[f32], b: &[f32]) -> String {
    let rel: Vec<f32> = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / y.abs().max(1e-6))
        .collect();
    let n = rel.len().max(1) as f64;
    let share = |t: f32| rel.iter().filter(|&&r| r <= t).count() as f64 / n;
    let worst = rel.iter().copied().fold(0.0f32, f32::max);
    format!(
        "{} values: within 1e-6 {:.4}, 1e-5 {:.4}, 1e-4 {:.4}, 1e-3 {:.4}; largest {worst:.3e}",
        rel.len(),
        share(1e-6),
        share(1e-5),
        share(1e-4),
        share(1e-3)
    )
}

/// The test device as an engine (`common::gpu`).
pub fn device() -> lobelight::renderer::Engine {
    lobelight::renderer::Engine::Device(std::sync::Arc::new(gpu()))
}

/// `scene`'s photons traced by the mirror (sorted by key) and the grid they were traced
/// through.
pub fn mirror_photons(
    scene: &lobelight::scene::Scene,
    cfg: &lobelight::photons::PhotonConfig,
) -> (lobelight::photons::PhotonMap, lobelight::grid::SplatGrid) {
    use lobelight::renderer::{Engine, Renderer};
    let renderer = Renderer::new(std::sync::Arc::new(scene.clone()), &Engine::Mirror).unwrap();
    let map = renderer.trace_photons(cfg, &mut |_, _| {}).unwrap().map;
    (map, renderer.read_grid().unwrap().into_owned())
}
