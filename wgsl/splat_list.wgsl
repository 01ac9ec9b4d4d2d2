// Splat pass 0b, the list of the splats a frame of baked direct light draws (docs/design.md
// section 8): one invocation a chunk, which writes the drawn splats (drawn radius above 0, as
// splat_select found) among the entries of the levels splat_select visited, from the chunk's
// offset in the scanned counts and in the chunk's order, so that the raster passes, which draw
// this list alone, blend in the same order in every run, and splat_shade's dispatch, sized by
// the list rather than the scene (empty workgroups cost llvmpipe 1 s a frame at 10 M splats).
// A chunk's few hundred entries at most are walked in order by one invocation: no barrier, no
// prefix over flags (a workgroup a chunk with a barrier a round took 2.3x this on llvmpipe). A
// chunk that visits nothing (its node's walk ruled it out) is not read. The last chunk writes
// the list's length and the raster passes' indirect draw. Twin: src/cpu/splat_list.rs.

// #import dispatch
// #import splat

// splat_select's counts per chunk, exclusive-scanned: where each chunk's entries start.
@group(0) @binding(0) var<storage, read> offsets: array<u32>;
// #paged
@group(0) @binding(1) var<storage, read> drawn: array<f32>;
// [0]: how many splats the list holds.
@group(0) @binding(2) var<storage, read_write> selected_count: array<u32>;
// #paged
@group(0) @binding(3) var<storage, read_write> selected: array<u32>;
// The raster passes' draw: vertices an instance, instances, first vertex, first instance;
// then splat_shade's dispatch: workgroups in x, y and z, one invocation a listed splat.
@group(0) @binding(4) var<storage, read_write> draw_args: array<u32>;
@group(0) @binding(5) var<storage, read> chunks: array<SplatChunk>;
// #paged
@group(0) @binding(6) var<storage, read> order: array<u32>;
// Per chunk, the levels splat_select visited.
@group(0) @binding(7) var<storage, read> visits: array<u32>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let c = linear_workgroup(wg, num_wg) * WG + lid;
    let n = arrayLength(&chunks);
    if c >= n {
        return;
    }
    let visited = visits[c];
    var at = offsets[c];
    // A chunk that visits nothing lists nothing: its record is not read.
    if visited != 0u {
        let ch = chunks[c];
        var start = 0u;
        for (var t = 0u; t < LOD_LEVELS; t++) {
            let end = ch.ends[t];
            if (visited >> t & 1u) != 0u {
                for (var e = start; e < end; e++) {
                    let i = order_at(ch.first + e);
                    if drawn_at(i) > 0.0 {
                        selected_put(at, i);
                        at += 1u;
                    }
                }
            }
            start = end;
        }
    }
    if c == n - 1u {
        selected_count[0] = at;
        draw_args[0] = SPLAT_CORNERS * SPLATS_PER_INSTANCE;
        draw_args[1] = (at + SPLATS_PER_INSTANCE - 1u) / SPLATS_PER_INSTANCE;
        draw_args[2] = 0u;
        draw_args[3] = 0u;
        // Within the per-dimension limit every device has (linear_workgroup undoes it).
        let groups = (at + WG - 1u) / WG;
        let x = max(min(groups, 65535u), 1u);
        draw_args[4] = select(x, 0u, groups == 0u);
        draw_args[5] = (groups + x - 1u) / x;
        draw_args[6] = 1u;
    }
}
