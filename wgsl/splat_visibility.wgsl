// Splat pass 1, visibility (docs/design.md section 8): every front-facing splat as a triangle; the
// fragment shader intersects the pixel's view ray with the disk, discards outside it, and
// writes the hit's depth pushed back by `depth_tolerance` splat radii along view z, and the
// splat's normal (octahedral) into the front target. The attribute pass then blends every
// splat within that tolerance of the nearest surface and facing its way (same_surface).
// Depth is reversed (greater is nearer). Twin: src/cpu/splat_visibility.rs.

// #import splat

@group(0) @binding(0) var<uniform> cam: Camera;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
// With the level of detail (LOD), the radius splat_select chose for each splat.
// #paged
@group(0) @binding(2) var<storage, read> drawn: array<f32>;

@vertex
fn vs_main(@builtin(vertex_index) k: u32, @builtin(instance_index) b: u32) -> SplatVertex {
    let i = instance_splat(k, b);
    if i >= splats_len() {
        return surplus_vertex(i);
    }
    var s = splats_at(i);
    if LOD {
        s.radius = drawn_at(i);
    }
    return splat_vertex(cam, s, i, instance_corner(k));
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
    if !covers(cam, h, d) {
        discard;
    }
    let z = h.t * dot(d, cam.forward);
    return Visible(view_depth(cam, z + cam.depth_tolerance * s.radius), oct_encode(s.normal));
}
