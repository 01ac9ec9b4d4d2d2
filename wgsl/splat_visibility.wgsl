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
// Frames of baked direct light (LISTED) draw splat_list's list alone, each splat at the radius
// splat_select chose for it.
// #paged
@group(0) @binding(2) var<storage, read> drawn: array<f32>;
@group(0) @binding(3) var<storage, read> selected_count: array<u32>;
// #paged
@group(0) @binding(4) var<storage, read> selected: array<u32>;

@vertex
fn vs_main(@builtin(vertex_index) k: u32, @builtin(instance_index) b: u32) -> SplatVertex {
    let i = instance_splat(k, b);
    if LISTED {
        if i >= selected_count[0] {
            return surplus_vertex(i);
        }
        let listed = selected_at(i);
        return splat_vertex(cam, drawn_splat(splats_at(listed), drawn_at(listed)), listed,
                            instance_corner(k));
    }
    if i >= splats_len() {
        return surplus_vertex(i);
    }
    return splat_vertex(cam, splats_at(i), i, instance_corner(k));
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
