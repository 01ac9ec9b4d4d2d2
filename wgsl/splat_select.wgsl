// Splat pass 0, the splats a frame of baked direct light draws (docs/design.md section 8):
// those facing the eye, inside the view and drawn at their level of detail (lod_radius). It
// writes the radius each splat is drawn with (0: not drawn) and each workgroup's count of them;
// splat_list then lists them in index order, for splat_shade and the raster passes, which draw
// that list alone. Twin: src/cpu/splat_select.rs.

// #import dispatch
// #import splat

@group(0) @binding(0) var<uniform> cam: Camera;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
// Per workgroup of WG splats, how many it draws (scanned into splat_list's offsets).
@group(0) @binding(2) var<storage, read_write> group_counts: array<u32>;
// The level of detail's merge tree (read only with it on; a stand-in before it is built).
// #paged
@group(0) @binding(3) var<storage, read> lods: array<SplatLod>;
// #paged
@group(0) @binding(4) var<storage, read_write> drawn: array<f32>;

const WG: u32 = 64u;

var<workgroup> group_count: atomic<u32>;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    if lid == 0u {
        atomicStore(&group_count, 0u);
    }
    workgroupBarrier();
    let group = linear_workgroup(wg, num_wg);
    let i = group * WG + lid;
    if i < splats_len() {
        var s = splats_at(i);
        if cam.lod > 0.0 {
            s.radius = lod_radius(cam, s, lods_at(i));
        }
        let shown = faces_camera(s, cam.eye) && s.radius > 0.0 && in_view(cam, s);
        if shown {
            atomicAdd(&group_count, 1u);
        }
        drawn_put(i, select(0.0, s.radius, shown));
    }
    workgroupBarrier();
    if lid == 0u && group * WG < splats_len() {
        group_counts[group] = atomicLoad(&group_count);
    }
}
