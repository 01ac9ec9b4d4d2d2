// Where the drawn splats' surfaces end (SurfaceClip in src/types.rs), for the passes that draw
// splats: a pixel sees a disk only where the disk's surface keeps the hit, as a traced ray
// does (trace.wgsl), so that a box's edges are drawn where the box ends, as the path tracer
// sees them. The vertex passes on which of the clip's rows cut its disk (none for nearly all)
// and its surface, in one flat value: a fragment of a cut disk reads those rows from the uniform
// and tests them, one of an uncut disk tests nothing. Passing the rows themselves (eight flat
// floats a vertex) cost llvmpipe's vertex and setup work 15-20 % of a 160x90 frame of the
// bunny (docs/viewer.md). Each drawing stage declares
// `drawn_clips: array<SurfaceClip, DRAWN_CLIPS>`, a uniform, at the binding after its own (so
// that its bindings stay numbered without a gap): the clips of the first DRAWN_CLIPS - 1
// surfaces, then a zero clip for every later one (`drawn_clip`). A uniform, not a storage
// array: llvmpipe's vertex shaders paid 8 ms a pass at 512² for a storage read, even one
// under a branch none took. Twin: src/shared/splat.rs (`drawn_keeps`).

// #import types
// #import splat

// Surfaces whose clips the drawing passes hold (the last entry stays zero).
const DRAWN_CLIPS: u32 = 64u;

// Splat s's surface's entry in a stage's drawn_clips.
fn drawn_clip_index(s: Splat) -> u32 {
    return min(s.object, DRAWN_CLIPS - 1u);
}

// Vertex v of splat s, whose surface's clip is c (drawn_clips[drawn_clip_index(s)]): bits 0-2
// of its `clip` say which of the rows x, y, z cut the disk (clip_cut_rows), the bits above the
// surface.
fn clipped_vertex(v: SplatVertex, s: Splat, c: SurfaceClip) -> SplatVertex {
    var out = v;
    out.clip = clip_cut_rows(c, s) | (drawn_clip_index(s) << 3u);
    return out;
}

// Whether a hit at p on a disk whose cutting rows are a and b is drawn.
fn rows_pass(a: vec4<f32>, b: vec4<f32>, p: vec3<f32>) -> bool {
    let q = vec4<f32>(p, 1.0);
    return abs(dot(a, q)) <= 1.0 && abs(dot(b, q)) <= 1.0;
}

// Whether row r, where it cuts the disk (`cut`), keeps the point q.
fn row_keeps(cut: bool, r: vec4<f32>, q: vec4<f32>) -> bool {
    return !cut || abs(dot(r, q)) <= 1.0;
}

// The rows of its surface's clip that cut vertex v's disk (bits 0-2; 0 for nearly every disk),
// and that surface's entry in drawn_clips.
fn clip_cuts(v: SplatVertex) -> u32 {
    return v.clip & 7u;
}

fn clip_surface(v: SplatVertex) -> u32 {
    return v.clip >> 3u;
}

// Whether the rows of clip c that cut vertex v's disk keep a hit at p. A stage's clip_passes
// reads c from its drawn_clips only where a row cuts (clip_cuts), so that the fragments of
// nearly every disk read nothing.
fn cut_rows_keep(v: SplatVertex, c: SurfaceClip, p: vec3<f32>) -> bool {
    let cuts = clip_cuts(v);
    let q = vec4<f32>(p, 1.0);
    return row_keeps((cuts & 1u) != 0u, c.x, q) && row_keeps((cuts & 2u) != 0u, c.y, q)
        && row_keeps((cuts & 4u) != 0u, c.z, q);
}
