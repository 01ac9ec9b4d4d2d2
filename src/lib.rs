//! lobelight: global illumination on splats with per-splat Gaussian lobes of incident light.
//!
//! Every stage runs as a WGSL compute or render pass (`gpu`), and has a CPU mirror (`cpu`) used
//! as the reference in tests and as an engine of its own where there is no GPU driver. The
//! modules, from the bottom up (each uses only those before it; `tests/layering.rs` holds the
//! order, docs/architecture.md §2 explains it):
//!
//! - `error`, `large_pages` (the command's allocator), `timing`, `budget` (the memory budget),
//!   `types` (the `#[repr(C)]` records shared with WGSL), `grid` (the splat grid's cells),
//!   `shared` (math shared by the mirrors and the host), `shaders` (the WGSL sources, the stage
//!   table and what naga reads);
//! - `photons`, `em`, `bins`, `tone`, `lobe_norms`, `convolution`, `fit_groups`, `lod`: each
//!   stage's settings, limits and host-side data;
//! - `scene` (the scene file, procedural shapes and model files) and `camera`;
//! - `sequence` (each multi-dispatch stage's dispatches, written once), `direct`, `frame` (what a
//!   frame draws), `objects` (which surface each pixel shows), `plan` (the bake's plan), `host` (the
//!   bake's passes from host data to host data, on any executor), then the two engines: `cpu`
//!   (the mirrors) and `gpu` (the device host);
//! - `bake` (photons → bins → lobes on either engine), `cache` (a bake on disk) and `renderer`
//!   (one renderer over either engine, chosen once);
//! - `cli` (feature `app`): the `lobelight` commands.
//!
//! Rendering the default scene on whichever engine this machine has (the README's example,
//! compiled by the doc tests):
//!
//! ```no_run
//! use std::{path::Path, sync::Arc};
//! use lobelight::bake::Progress;
//! use lobelight::{camera::View, frame::FrameConfig};
//! use lobelight::renderer::{BackendChoice, Engine, EngineChoice, Renderer};
//!
//! let scene = Arc::new(lobelight::scene::load(Path::new("scenes/cornell.toml"))?);
//! let (engine, _) = Engine::open(EngineChoice::Auto, BackendChoice::Auto)?;
//! let mut renderer = Renderer::new(scene.clone(), &engine)?;
//! renderer.bake(&Progress::new(false))?;
//! renderer.draw(&View::new(&scene.camera, 512, 512), &FrameConfig::default(), 16, |_| {})?;
//! let hdr: Vec<[f32; 4]> = renderer.read_hdr()?;
//! # Ok::<(), lobelight::Error>(())
//! ```

pub mod bake;
pub mod bins;
pub mod budget;
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
pub mod host;
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
#[cfg(feature = "video")]
pub mod video;

#[cfg(feature = "app")]
pub mod cli;

pub use error::{Error, Result};
