// Splat pass 0b, the list of the splats a frame of baked direct light draws, in index order
// (docs/design.md section 8): each workgroup writes its drawn splats (drawn radius above 0, as
// splat_select found) from its offset in the scanned counts, in order, so that the raster
// passes, which draw this list alone, blend in the same order in every run. The last workgroup
// writes the list's length and the raster passes' indirect draw. Twin: src/cpu/splat_list.rs.

// #import dispatch
// #import splat

// splat_select's counts per workgroup, exclusive-scanned: where each workgroup's entries start.
@group(0) @binding(0) var<storage, read> offsets: array<u32>;
// #paged
@group(0) @binding(1) var<storage, read> drawn: array<f32>;
// [0]: how many splats the list holds.
@group(0) @binding(2) var<storage, read_write> selected_count: array<u32>;
// #paged
@group(0) @binding(3) var<storage, read_write> selected: array<u32>;
// The raster passes' draw: vertices an instance, instances, first vertex, first instance.
@group(0) @binding(4) var<storage, read_write> draw_args: array<u32>;

const WG: u32 = 64u;

var<workgroup> shown: array<u32, 64>;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let group = linear_workgroup(wg, num_wg);
    let n = drawn_len();
    let i = group * WG + lid;
    shown[lid] = select(0u, 1u, i < n && drawn_at(i) > 0.0);
    workgroupBarrier();
    if group * WG >= n {
        return;
    }
    var rank = 0u;
    for (var k = 0u; k < lid; k++) {
        rank += shown[k];
    }
    if shown[lid] != 0u {
        selected_put(offsets[group] + rank, i);
    }
    if lid == WG - 1u && (group + 1u) * WG >= n {
        let count = offsets[group] + rank + shown[lid];
        selected_count[0] = count;
        draw_args[0] = SPLAT_CORNERS * SPLATS_PER_INSTANCE;
        draw_args[1] = (count + SPLATS_PER_INSTANCE - 1u) / SPLATS_PER_INSTANCE;
        draw_args[2] = 0u;
        draw_args[3] = 0u;
    }
}
