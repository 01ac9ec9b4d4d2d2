// Splat pass 0, the splats a frame of baked direct light draws (docs/design.md section 8):
// those facing the eye, inside the view and drawn at their level of detail (lod_radius), listed
// for splat_shade, which then shades them and no others; and for the raster passes, the radius
// each splat is drawn with (0: not drawn). Culled in splat_shade itself, they
// cost as much as the rest: a SIMD group runs the shading while any of its lanes needs it. The
// list's order is the atomic counter's and may vary between runs; each splat's shading goes to
// its own slot, so the image does not. Twin: src/cpu/splat_select.rs.

// #import dispatch
// #import splat

@group(0) @binding(0) var<uniform> cam: Camera;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
// [0]: how many splats the list holds (cleared before the pass).
@group(0) @binding(2) var<storage, read_write> selected_count: array<atomic<u32>>;
// #paged
@group(0) @binding(3) var<storage, read_write> selected: array<u32>;
// The level of detail's merge tree (read only with it on; a stand-in before it is built).
// #paged
@group(0) @binding(4) var<storage, read> lods: array<SplatLod>;
// #paged
@group(0) @binding(5) var<storage, read_write> drawn: array<f32>;

const WG: u32 = 64u;
const NOT_LISTED: u32 = 0xffffffffu;

// A workgroup counts its splats first and takes its places in the list with one atomic add:
// an add per splat on the one counter cost the bunny's 512^2 frame about 2 ms on llvmpipe.
var<workgroup> group_count: atomic<u32>;
var<workgroup> group_first: u32;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    if lid == 0u {
        atomicStore(&group_count, 0u);
    }
    workgroupBarrier();
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    var slot = NOT_LISTED;
    if i < splats_len() {
        var s = splats_at(i);
        if cam.lod > 0.0 {
            s.radius = lod_radius(cam, s, lods_at(i));
        }
        if faces_camera(s, cam.eye) && s.radius > 0.0 && in_view(cam, s) {
            slot = atomicAdd(&group_count, 1u);
        }
        drawn_put(i, select(0.0, s.radius, slot != NOT_LISTED));
    }
    workgroupBarrier();
    if lid == 0u {
        group_first = atomicAdd(&selected_count[0], atomicLoad(&group_count));
    }
    workgroupBarrier();
    if slot != NOT_LISTED {
        selected_put(group_first + slot, i);
    }
}
