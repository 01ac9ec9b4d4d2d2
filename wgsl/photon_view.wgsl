// The photon view (thesis Fig. 3.1): every stored photon that the camera sees (on the front of
// its splat, with nothing in between) adds its power times the splat's albedo (rho_d + rho_s)
// to its pixel: a photon stores the power that arrives, and the surface's colour shows only
// in what leaves. The sums are fixed point (`params.scale` units per unit of power, each
// photon capped at PHOTON_CAP units) in integer atomics, so the image does not depend on the
// order the photons land in. One invocation per photon of one page.
// CPU mirror: src/cpu/photon_view.rs. Then photon_resolve turns the sums into HDR pixels.

// #import types
// #import dispatch
// #import splat
// #import trace

@group(0) @binding(0) var<uniform> params: PhotonViewParams;
@group(0) @binding(1) var<uniform> cam: Camera;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
@group(0) @binding(3) var<storage, read> photons: array<Photon>;
@group(0) @binding(4) var<storage, read_write> sums: array<atomic<u32>>;

const WG: u32 = 64u;
// At most 2^16 units from one photon: a pixel overflows only past 65536 capped photons.
const PHOTON_CAP: f32 = 65536.0;

// The pixel p projects into (the raster passes' projection, `clip_position`), as (x, y);
// x = -1 when p is behind the camera or outside.
fn project_pixel(p: vec3<f32>) -> vec2<i32> {
    let clip = clip_position(cam, p);
    if clip.w <= 0.0 {
        return vec2<i32>(-1);
    }
    let ndc = clip.xy / clip.w;
    let x = (ndc.x * 0.5 + 0.5) * cam.size.x;
    let y = (0.5 - ndc.y * 0.5) * cam.size.y;
    if !(x >= 0.0 && x < cam.size.x && y >= 0.0 && y < cam.size.y) {
        return vec2<i32>(-1);
    }
    return vec2<i32>(i32(x), i32(y));
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= params.count {
        return;
    }
    let p = photons[i];
    let pixel = project_pixel(p.position);
    if pixel.x < 0 {
        return;
    }
    let s = splats_at(p.splat);
    let to_eye = cam.eye - p.position;
    if dot(s.normal, to_eye) <= 0.0 {
        return;
    }
    let dist = length(to_eye);
    var budget = SHADOW_RAY_BUDGET;
    let hit = trace_ray(p.position, to_eye / dist, p.splat, dist * 0.999, &budget);
    if hit.splat != NO_SPLAT || hit.aborted != 0u {
        return;
    }
    let albedo = s.diffuse + materials[s.material].specular;
    let units = min(p.power * albedo * params.scale, vec3<f32>(PHOTON_CAP));
    let at = 3u * (u32(pixel.y) * params.width + u32(pixel.x));
    for (var c = 0u; c < 3u; c++) {
        atomicAdd(&sums[at + c], u32(units[c]));
    }
}
