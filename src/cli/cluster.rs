//! `lobelight bench cluster`: rays through a small dense cloud in a large room against rays
//! through the room with an ordinary block. Two generated scenes share the Cornell room, its
//! light and one glossy object in the same place, filling about 1 % of the room's volume: a
//! block of splats at the room's spacing (the default scene's kind), or a sphere of `N` splats
//! (a scanned object: 200 k by default, tens of them to a splat-grid cell). Both bake on one
//! engine; the figures are the photons' rate and final gathering's rays a second, and how many
//! times slower the cloud's are.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::bake::Progress;
use crate::direct::DIRECT_SAMPLES;
use crate::error::{Error, Result};
use crate::renderer::{Engine, Renderer};
use crate::scene::{self, Scene};

/// The dense cloud's default splat count.
pub const DEFAULT_CLUSTER: u64 = 200_000;

/// The object's half size: a cube of 0.43 holds 1 % of the room's 2³.
const HALF: f32 = 0.215;

#[derive(Debug, Serialize)]
pub struct ClusterBench {
    pub adapter: String,
    pub backend: String,
    /// The room with the block, then the room with the dense cloud.
    pub rows: Vec<ClusterRow>,
    /// How many times slower the cloud's photons and gathering rays run than the block's.
    pub photons_slowdown: f64,
    pub gather_slowdown: f64,
}

#[derive(Debug, Serialize)]
pub struct ClusterRow {
    pub scene: String,
    pub splats: usize,
    /// The object's splats, and the splats of the splat grid's fullest cell.
    pub object_splats: usize,
    pub max_cell_len: u32,
    pub photons_ms: f64,
    pub photons_per_s: f64,
    /// Final gathering: its rays, the direct bake's shadow rays it runs first (every splat's,
    /// `DIRECT_SAMPLES` a light), their time and their rate together.
    pub rays: u64,
    pub direct_rays: u64,
    pub final_gather_ms: f64,
    pub gather_rays_per_s: f64,
    pub em_ms: f64,
}

