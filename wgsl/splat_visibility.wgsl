// Splat pass 1, visibility (docs/design.md section 8): every front-facing splat as a triangle; the
// fragment shader intersects the pixel's view ray with the disk, discards outside it (and
// outside its surface's bounds, drawn_clip.wgsl), and
// writes the hit's depth pushed back by `depth_tolerance` splat radii along view z, and the
// splat's normal (octahedral) into the front target. The attribute pass then blends every
// splat within that tolerance of the nearest surface and facing its way (same_surface).
// Depth is reversed (greater is nearer). Twin: src/cpu/splat_visibility.rs.

// #import splat
// #import drawn_clip

@group(0) @binding(0) var<uniform> cam: Camera;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
// Frames of baked direct light (LISTED) draw splat_list's list alone, each splat at the radius
// splat_select chose for it.
// #paged
@group(0) @binding(2) var<storage, read> drawn: array<f32>;
@group(0) @binding(3) var<storage, read> selected_count: array<u32>;
// #paged
@group(0) @binding(4) var<storage, read> selected: array<u32>;
// Where each surface's disks end (drawn_clip.wgsl).
@group(0) @binding(5) var<uniform> drawn_clips: array<SurfaceClip, DRAWN_CLIPS>;

// Splat s's surface's clip as drawn (drawn_clip.wgsl).
fn drawn_clip(s: Splat) -> SurfaceClip {
    return drawn_clips[drawn_clip_index(s)];
}

// Whether the fragment of vertex v with its hit at p is drawn (drawn_clip.wgsl).
fn clip_passes(v: SplatVertex, p: vec3<f32>) -> bool {
    return clip_cuts(v) == 0u || cut_rows_keep(v, drawn_clips[clip_surface(v)], p);
}

@vertex
fn vs_main(@builtin(vertex_index) k: u32, @builtin(instance_index) b: u32) -> SplatVertex {
    let i = instance_splat(k, b);
    if LISTED {
        if i >= selected_count[0] {
            return surplus_vertex(i);
        }
        let listed = selected_at(i);
        let s = drawn_splat(splats_at(listed), drawn_at(listed));
        return clipped_vertex(splat_vertex(cam, s, listed, instance_corner(k)), s,
                              drawn_clip(s));
    }
    if i >= splats_len() {
        return surplus_vertex(i);
    }
    let s = splats_at(i);
    return clipped_vertex(splat_vertex(cam, s, i, instance_corner(k)), s,
                          drawn_clip(s));
}

struct Visible {
    @builtin(frag_depth) depth: f32,
    @location(0) front: u32,
}

@fragment
fn fs_main(v: SplatVertex) -> Visible {
    let s = vertex_splat(v);
    let d = pixel_ray(cam, v.position.xy);
    let h = splat_hit(s, cam.eye, d);
    if !covers(cam, h, d) || !clip_passes(v, cam.eye + h.t * d) {
        discard;
    }
    let z = h.t * dot(d, cam.forward);
    return Visible(view_depth(cam, z + cam.depth_tolerance * s.radius), oct_encode(s.normal));
}
