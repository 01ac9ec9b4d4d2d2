// Splat pass 2b, per-splat shading of frames with baked direct light (docs/design.md section 8):
// one invocation per splat splat_list listed, the radiance it sends towards the eye from its
// centre, by its lobes and irradiance (indirect) and its baked direct light; the attribute
// pass then blends that value over the splat's pixels. Shading every fragment with its own
// view ray took 86 of the attribute pass's 127 ms on the bunny at 512^2; once per splat it
// takes 11 ms. The view direction varies across a disk by its angular size alone.
// Splats not listed (turned away, outside the view, left out by the level of detail) are not
// drawn: their slots keep what they held. A glossy splat drawn as a merged disk is shaded with
// the mean of the normals the disk stands for and its lobe widened by their spread (lod_normal,
// lod_roughness): one normal's sharp highlight over a disk of several splats' surface mottled
// curved models.
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
// splat_select's word of each drawn splat's merged normals (LodSpread; 0 at its own level); a
// stand-in where the scene has nothing glossy.
// #paged
@group(0) @binding(13) var<storage, read> drawn_normals: array<u32>;
// The environment light's map (lights.wgsl), after the stage's own bindings.
@group(0) @binding(14) var<storage, read> sky: array<vec4<f32>>;

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
    var s_shaded = s;
    // Only where drawn with the level of detail, and only glossy splats: a scene with nothing
    // glossy binds a stand-in (lod::merge_tree), and frames without it leave the words as an
    // earlier frame wrote them.
    if cam.lod > 0.0 && glossy_lobe(m) {
        let word = drawn_normals_at(i);
        if word != 0u {
            m.roughness = lod_roughness(m.roughness, word);
            s_shaded.normal = lod_normal(word, s.normal);
        }
    }
    let l = indirect(i, s_shaded, m, wo) + baked_direct(i, s_shaded, m, s.center, wo);
    shaded_put(i, vec4<f32>(l, 0.0));
}
