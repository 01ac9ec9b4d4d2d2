//! lobelight: global illumination on splats with per-splat Gaussian lobes of incident light.
//!
//! Every stage runs as a WGSL compute or render pass (`gpu`), and has a CPU mirror (`cpu`) used
//! as the reference in tests. The modules, from the bottom up (each uses only those above it
//! in this list; docs/architecture.md):
//!
//! - `error`, `large_pages` (the command's allocator), `types` (the `#[repr(C)]` records
//!   shared with WGSL), `shared` (math shared by the mirrors and the host), `shaders` (the WGSL
//!   sources, the stage table and what naga reads of them);
//! - `grid`, `photons`, `bins`, `em`, `tone` (each stage's settings, limits and host-side
//!   data), `fit_groups` (the splats that share a lobe fit), `lobe_norms` (the lobe-norm table every frame's shading divides by, and its
//!   quadrature), `convolution` (the lobe × BRDF shading study), `lod` (the level of detail's
//!   merge tree);
//! - `scene` (the scene file, procedural shapes and model files) and `camera`;
//! - `sequence` (each multi-dispatch stage's dispatches, written once), run by `cpu` (the
//!   mirrors) and `gpu` (the device host); `frame` (what a frame draws); `objects` (which
//!   surface each pixel shows);
//! - `bake` (photons → bins → lobes on either), `cache` (a bake on disk) and `renderer` (the
//!   device's frame: bake, draw from a view, tone map, read back);
//! - `cli` (feature `app`): the `lobelight` commands.
//!
//! Baking a scene on the CPU mirror (the README's example, compiled by the doc tests):
//!
//! ```no_run
//! use lobelight::bake::{BakeDevice, Progress, bake};
//! use lobelight::{cpu, scene};
//!
//! let scene = scene::load(std::path::Path::new("scenes/cornell.toml"))?;
//! let grid = cpu::scene_grid(&scene)?;
//! let baked = bake(&scene, BakeDevice::Cpu(&grid), &Progress::new(false))?;
//! println!("{} splats lit", baked.em.splats_lit.unwrap_or(0));
//! # Ok::<(), lobelight::Error>(())
//! ```

pub mod bake;
pub mod bins;
pub mod cache;
pub mod camera;
pub mod convolution;
pub mod cpu;
pub mod direct;
pub mod em;
pub mod error;
pub mod fit_groups;
pub mod frame;
pub mod gpu;
pub mod grid;
pub mod large_pages;
pub mod lobe_norms;
pub mod lod;
pub mod objects;
pub mod photons;
pub mod plan;
pub mod renderer;
pub mod scene;
pub mod sequence;
pub mod shaders;
pub mod shared;
pub mod timing;
pub mod tone;
pub mod types;

#[cfg(feature = "app")]
pub mod cli;

pub use error::{Error, Result};
