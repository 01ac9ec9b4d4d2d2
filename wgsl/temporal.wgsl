// Temporal anti-aliasing of moving frames (docs/design.md section 8, "Moving frames"): each
// moving frame is drawn with its own sub-pixel jitter and blended into the last resolved image,
// found where the surface a pixel shows was in the last frame's camera. Per pixel:
// - the history: the four last-frame pixels around where the pixel's surface was (where it
//   shows none, the nearest surface an edge neighbour shows, else its view direction, a point
//   at infinity: moved_point), each kept only where it showed a
//   surface the pixel shows now (its distance from the last eye within depth_tolerance of
//   that surface's, its normal within normal_cos; what the motion uncovered starts anew), or
//   one an edge neighbour shows where what it showed lies within the pixel's footprint now,
//   bilinear among the kept ones. The neighbours count because a jittered pixel on an edge
//   shows either side of it: held to its own surface alone, the history was dropped there
//   every few frames and the edge showed that frame's aliased sample. The footprint keeps a
//   silhouette that moved off the pixel from staying in it. Lights carry their surface's
//   normal reversed (shade.wgsl), so a light and the ceiling it lies on are two surfaces;
// - the clamp: the history's colour limited to the range of the frame's neighbourhood (the
//   pixel and its four edge neighbours), so that what moved or changed light leaves no trail
//   beyond it;
// - the blend: the running mean of the history's frames and this one, counting at most
//   max_frames (then an exponential mean of weight 1 / max_frames).
// The resampling and the blend weigh each colour by 1 / (1 + its luminance as displayed):
// resampled again every frame, a light's few bright pixels would otherwise bleed into the dim
// ones around it, tens of times their value (the ring a moving camera left round the box's
// light), and the clamp lets it be where the light is in the neighbourhood. "As displayed":
// times the tone map's exposure of this frame, WEIGHT_KEY over its log-average (log_sum), so
// that the weights do not depend on the lights' power. In the scene's own units the bunny's
// radiances lie well below 1 and were blended nearly unweighted: its 20-frame orbit read
// 0.0120 (median relMSE), 0.0103 weighed as displayed. (Tried and not kept, on the box's
// orbit: the nearest surface of the 3x3 neighbourhood in place of the pixel's own, which
// haloed every silhouette with the object in front; Catmull-Rom resampling, no better; on the
// bunny's, variance clipping, which pulled a row's history across the light's edge.)
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
// This frame's (sum of log(eps + Y), count), as tonemap_reduce sums it.
@group(0) @binding(9) var<storage, read> log_sum: array<vec2<f32>>;

const WG: u32 = 64u;
// A distance at least this large is no surface (shade writes FAR there).
const NO_SURFACE: f32 = 1.0e37;

fn pixel_index(x: i32, y: i32) -> u32 {
    return u32(y) * params.width + u32(x);
}

// The key of the weights' exposure: the tone map's default key.
const WEIGHT_KEY: f32 = 0.18;

// The exposure that displays this frame: WEIGHT_KEY over its log-average luminance (1 where it
// has no finite pixel).
fn frame_exposure() -> f32 {
    let s = log_sum[0];
    if s.y <= 0.0 {
        return 1.0;
    }
    return WEIGHT_KEY / exp(s.x / s.y);
}

// A colour's weight in the resampling and the blend, its luminance scaled by `exposure`.
fn weight_of(c: vec3<f32>, exposure: f32) -> f32 {
    return 1.0 / (1.0 + exposure * max(luminance(c), 0.0));
}

// The point at distance t along pixel q's ray in this frame's camera.
fn point_shown(q: vec2<i32>, t: f32) -> vec3<f32> {
    return cam.eye + t * pixel_ray(cam, vec2<f32>(q) + 0.5);
}

// Surface s (normal, distance along its ray) that pixel q shows, as (normal, distance from
// the last frame's eye); NO_SURFACE where it shows none.
fn seen_from_last_eye(q: vec2<i32>, s: vec4<f32>) -> vec4<f32> {
    if s.w >= NO_SURFACE {
        return vec4<f32>(s.xyz, NO_SURFACE);
    }
    return vec4<f32>(s.xyz, length(point_shown(q, s.w) - prev.eye));
}

// Whether the last frame's surface `was` (normal, distance from its eye) is the surface
// `seen` (seen_from_last_eye): both none, or distances within depth_tolerance and normals
// within normal_cos.
fn same_surface_seen(was: vec4<f32>, seen: vec4<f32>) -> bool {
    let was_shown = was.w < NO_SURFACE;
    let shown = seen.w < NO_SURFACE;
    if !was_shown || !shown {
        return was_shown == shown;
    }
    return abs(was.w - seen.w) <= params.depth_tolerance * seen.w
        && dot(was.xyz, seen.xyz) >= params.normal_cos;
}

