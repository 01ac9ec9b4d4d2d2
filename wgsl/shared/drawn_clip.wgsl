// Where the drawn splats' surfaces end (SurfaceClip in src/types.rs), for the passes that draw
// splats: a pixel sees a disk only where the disk's surface keeps the hit, as a traced ray
// does (trace.wgsl), so that a box's edges are drawn where the box ends, as the path tracer
// sees them. A disk wholly inside its surface's bounds (nearly all) needs no test per pixel:
// the vertex names the surface only for disks that cross them. Each drawing stage declares
// `drawn_clips: array<SurfaceClip>` at the binding after its own (so that its bindings stay
// numbered without a gap), one entry for every surface a splat names (`device_clips`), and
// passes its splat's entry in. Twin: src/shared/splat.rs (`drawn_keeps`).

// #import types
// #import splat

// Vertex v of splat s, whose surface's clip is c: v.clip names the surface where the disk
// crosses its bounds, else NO_CLIP.
fn clipped_vertex(v: SplatVertex, s: Splat, c: SurfaceClip) -> SplatVertex {
    var out = v;
    out.clip = select(s.object, NO_CLIP, clip_holds_disk(c, s));
    return out;
}
