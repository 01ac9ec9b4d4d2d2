// Temporal anti-aliasing of moving frames (docs/design.md section 8, "Moving frames"): each
// moving frame is drawn with its own sub-pixel jitter and blended into the last resolved image,
// found where the surface a pixel shows was in the last frame's camera. Per pixel:
// - the history: the four last-frame pixels around where the pixel's surface was (where it
//   shows none, its view direction's, a point at infinity), each kept only where it showed
//   the same surface (its distance from the last eye within depth_tolerance of the reprojected
//   point's, its normal within normal_cos; what the motion uncovered starts anew), bilinear
//   among the kept ones;
// - the clamp: the history's colour limited to the range of the frame's neighbourhood (the
//   pixel and its four edge neighbours), so that what moved or changed light leaves no trail
//   beyond it;
// - the blend: the running mean of the history's frames and this one, counting at most
//   max_frames (then an exponential mean of weight 1 / max_frames).
// The resampling and the blend weigh each colour by 1 / (1 + its luminance): resampled again
// every frame, a light's few bright pixels would otherwise bleed into the dim ones around it,
// tens of times their value (the ring a moving camera left round the box's light), and the
// clamp lets it be where the light is in the neighbourhood. (Tried and not kept, on the box's
// orbit: the nearest surface of the 3x3 neighbourhood in place of the pixel's own, which
// haloed every silhouette with the object in front; Catmull-Rom resampling, no better.)
// Writes the resolved image (w: the frames it holds) and each pixel's surface, the next
// frame's history. Twin: src/cpu/temporal.rs.

// #import types
// #import dispatch
// #import splat
// #import tone

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> prev: Camera;
@group(0) @binding(2) var<uniform> params: TemporalParams;
// This frame: its radiance, and per pixel the surface it shows (normal, distance from the
// eye along the pixel's ray; FAR where it shows none).
@group(0) @binding(3) var<storage, read> hdr: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> surface: array<vec4<f32>>;
// The last resolved frame and its kept surfaces.
@group(0) @binding(5) var<storage, read> history: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> history_surface: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> resolved: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> resolved_surface: array<vec4<f32>>;

const WG: u32 = 64u;
// A distance at least this large is no surface (shade writes FAR there).
const NO_SURFACE: f32 = 1.0e37;

fn pixel_index(x: i32, y: i32) -> u32 {
    return u32(y) * params.width + u32(x);
}

// A colour's weight in the resampling and the blend.
fn weight_of(c: vec3<f32>) -> f32 {
    return 1.0 / (1.0 + max(luminance(c), 0.0));
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = linear_workgroup(wg, num_wg) * WG + lid;
    if i >= params.width * params.height {
        return;
    }
    let px = vec2<i32>(i32(i % params.width), i32(i / params.width));
    let size = vec2<i32>(i32(params.width), i32(params.height));
    let current = hdr[i].xyz;
    // The neighbourhood's colour range: the pixel and its four edge neighbours (the 3x3
    // square's corners cost llvmpipe a third of the pass for a range hardly wider).
    var lo = current;
    var hi = current;
    for (var k = 0; k < 4; k++) {
        let step = select(vec2<i32>(1 - 2 * (k & 1), 0), vec2<i32>(0, 1 - 2 * (k & 1)), k >= 2);
        let q = clamp(px + step, vec2<i32>(0), size - 1);
        let c = hdr[pixel_index(q.x, q.y)].xyz;
        lo = min(lo, c);
        hi = max(hi, c);
    }
    let own = surface[i];
    let shows = own.w < NO_SURFACE;
    var out = vec4<f32>(current, 1.0);
    if params.reset == 0u {
        // Where the surface is now and was in the last frame's image: a point, or where the
        // pixel shows none, a direction (the same from either eye).
        let d = pixel_ray(cam, vec2<f32>(px) + 0.5);
        let p = cam.eye + own.w * d;
        let now = project_point(cam, select(cam.eye + d, p, shows));
        let was = project_point(prev, select(prev.eye + d, p, shows));
        let expected = length(p - prev.eye);
        // The pixel's centre moved as the surface did; pixel k's centre is at k + 0.5.
        let at = vec2<f32>(px) + (was.xy - now.xy);
        let base = floor(at);
        let f = at - base;
        var sum = vec4<f32>(0.0);
        var weight = 0.0;
        var bilinear = 0.0;
        for (var k = 0; k < 4; k++) {
            let q = vec2<i32>(base) + vec2<i32>(k & 1, k >> 1u);
            let inside = all(q >= vec2<i32>(0)) && all(q < size);
            if !inside || was.z <= 0.0 {
                continue;
            }
            let j = pixel_index(q.x, q.y);
            let was_surface = history_surface[j];
            let was_shown = was_surface.w < NO_SURFACE;
            var same = !shows && !was_shown;
            if shows && was_shown {
                same = abs(was_surface.w - expected) <= params.depth_tolerance * expected
                    && dot(was_surface.xyz, own.xyz) >= params.normal_cos;
            }
            if same {
                let b = select(1.0 - f.x, f.x, (k & 1) == 1) * select(1.0 - f.y, f.y, k >= 2);
                let h = history[j];
                let w = b * weight_of(h.xyz);
                sum += vec4<f32>(w * h.xyz, b * h.w);
                weight += w;
                bilinear += b;
            }
        }
        if weight > 0.0 {
            let kept = clamp(sum.xyz / weight, lo, hi);
            let frames = min(sum.w / bilinear + 1.0, f32(params.max_frames));
            let wc = weight_of(current) / frames;
            let wh = weight_of(kept) * (1.0 - 1.0 / frames);
            out = vec4<f32>((wc * current + wh * kept) / (wc + wh), frames);
        }
    }
    resolved[i] = out;
    resolved_surface[i] = own;
}