// Edge neighbour k (0-3: right, left, down, up) of pixel px, clamped to the image.
fn edge_neighbour(px: vec2<i32>, k: i32, size: vec2<i32>) -> vec2<i32> {
    let step = select(vec2<i32>(1 - 2 * (k & 1), 0), vec2<i32>(0, 1 - 2 * (k & 1)), k >= 2);
    return clamp(px + step, vec2<i32>(0), size - 1);
}

// Whether one of pixel px's edge neighbours shows the last frame's surface `was` now.
fn shown_beside(px: vec2<i32>, size: vec2<i32>, was: vec4<f32>) -> bool {
    for (var k = 0; k < 4; k++) {
        let q = edge_neighbour(px, k, size);
        if same_surface_seen(was, seen_from_last_eye(q, surface[pixel_index(q.x, q.y)])) {
            return true;
        }
    }
    return false;
}

// Whether what last-frame pixel q showed (surface `was`: normal, distance along its ray)
// lies within pixel px's footprint in this frame's image; nothing lies everywhere.
fn in_footprint(px: vec2<i32>, q: vec2<i32>, was: vec4<f32>) -> bool {
    if was.w >= NO_SURFACE {
        return true;
    }
    let now = project_point(cam, prev.eye + was.w * pixel_ray(prev, vec2<f32>(q) + 0.5));
    return now.z > 0.0 && all(vec2<i32>(floor(now.xy)) == px);
}

// What pixel px's history moved with, as (point, 1), or (direction, 0) for a point at
// infinity: the surface it shows (own, at p along its ray d); where it shows none, the nearest
// surface an edge neighbour shows; else its view direction. A pixel that shows nothing beside
// a surface is an edge the jittered samples cover in part: following the view direction there
// fetched the history of pixels that showed nothing, and every sample that missed the
// surface set the pixel back to black (the box's outline read 0 where the still image has
// two thirds of the floor).
fn moved_point(px: vec2<i32>, size: vec2<i32>, own: vec4<f32>, d: vec3<f32>,
               p: vec3<f32>) -> vec4<f32> {
    if own.w < NO_SURFACE {
        return vec4<f32>(p, 1.0);
    }
    var nearest = vec4<f32>(d, 0.0);
    var t = NO_SURFACE;
    for (var k = 0; k < 4; k++) {
        let q = edge_neighbour(px, k, size);
        let s = surface[pixel_index(q.x, q.y)];
        if s.w < t {
            t = s.w;
            nearest = vec4<f32>(point_shown(q, t), 1.0);
        }
    }
    return nearest;
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
    let own = surface[i];
    let shows = own.w < NO_SURFACE;
    // The neighbourhood's colour range: the pixel and its four edge neighbours (the 3x3
    // square's corners cost llvmpipe a third of the pass for a range hardly wider).
    var lo = current;
    var hi = current;
    for (var k = 0; k < 4; k++) {
        let q = edge_neighbour(px, k, size);
        let c = hdr[pixel_index(q.x, q.y)].xyz;
        lo = min(lo, c);
        hi = max(hi, c);
    }
    var out = vec4<f32>(current, 1.0);
    if params.reset == 0u {
        let exposure = frame_exposure();
        // Where the surface is now and was in the last frame's image: a point, or where the
        // pixel shows none, a direction (the same from either eye).
        let d = pixel_ray(cam, vec2<f32>(px) + 0.5);
        let p = cam.eye + own.w * d;
        // The pixel's own surface as seen_from_last_eye gives it, from the ray already cast.
        let seen = vec4<f32>(own.xyz, select(NO_SURFACE, length(p - prev.eye), shows));
        let moved = moved_point(px, size, own, d, p);
        let now = project_point(cam, select(cam.eye + moved.xyz, moved.xyz, moved.w > 0.0));
        let was = project_point(prev, select(prev.eye + moved.xyz, moved.xyz, moved.w > 0.0));
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
            // A surface only a neighbour shows counts where this pixel's footprint held it (the
            // neighbours are read only then: on edges).
            let same = same_surface_seen(was_surface, seen)
                || (shown_beside(px, size, was_surface) && in_footprint(px, q, was_surface));
            if same {
                let b = select(1.0 - f.x, f.x, (k & 1) == 1) * select(1.0 - f.y, f.y, k >= 2);
                let h = history[j];
                let w = b * weight_of(h.xyz, exposure);
                sum += vec4<f32>(w * h.xyz, b * h.w);
                weight += w;
                bilinear += b;
            }
        }
        if weight > 0.0 {
            let kept = clamp(sum.xyz / weight, lo, hi);
            let frames = min(sum.w / bilinear + 1.0, f32(params.max_frames));
            let wc = weight_of(current, exposure) / frames;
            let wh = weight_of(kept, exposure) * (1.0 - 1.0 / frames);
            out = vec4<f32>((wc * current + wh * kept) / (wc + wh), frames);
        }
    }
    resolved[i] = out;
    resolved_surface[i] = own;
}
