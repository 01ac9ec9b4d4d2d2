//! CPU mirrors of the WGSL stages: one file per `wgsl/<stage>.wgsl`, with the same name, the
//! same bindings as arguments in binding order, and the same loop shape (workgroups, then
//! local invocations), so that a difference between the two points at one line.
//! They are the reference for the parity tests and a fallback when no GPU is wanted; `host`
//! runs their sequences as the device's host does (the CPU bake).

pub mod bin_count;
pub mod bin_place;
pub mod bin_rank;
pub mod bin_scatter;
pub mod direct_bake;
pub mod em_coverage;
pub mod em_deposit;
pub mod em_deposit_list;
pub mod em_fit;
pub mod em_gather;
pub mod em_select;
pub mod em_share;
pub mod exec;
pub mod final_gather;
pub mod frames;
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
pub mod splat_select;
pub mod splat_shade;
pub mod splat_shading;
pub mod splat_tiles;
pub mod splat_visibility;
pub mod tonemap_apply;
pub mod tonemap_reduce;
pub mod trace_rays;

pub use crate::shared::dispatch::groups_for;
pub use exec::{CpuBuffer, CpuExecutor};
pub use host::*;
