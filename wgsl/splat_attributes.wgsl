// Splat pass 2, attributes (docs/design.md sections 7-8): the splats within the depth
// tolerance of the visible surface (depth test against pass 1, no depth writes) and facing
// its way (pass 1's front target) add
// weight x (what the shade pass needs) into four float targets by additive blending, in
// draw order. Each fragment of fs_main is shaded from its own splat's lobes with its own
// view ray: the indirect light, diffuse from the total irradiance and specular from every
// lobe. With baked direct light (params.direct), fs_baked blends what splat_shade found per
// splat instead. Twin: src/cpu/splat_attributes.rs.

// #import splat
// #import splat_shading
// #import drawn_clip

@group(0) @binding(0) var<uniform> cam: Camera;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
// Pass 1's front target: the normal of each pixel's nearest splat.
@group(0) @binding(10) var front: texture_2d<u32>;
// With baked direct light, the radiance splat_shade gave each splat towards the eye.
// #paged
@group(0) @binding(11) var<storage, read> shaded: array<vec4<f32>>;
// Frames of baked direct light draw splat_list's list alone (LISTED), each splat at the radius
// splat_select chose for it.
// #paged
@group(0) @binding(12) var<storage, read> drawn: array<f32>;
@group(0) @binding(13) var<storage, read> selected_count: array<u32>;
// #paged
@group(0) @binding(14) var<storage, read> selected: array<u32>;
// Where each surface's disks end (drawn_clip.wgsl).
@group(0) @binding(15) var<uniform> drawn_clips: array<SurfaceClip, DRAWN_CLIPS>;
// The environment light's map (lights.wgsl), which these passes do not read: their derived
// layouts leave it out.
@group(0) @binding(16) var<storage, read> sky: array<vec4<f32>>;

// Whether splat s is of the surface the pixel sees (same_surface).
fn in_front(v: SplatVertex, s: Splat) -> bool {
    return same_surface(textureLoad(front, vec2<i32>(v.position.xy), 0).x, s.normal);
}

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
    if i >= splats_len() {
        return surplus_vertex(i);
    }
    let s = splats_at(i);
    return clipped_vertex(splat_vertex(cam, s, i, instance_corner(k)), s,
                          drawn_clip(s));
}

@fragment
fn fs_main(v: SplatVertex) -> Attributes {
    var s = splats_at(v.splat);
    s.radius = v.radius;
    let d = pixel_ray(cam, v.position.xy);
    let h = splat_hit(s, cam.eye, d);
    if !covers(cam, h, d) || !clip_passes(v, cam.eye + h.t * d) || !in_front(v, s) {
        discard;
    }
    let w = splat_weight(h.q);
    let m = materials[s.material];
    let gloss = (m.specular.x + m.specular.y + m.specular.z) * (1.0 / 3.0);
    var out: Attributes;
    out.radiance = w * vec4<f32>(indirect(v.splat, s, m, -d), 1.0);
    out.geometry = w * vec4<f32>(s.normal, h.t);
    out.diffuse = w * vec4<f32>(s.diffuse, gloss * m.roughness);
    out.specular = w * vec4<f32>(m.specular, gloss);
    return out;
}

// What the attribute pass blends with baked direct light: the shade pass casts no shadow
// ray, so it needs only the radiance and the distance (for lights seen in front).
struct BakedAttributes {
    @location(0) radiance: vec4<f32>,
    @location(1) geometry: vec4<f32>,
}

// The vertex of the baked variant: the splat's radiance comes with it.
@vertex
fn vs_baked(@builtin(vertex_index) k: u32, @builtin(instance_index) b: u32) -> SplatVertex {
    let i = instance_splat(k, b);
    if i >= selected_count[0] {
        return surplus_vertex(i);
    }
    let listed = selected_at(i);
    let s = drawn_splat(splats_at(listed), drawn_at(listed));
    var out = clipped_vertex(splat_vertex(cam, s, listed, instance_corner(k)), s, drawn_clip(s));
    out.radiance = shaded_at(listed).xyz;
    return out;
}

// The fragment of the baked-direct variant (params.direct == DIRECT_BAKED): the splat's
// radiance as splat_shade found it (indirect and baked direct light, shaded once per splat)
// into the first two targets; blending two targets, not four, is what a software rasterizer
// saves most on.
@fragment
fn fs_baked(v: SplatVertex) -> BakedAttributes {
    let s = vertex_splat(v);
    let d = pixel_ray(cam, v.position.xy);
    let h = splat_hit(s, cam.eye, d);
    if !covers(cam, h, d) || !clip_passes(v, cam.eye + h.t * d) || !in_front(v, s) {
        discard;
    }
    let w = splat_weight(h.q);
    var out: BakedAttributes;
    out.radiance = w * vec4<f32>(v.radiance, 1.0);
    out.geometry = w * vec4<f32>(s.normal, h.t);
    return out;
}
