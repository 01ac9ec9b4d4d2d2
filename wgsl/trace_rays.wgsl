// The nearest hit of each ray in a list: the tracer of wgsl/shared/trace.wgsl on its own, for
// tests of the traversal and for any stage that needs a batch of rays answered.
// One invocation per ray, with the same iteration budget a photon path gets.
// CPU mirror: src/cpu/trace_rays.rs.

// #import types
// #import dispatch
// #import trace

@group(0) @binding(0) var<uniform> params: TraceParams;
@group(0) @binding(1) var<storage, read> rays: array<Ray>;
@group(0) @binding(2) var<storage, read_write> hits: array<Hit>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= params.path_count {
        return;
    }
    let r = rays[i];
    var budget = params.iteration_budget;
    hits[i] = trace_ray(r.origin, r.direction, r.skip, r.t_max, &budget);
}
