// Splat pass 0 of a frame of baked direct light, before splat_select (docs/design.md section
// 8): one level of the walk down the hierarchy of nodes over the level of detail's chunks
// (lod::LodTree::nodes), from the top. One invocation a node, which writes the levels its
// subtree may visit: none where its parent's subtree visits none (then its record is not
// read), else those chunk_visits finds in its bounds and its parent's allow. splat_select
// then reads the level above the chunks the same way, so that a subtree outside the view or
// drawn by coarser disks costs a word a record, not its tests. Twin: src/cpu/splat_nodes.rs.

// #import dispatch
// #import splat

@group(0) @binding(0) var<uniform> cam: Camera;
// This level's nodes.
@group(0) @binding(1) var<storage, read> nodes: array<SplatChunk>;
// The level above's visits (node j's parent is j / NODE_FANOUT); at the top, one word of all
// levels.
@group(0) @binding(2) var<storage, read> parent_visits: array<u32>;
@group(0) @binding(3) var<storage, read_write> node_visits: array<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let j = linear_workgroup(wg, num_wg) * WG + lid;
    if j >= arrayLength(&nodes) {
        return;
    }
    let up = parent_visits[j / NODE_FANOUT];
    var visits = 0u;
    if up != 0u {
        visits = chunk_visits(cam, nodes[j]) & up;
    }
    node_visits[j] = visits;
}
