//! CPU mirrors of the WGSL stages: one file per `wgsl/<stage>.wgsl`, with the same name, the
//! same bindings as arguments in binding order, and the same loop shape (workgroups, then
//! local invocations), so that a difference between the two points at one line.
//! They are the reference for the parity tests and a fallback when no GPU is wanted; `host`
//! runs their sequences as the device's host does (the CPU bake).

pub mod bindings;
pub mod exec;
pub mod frames;
pub mod host;
pub mod splat_shading;

/// Declares the mirror modules, one a line, and `MIRRORS`, their rows.
macro_rules! mirrors {
    ($($module:ident,)*) => {
        $(pub mod $module;)*

        /// Each mirror module's `ROWS`: the stages it mirrors, with their workgroup shapes and
        /// how the executor runs them, written in the mirror's own file.
        pub const MIRRORS: &[&[MirrorRow]] = &[$($module::ROWS,)*];
    };
}

// The mirror modules: a new stage's mirror adds its line here.
mirrors! {
    bin_count,
    bin_place,
    bin_rank,
    bin_scatter,
    direct_bake,
    estimate_coverage,
    deposit_add,
    deposit_list,
    em_fit,
    estimate_gather,
    fit_select,
    deposit_share,
    estimate_smooth,
    final_gather,
    grid_cone,
    grid_count,
    grid_distance,
    grid_rank,
    grid_scatter,
    path_trace,
    photon_resolve,
    photon_trace,
    photon_view,
    present,
    reference_gather,
    scan_apply,
    scan_reduce,
    shade,
    splat_attributes,
    splat_list,
    splat_nodes,
    splat_select,
    splat_shade,
    splat_tiles,
    splat_visibility,
    temporal,
    tonemap_apply,
    tonemap_reduce,
    trace_rays,
}

pub use crate::shared::dispatch::groups_for;
pub use bindings::CpuBuffer;
pub use exec::CpuExecutor;
pub use host::*;

use crate::error::Result;
use crate::shaders::{Pass, Stage};
use crate::shared::trace::Geometry;
use bindings::Bindings;

/// How the executor runs a stage's mirror: over the dispatch's bindings, or over them and the
/// scene's geometry (a tracing stage's bind group 1, which `tests/shaders.rs` checks against
/// the WGSL's).
#[derive(Clone, Copy)]
pub enum Mirror {
    Plain(fn(&Bindings, u32) -> Result<()>),
    Traced(fn(&Bindings, &Geometry, u32) -> Result<()>),
}

/// One stage as its mirror's file states it: the workgroup size and values per invocation its
/// loops take (`None`: none fixed, as the WGSL's pipeline constant or raster pass;
/// `tests/shaders.rs` checks them against the WGSL's), and how the executor runs it (`None`:
/// its host calls it directly, as `frames` calls the splat passes).
#[derive(Clone, Copy)]
pub struct MirrorRow {
    pub stage: Stage,
    /// The compute entry point it mirrors (`shaders::Pass`): `main`, or another pass of the
    /// stage, each a row of its own.
    pub entry: &'static str,
    pub workgroup_size: Option<u32>,
    pub items: u32,
    pub run: Option<Mirror>,
}

/// Every mirror row, in the table's order.
pub fn mirror_rows() -> impl Iterator<Item = &'static MirrorRow> {
    MIRRORS.iter().flat_map(|rows| rows.iter())
}

/// The mirror the executor runs for `pass`, where it runs one.
pub fn mirror(pass: Pass) -> Option<Mirror> {
    mirror_rows()
        .find(|r| r.stage == pass.stage && r.entry == pass.entry)
        .and_then(|r| r.run)
}
