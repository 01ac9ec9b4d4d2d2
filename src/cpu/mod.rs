//! CPU mirrors of the WGSL stages: one file per `wgsl/<stage>.wgsl`, with the same name, the
//! same bindings as arguments in binding order, and the same loop shape (workgroups, then
//! local invocations), so that a difference between the two points at one line.
//! They are the reference for the parity tests and a fallback when no GPU is wanted; `host`
//! runs their sequences as the device's host does (the CPU bake).

pub mod bin_count;
pub mod bin_place;
pub mod bin_rank;
pub mod bin_scatter;
pub mod bindings;
pub mod direct_bake;
pub mod em_coverage;
pub mod em_deposit;
pub mod em_deposit_list;
pub mod em_fit;
pub mod em_gather;
pub mod em_select;
pub mod em_share;
pub mod em_smooth;
pub mod exec;
pub mod final_gather;
pub mod frames;
pub mod grid_cone;
pub mod grid_count;
pub mod grid_distance;
pub mod grid_rank;
pub mod grid_scatter;
pub mod host;
pub mod path_trace;
pub mod photon_resolve;
pub mod photon_trace;
pub mod photon_view;
pub mod present;
pub mod reference_gather;
pub mod scan_apply;
pub mod scan_reduce;
pub mod shade;
pub mod splat_attributes;
pub mod splat_list;
pub mod splat_nodes;
pub mod splat_select;
pub mod splat_shade;
pub mod splat_shading;
pub mod splat_tiles;
pub mod splat_visibility;
pub mod temporal;
pub mod tonemap_apply;
pub mod tonemap_reduce;
pub mod trace_rays;

pub use crate::shared::dispatch::groups_for;
pub use bindings::CpuBuffer;
pub use exec::CpuExecutor;
pub use host::*;

use crate::error::Result;
use crate::shaders::Stage;
use crate::shared::trace::Geometry;
use bindings::Bindings;

/// How the executor runs a stage's mirror: over the dispatch's bindings, or over them and the
/// scene's geometry (a tracing stage's bind group 1).
#[derive(Clone, Copy)]
pub enum Mirror {
    Plain(fn(&Bindings, u32) -> Result<()>),
    Traced(fn(&Bindings, &Geometry, u32) -> Result<()>),
}

/// The mirror the executor runs for each stage it dispatches, one row a stage: each mirror's
/// `dispatch` unpacks its own bindings beside its code. The match names every stage, so that a
/// new one does not compile without its row; the stages whose row is `None` (the splat passes,
/// `shade`, `present`, `reference_gather`, `trace_rays`) are called by their hosts directly
/// (`frames`, the tests).
pub fn mirror(stage: Stage) -> Option<Mirror> {
    Some(match stage {
        Stage::BinCount => Mirror::Plain(bin_count::dispatch),
        Stage::BinPlace => Mirror::Plain(bin_place::dispatch),
        Stage::BinRank => Mirror::Plain(bin_rank::dispatch),
        Stage::BinScatter => Mirror::Plain(bin_scatter::dispatch),
        Stage::DirectBake => Mirror::Traced(direct_bake::dispatch),
        Stage::EmCoverage => Mirror::Traced(em_coverage::dispatch),
        Stage::EmDeposit => Mirror::Plain(em_deposit::dispatch),
        Stage::EmDepositList => Mirror::Plain(em_deposit_list::dispatch),
        Stage::EmFit => Mirror::Plain(em_fit::dispatch),
        Stage::EmGather => Mirror::Plain(em_gather::dispatch),
        Stage::EmSelect => Mirror::Plain(em_select::dispatch),
        Stage::EmShare => Mirror::Plain(em_share::dispatch),
        Stage::EmSmooth => Mirror::Plain(em_smooth::dispatch),
        Stage::FinalGather => Mirror::Traced(final_gather::dispatch),
        Stage::GridCount => Mirror::Plain(grid_count::dispatch),
        Stage::GridDistance => Mirror::Plain(grid_distance::dispatch),
        Stage::GridCone => Mirror::Plain(grid_cone::dispatch),
        Stage::GridRank => Mirror::Plain(grid_rank::dispatch),
        Stage::GridScatter => Mirror::Plain(grid_scatter::dispatch),
        Stage::PathTrace => Mirror::Traced(path_trace::dispatch),
        Stage::PhotonResolve => Mirror::Plain(photon_resolve::dispatch),
        Stage::PhotonTrace => Mirror::Traced(photon_trace::dispatch),
        Stage::PhotonView => Mirror::Traced(photon_view::dispatch),
        Stage::ScanApply => Mirror::Plain(scan_apply::dispatch),
        Stage::ScanReduce => Mirror::Plain(scan_reduce::dispatch),
        Stage::SplatTileCount => Mirror::Plain(splat_tiles::dispatch_tile_count),
        Stage::SplatTileScatter => Mirror::Plain(splat_tiles::dispatch_tile_scatter),
        Stage::Temporal => Mirror::Plain(temporal::dispatch),
        Stage::TonemapApply => Mirror::Plain(tonemap_apply::dispatch),
        Stage::TonemapReduce => Mirror::Plain(tonemap_reduce::dispatch),
        Stage::TraceRays
        | Stage::SplatVisibility
        | Stage::SplatNodes
        | Stage::SplatSelect
        | Stage::SplatList
        | Stage::SplatShade
        | Stage::SplatAttributes
        | Stage::SplatCompute
        | Stage::Shade
        | Stage::ReferenceGather
        | Stage::Present => return None,
    })
}
