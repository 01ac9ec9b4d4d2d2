//! Twin of `wgsl/shared/dispatch.wgsl`: how many workgroups cover a count. The host lays
//! counts past the per-dimension limit out in 2D (`Gpu::dispatch_dims`); the shaders turn
//! the workgroup id back into one linear index.

/// Workgroups of `wg` invocations (or items) that cover `n`.
pub fn groups_for(n: u32, wg: u32) -> u32 {
    n.div_ceil(wg)
}
