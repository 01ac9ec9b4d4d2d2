// Dispatches larger than max_compute_workgroups_per_dimension are laid out in 2D by the host
// (`Gpu::dispatch_dims` in src/gpu/mod.rs); this turns the workgroup id back into one linear index.
fn linear_workgroup(wg: vec3<u32>, num_wg: vec3<u32>) -> u32 {
    return wg.x + wg.y * num_wg.x;
}