/// Writes both scenes to `dir` and bakes each on `engine`; `settings` applies the command
/// line's bake settings.
pub fn cluster(
    engine: &Engine,
    splats: u64,
    dir: &Path,
    settings: &dyn Fn(&mut Scene) -> Result<()>,
) -> Result<ClusterBench> {
    if splats == 0 {
        return Err(Error::Invalid(
            "bench cluster needs a cloud of at least one splat (--cluster-splats 200000)".into(),
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let block = write_scene(dir, "cluster_block.toml", BLOCK)?;
    let ply = write_sphere(dir, splats)?;
    let cloud = write_scene(dir, &format!("cluster_{splats}.toml"), &cloud_object(&ply))?;
    let rows = [block, cloud]
        .iter()
        .map(|path| {
            let mut scene = scene::load(path)?;
            settings(&mut scene)?;
            measure(engine, scene)
        })
        .collect::<Result<Vec<_>>>()?;
    let slowdown = |f: fn(&ClusterRow) -> f64| f(&rows[0]) / f(&rows[1]).max(1e-9);
    let adapter = engine.adapter_and_threads();
    let backend = engine.backend().to_string();
    Ok(ClusterBench {
        adapter,
        backend,
        photons_slowdown: slowdown(|r| r.photons_per_s),
        gather_slowdown: slowdown(|r| r.gather_rays_per_s),
        rows,
    })
}

fn measure(engine: &Engine, scene: Scene) -> Result<ClusterRow> {
    let quiet = Progress::new(false);
    let mut renderer = Renderer::new(std::sync::Arc::new(scene), engine)?;
    let max_cell_len = max_cell(&*renderer.read_grid()?);
    let baked = renderer.bake(&quiet)?;
    let scene = renderer.scene();
    let s = &renderer.lobes().stats;
    let direct_rays = scene.splats.len() as u64 * scene.lights.len() as u64 * DIRECT_SAMPLES as u64;
    let photons_ms = baked.photons.ms.unwrap_or(0.0);
    let emitted = scene.bake.photons as f64;
    let object_splats = scene.objects.last().map_or(0, |o| o.splats);
    Ok(ClusterRow {
        scene: scene.path.display().to_string(),
        splats: scene.splats.len(),
        object_splats,
        max_cell_len,
        photons_ms,
        photons_per_s: emitted / (photons_ms / 1e3).max(1e-9),
        rays: s.rays,
        direct_rays,
        final_gather_ms: s.final_gather_ms,
        gather_rays_per_s: (s.rays + direct_rays) as f64 / (s.final_gather_ms / 1e3).max(1e-9),
        em_ms: s.ms,
    })
}

/// The most splats one cell of the splat grid lists.
fn max_cell(grid: &crate::grid::SplatGrid) -> u32 {
    grid.cell_start
        .windows(2)
        .map(|w| w[1] - w[0])
        .max()
        .unwrap_or(0)
}

/// The room and its light (the default scene's), then the glossy material.
const ROOM: &str = r#"
[camera]
eye = [0.0, 0.0, 3.9]
target = [0.0, 0.0, 0.0]
fov = 39.3077
resolution = [256, 256]

[materials.white]
diffuse = [0.885809, 0.698859, 0.666422]

[materials.red]
diffuse = [0.570068, 0.0430135, 0.0443706]

[materials.green]
diffuse = [0.105421, 0.37798, 0.076425]

[materials.object]
diffuse = [0.45, 0.4, 0.35]
specular = 0.4
roughness = 0.1

[[light]]
type = "area"
center = [0.0, 0.99, 0.01]
size = [0.46, 0.38]
normal = [0.0, -1.0, 0.0]
u_axis = [1.0, 0.0, 0.0]
radiance = [18.387, 13.9873, 6.75357]

[[object]]
shape = "cornell_box"
material = "white"
left_material = "red"
right_material = "green"
spacing = 0.025
"#;

/// A glossy block of the room's spacing where the cloud stands.
const BLOCK: &str = r#"
[[object]]
shape = "box"
scale = 0.215
translate = [0.0, -0.5, 0.0]
spacing = 0.025
material = "object"
"#;

fn cloud_object(ply: &Path) -> String {
    let name = ply
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    format!("\n[[object]]\nshape = \"model\"\npath = \"{name}\"\nmaterial = \"object\"\n")
}

fn write_scene(dir: &Path, name: &str, object: &str) -> Result<PathBuf> {
    let path = dir.join(name);
    let text = format!(
        "# A generated scene of lobelight bench cluster: the Cornell room and one glossy \
         object filling about 1 % of it.\n{ROOM}{object}"
    );
    std::fs::write(&path, text).map_err(|e| Error::io(&path, e))?;
    Ok(path)
}

/// A sphere of `n` points (a Fibonacci lattice, even spacing) with outward normals, inscribed
/// in the block's cube, as a binary PLY.
fn write_sphere(dir: &Path, n: u64) -> Result<PathBuf> {
    let ply = dir.join(format!("cluster_{n}.ply"));
    let file = std::fs::File::create(&ply).map_err(|e| Error::io(&ply, e))?;
    let mut out = std::io::BufWriter::with_capacity(1 << 20, file);
    let io = |e| Error::io(&ply, e);
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\n\
         property float y\nproperty float z\nproperty float nx\nproperty float ny\n\
         property float nz\nend_header\n"
    );
    out.write_all(header.as_bytes()).map_err(io)?;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for i in 0..n {
        let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - y * y).sqrt();
        let a = golden * i as f64;
        let normal = [r * a.cos(), y, r * a.sin()].map(|v| v as f32);
        let p = [HALF * normal[0], -0.5 + HALF * normal[1], HALF * normal[2]];
        for v in p.iter().chain(&normal) {
            out.write_all(&v.to_le_bytes()).map_err(io)?;
        }
    }
    out.flush().map_err(io)?;
    Ok(ply)
}

impl std::fmt::Display for ClusterBench {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "device {} ({})", self.adapter, self.backend)?;
        writeln!(
            f,
            "{:<28} {:>8} {:>8} {:>9} {:>12} {:>12} {:>9}",
            "scene", "splats", "object", "max cell", "photons/s", "rays/s", "EM ms"
        )?;
        for r in &self.rows {
            let name = Path::new(&r.scene)
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            writeln!(
                f,
                "{:<28} {:>8} {:>8} {:>9} {:>12.0} {:>12.0} {:>9.0}",
                name,
                r.splats,
                r.object_splats,
                r.max_cell_len,
                r.photons_per_s,
                r.gather_rays_per_s,
                r.em_ms
            )?;
        }
        write!(
            f,
            "the dense cloud's photons {:.2}× and gathering rays {:.2}× slower than the block's",
            self.photons_slowdown, self.gather_slowdown
        )
    }
}
