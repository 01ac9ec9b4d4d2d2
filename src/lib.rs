//! lobelight: global illumination on splats with per-splat Gaussian lobes of incident light.
//!
//! Every stage runs as a WGSL compute or render pass (`gpu`), and has a CPU mirror (`cpu`) used
//! as the reference in tests. See README.md for the command line and DESIGN notes for the math.

pub mod bake;
pub mod bench;
pub mod bins;
pub mod cache;
pub mod camera;
pub mod compare;
pub mod convolution;
pub mod cpu;
pub mod em;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod grid;
pub mod info;
pub mod lobe_norms;
pub mod model;
pub mod photons;
pub mod plot;
pub mod rebake;
pub mod render;
pub mod scene;
pub mod shared;
pub mod sweep;
pub mod tone;
pub mod types;
pub mod view;

pub use error::{Error, Result};
