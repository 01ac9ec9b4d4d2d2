// Splat pass 2a, per-splat shading of frames with baked direct light (docs/design.md section 8):
// one invocation per splat, the radiance it sends towards the eye from its centre, by its
// lobes and irradiance (indirect) and its baked direct light; the attribute pass then blends
// that value over the splat's pixels. Shading every fragment with its own view ray took 86 of
// the attribute pass's 127 ms on the bunny at 512^2; once per splat it takes 11 ms. The view
// direction varies across a disk by its angular size alone.
// Splats turned away or outside the view are not drawn: they get 0.
// Twin: src/cpu/splat_shade.rs.

// #import dispatch
// #import splat
// #import splat_shading

@group(0) @binding(0) var<uniform> cam: Camera;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
// #paged
@group(0) @binding(10) var<storage, read_write> shaded: array<vec4<f32>>;

const WG: u32 = 64u;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= splats_len() {
        return;
    }
    let s = splats_at(i);
    var out = vec4<f32>(0.0);
    if faces_camera(s, cam.eye) && in_view(cam, s) {
        let wo = normalize(cam.eye - s.center);
        let m = materials[s.material];
        out = vec4<f32>(indirect(i, s, m, wo) + baked_direct(i, s, m, s.center, wo), 0.0);
    }
    shaded_put(i, out);
}
