// Splat pass 2b, per-splat shading of frames with baked direct light (docs/design.md section 8):
// one invocation per splat splat_list listed, the radiance it sends towards the eye from its
// centre, by its lobes and irradiance (indirect) and its baked direct light; the attribute
// pass then blends that value over the splat's pixels. Shading every fragment with its own
// view ray took 86 of the attribute pass's 127 ms on the bunny at 512^2; once per splat it
// takes 11 ms. The view direction varies across a disk by its angular size alone.
// Splats not listed (turned away, outside the view, left out by the level of detail) are not
// drawn: their slots keep what they held. A glossy splat drawn as a merged disk is shaded with
// its lobe widened by the spread of the normals the disk stands for (lod_roughness): one
// normal's sharp highlight over a disk of several splats' surface mottled curved models.
// Twin: src/cpu/splat_shade.rs.

// #import dispatch
// #import splat
// #import splat_shading

@group(0) @binding(0) var<uniform> cam: Camera;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
// #paged
@group(0) @binding(10) var<storage, read_write> shaded: array<vec4<f32>>;
// splat_select's list: its length ([0]) and the splats' indices.
@group(0) @binding(11) var<storage, read> selected_count: array<u32>;
// #paged
@group(0) @binding(12) var<storage, read> selected: array<u32>;
// The level of detail's merge tree and its normals' spread (read only with it on; stand-ins
// before it is built).
// #paged
@group(0) @binding(13) var<storage, read> lods: array<SplatLod>;
// #paged
@group(0) @binding(14) var<storage, read> lod_spreads: array<vec2<u32>>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let j = linear_workgroup(wg, num_wg) * WG + lid;
    if j >= selected_count[0] {
        return;
    }
    let i = selected_at(j);
    let s = splats_at(i);
    let wo = normalize(cam.eye - s.center);
    var m = materials[s.material];
    if cam.lod > 0.0 && m.roughness >= MIN_ALPHA {
        let level = lod_level(cam, s, lods_at(i));
        m.roughness = lod_roughness(m.roughness, lod_spreads_at(i), level);
    }
    shaded_put(i, vec4<f32>(indirect(i, s, m, wo) + baked_direct(i, s, m, s.center, wo), 0.0));
}
