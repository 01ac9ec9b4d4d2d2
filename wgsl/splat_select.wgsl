// Splat pass 0, the splats a frame of baked direct light draws (docs/design.md section 8), by
// the level of detail's tree: one invocation a chunk of splats near one another, which visits
// the levels of its splats that its node's walk (splat_nodes) and chunk_visits cannot rule out
// (none outside the view), so that the frame's work follows what it draws rather than the
// scene. For each splat it visits it writes the radius it is drawn with (drawn_radius; 0: not
// drawn) and the word of its merged normals at that level (LodSpread; 0 at its own); per
// chunk, its count of drawn splats and the levels it visited, for splat_list, which lists them
// for splat_shade and the raster passes. Entries not visited keep an earlier frame's radius:
// nothing reads them. One invocation, not a workgroup, a chunk: a chunk holds a few hundred
// visited entries at most, and llvmpipe spent 20 µs a workgroup on 10 M splats' 39 k chunks
// (their barriers).
// Twin: src/cpu/splat_select.rs.

// #import dispatch
// #import splat

@group(0) @binding(0) var<uniform> cam: Camera;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
// Per chunk, how many splats it draws (scanned into splat_list's offsets).
@group(0) @binding(2) var<storage, read_write> group_counts: array<u32>;
// The level of detail's merge tree (read only with it on; a stand-in before it is built).
// #paged
@group(0) @binding(3) var<storage, read> lods: array<SplatLod>;
// #paged
@group(0) @binding(4) var<storage, read_write> drawn: array<f32>;
@group(0) @binding(5) var<storage, read> chunks: array<SplatChunk>;
// The splats chunk by chunk (LodTree::order).
// #paged
@group(0) @binding(6) var<storage, read> order: array<u32>;
// Per chunk, the levels it visited (bit t: its splats whose top level is t).
@group(0) @binding(7) var<storage, read_write> visits: array<u32>;
// The merge tree's words of merged normals (LodSpread: LOD_MAX_LEVEL a splat), and per splat
// the word of the level it is drawn at (0 at its own), which splat_shade shades glossy disks
// by; stand-ins where the scene has nothing glossy (lod::merge_tree).
// #paged
@group(0) @binding(8) var<storage, read> lod_spreads: array<u32>;
// #paged
@group(0) @binding(9) var<storage, read_write> drawn_normals: array<u32>;
// The levels the node above each chunk visits (splat_nodes; chunk c's is c / NODE_FANOUT).
@group(0) @binding(10) var<storage, read> parent_visits: array<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let c = linear_workgroup(wg, num_wg) * WG + lid;
    if c >= arrayLength(&chunks) {
        return;
    }
    // A chunk whose node visits nothing is not read: its subtree was ruled out above.
    let up = parent_visits[c / NODE_FANOUT];
    if up == 0u {
        group_counts[c] = 0u;
        visits[c] = 0u;
        return;
    }
    let ch = chunks[c];
    let visited = chunk_visits(cam, ch) & up;
    // The merge tree's merged normals, or a stand-in (one splat's words) where the scene has
    // nothing glossy or the level of detail is off: then drawn_normals is not written (and may
    // be a stand-in too). A glossy scene of one splat merges nothing: its words are all 0.
    let normals = lod_spreads_len() > LOD_MAX_LEVEL;
    var count = 0u;
    var start = 0u;
    for (var t = 0u; t < LOD_LEVELS; t++) {
        let end = ch.ends[t];
        if (visited >> t & 1u) != 0u {
            for (var e = start; e < end; e++) {
                let i = order_at(ch.first + e);
                let s = splats_at(i);
                let lod = lods_at(i);
                let level = lod_level(cam, s, lod);
                let r = drawn_radius(cam, s, lod, level);
                count += select(0u, 1u, r > 0.0);
                drawn_put(i, r);
                if normals {
                    var word = 0u;
                    if level > 0u {
                        word = lod_spreads_at(LOD_MAX_LEVEL * i + level - 1u);
                    }
                    drawn_normals_put(i, word);
                }
            }
        }
        start = end;
    }
    group_counts[c] = count;
    visits[c] = visited;
}
