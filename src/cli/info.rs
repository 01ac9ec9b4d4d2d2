//! `lobelight info`: what a scene holds and what it will cost, with the grid built on the
//! device (or the CPU mirror) so its figures are real.

use std::sync::Arc;

use serde::Serialize;

use crate::error::Result;
use crate::renderer::{Engine, Renderer};
use crate::scene::{ObjectSummary, Scene};
use crate::types::{Lobe, Photon, Splat};

#[derive(Debug, Serialize)]
pub struct Info {
    pub scene: String,
    pub adapter: String,
    pub backend: String,
    pub splats: usize,
    pub lights: usize,
    pub materials: Vec<String>,
    pub glossy: bool,
    pub objects: Vec<ObjectSummary>,
    pub bounds: Bounds,
    pub search_radius: f32,
    pub grid: GridInfo,
    pub memory_bytes: Memory,
}

#[derive(Debug, Serialize)]
pub struct Bounds {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

#[derive(Debug, Serialize)]
pub struct GridInfo {
    pub dims: [u32; 3],
    pub cell_size: f32,
    pub cells: u32,
    pub entries: u32,
    pub occupied_cells: usize,
    pub max_cell_len: u32,
    pub mean_cells_per_splat: f64,
    pub build_ms: f64,
}

/// Device memory the bake and render will need, by buffer family.
#[derive(Debug, Serialize)]
pub struct Memory {
    pub splats: u64,
    pub grid: u64,
    /// One stored photon per emitted photon: a rough estimate (the thesis stored ~0.7 per
    /// emitted; longer paths store more).
    pub photons: u64,
    pub lobes: u64,
    pub total: u64,
}

/// Builds the grid on `engine`.
pub fn info(scene: &Arc<Scene>, engine: &Engine) -> Result<Info> {
    let renderer = Renderer::new(scene.clone(), engine)?;
    let grid = renderer.read_grid()?;
    let build_ms = renderer.grid_ms();
    // In the file's coordinates (a far scene was moved to the origin on load).
    let (lo, hi) = scene.bounds();
    let (lo, hi) = (lo + scene.origin, hi + scene.origin);
    let n = scene.splats.len() as u64;
    let entries = grid.cell_splats.len() as u64;
    let memory = {
        let splats = n * std::mem::size_of::<Splat>() as u64;
        // Offsets, plus the build's scratch (two u32 per entry) and final lists.
        let grid = (grid.params.cell_count as u64 + 1) * 4 * 2 + entries * 4 * 3;
        let photons = scene.bake.photons * std::mem::size_of::<Photon>() as u64;
        // Lobes for glossy splats alone (the fit keeps none for the others).
        let glossy = scene
            .splats
            .iter()
            .filter(|s| scene.materials[s.material as usize].is_glossy())
            .count() as u64;
        let lobes = glossy * scene.bake.lobes as u64 * std::mem::size_of::<Lobe>() as u64;
        Memory {
            splats,
            grid,
            photons,
            lobes,
            total: splats + grid + photons + lobes,
        }
    };
    Ok(Info {
        scene: scene.path.display().to_string(),
        adapter: match engine {
            Engine::Mirror => "cpu mirror".into(),
            Engine::Device(_) => engine.adapter(),
        },
        backend: engine.backend().into(),
        splats: scene.splats.len(),
        lights: scene.lights.len(),
        materials: scene.material_names.clone(),
        glossy: scene.has_glossy(),
        objects: scene.objects.clone(),
        bounds: Bounds {
            min: lo.into(),
            max: hi.into(),
        },
        search_radius: scene.search_radius(),
        grid: GridInfo {
            dims: grid.params.dims,
            cell_size: grid.params.cell_size,
            cells: grid.params.cell_count,
            entries: entries as u32,
            occupied_cells: grid.occupied_cells(),
            max_cell_len: grid.max_cell_len(),
            mean_cells_per_splat: entries as f64 / n.max(1) as f64,
            build_ms,
        },
        memory_bytes: memory,
    })
}

fn mib(b: u64) -> String {
    format!("{:.1} MiB", b as f64 / (1 << 20) as f64)
}

impl std::fmt::Display for Info {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "scene      {}", self.scene)?;
        writeln!(f, "device     {} ({})", self.adapter, self.backend)?;
        writeln!(f, "splats     {}", self.splats)?;
        for o in &self.objects {
            let src = o
                .source
                .as_deref()
                .map(|s| format!(" {s}"))
                .unwrap_or_default();
            let unused =
                (o.dropped).saturating_sub(o.dropped_by.iter().map(|r| r.count).sum::<usize>());
            let dropped = if unused > 0 {
                format!(" ({unused} unused vertices dropped)")
            } else {
                String::new()
            };
            let backs = match o.back_sides {
                0 => String::new(),
                n => format!(", {n} of them back sides (an open surface)"),
            };
            writeln!(f, "  {}{src}: {} splats{backs}{dropped}", o.shape, o.splats)?;
            for r in &o.dropped_by {
                writeln!(f, "    left out: {} {}", r.count, r.rule)?;
            }
            if let Some(first) = &o.first_skipped {
                let n = o.skipped;
                writeln!(
                    f,
                    "    skipped: {n} points that could not be read (the first: {first})"
                )?;
            }
        }
        writeln!(f, "lights     {}", self.lights)?;
        writeln!(
            f,
            "materials  {} (glossy: {})",
            self.materials.join(", "),
            if self.glossy { "yes" } else { "no" }
        )?;
        let (lo, hi) = (self.bounds.min, self.bounds.max);
        writeln!(
            f,
            "bounds     [{:.3}, {:.3}, {:.3}] .. [{:.3}, {:.3}, {:.3}]",
            lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
        )?;
        writeln!(f, "radius     {:.4} (photon search)", self.search_radius)?;
        let g = &self.grid;
        writeln!(
            f,
            "grid       {}x{}x{} cells of {:.4}, {} occupied, {} entries ({:.2} per splat, at most {} in a cell), built in {:.1} ms",
            g.dims[0],
            g.dims[1],
            g.dims[2],
            g.cell_size,
            g.occupied_cells,
            g.entries,
            g.mean_cells_per_splat,
            g.max_cell_len,
            g.build_ms
        )?;
        let m = &self.memory_bytes;
        write!(
            f,
            "memory     {} (splats {}, grid {}, photons {}, lobes {})",
            mib(m.total),
            mib(m.splats),
            mib(m.grid),
            mib(m.photons),
            mib(m.lobes)
        )
    }
}
