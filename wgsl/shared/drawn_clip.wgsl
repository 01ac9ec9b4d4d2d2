// Where the drawn splats' surfaces end (SurfaceClip in src/types.rs), for the passes that draw
// splats: a pixel sees a disk only where the disk's surface keeps the hit, as a traced ray
// does (trace.wgsl), so that a box's edges are drawn where the box ends, as the path tracer
// sees them. The vertex passes on the clip's rows that cut its disk (none for nearly all), so
// that a fragment tests two planes and reads nothing. Each drawing stage declares
// `drawn_clips: array<SurfaceClip, DRAWN_CLIPS>`, a uniform, at the binding after its own (so
// that its bindings stay numbered without a gap): the clips of the first DRAWN_CLIPS - 1
// surfaces, then a zero clip for every later one (`drawn_clip`). A uniform, not a storage
// array: llvmpipe's vertex shaders paid 8 ms a pass at 512² for a storage read, even one
// under a branch none took. Twin: src/shared/splat.rs (`drawn_keeps`).

// #import types
// #import splat

// Surfaces whose clips the drawing passes hold (the last entry stays zero).
const DRAWN_CLIPS: u32 = 64u;

// Vertex v of splat s, whose surface's clip is c, with the rows that cut its disk.
fn clipped_vertex(v: SplatVertex, s: Splat, c: SurfaceClip) -> SplatVertex {
    var out = v;
    let rows = clip_drawn_rows(c, s);
    out.clip_a = rows[0];
    out.clip_b = rows[1];
    return out;
}

// Whether a hit at p on a disk whose cutting rows are a and b is drawn.
fn rows_pass(a: vec4<f32>, b: vec4<f32>, p: vec3<f32>) -> bool {
    let q = vec4<f32>(p, 1.0);
    return abs(dot(a, q)) <= 1.0 && abs(dot(b, q)) <= 1.0;
}

// Whether a fragment of vertex v with its hit at p is drawn. Nearly every disk has no row that
// cuts it (then the first is zero): such a triangle's fragments skip the test.
fn clip_passes(v: SplatVertex, p: vec3<f32>) -> bool {
    return all(v.clip_a == vec4<f32>(0.0)) || rows_pass(v.clip_a, v.clip_b, p);
}
