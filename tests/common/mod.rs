//! Helpers shared by the integration tests.
#![allow(dead_code)]

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
