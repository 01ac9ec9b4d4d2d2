//! Rust twins of the shared WGSL modules in `wgsl/shared/`: the same functions with the same
//! names and the same operations in the same order, used by the CPU mirrors of the stages.

pub mod bins;
pub mod deposits;
pub mod dispatch;
pub mod lights;
pub mod lobe_brdf;
pub mod lobes;
pub mod octahedral;
pub mod rng;
pub mod sampling;
pub mod splat;
pub mod tone;
pub mod trace;
pub mod ward;
