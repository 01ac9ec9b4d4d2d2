// Compute splatter, pass 3 (docs/design.md section 8): the two raster passes in one compute
// pass without triangles. One workgroup per screen tile, one invocation per pixel: over the
// tile's splats in index order (the raster passes' draw order), first the nearest depth
// pushed back by the tolerance and its normal (pass 1), then the weighted attributes of every
// splat within it and facing its way (pass 2's blending), summed in registers and stored once. It writes what the
// attribute pass blends, so the shade pass follows unchanged. CPU mirror: the raster passes'
// (src/cpu/splat_visibility.rs, src/cpu/splat_attributes.rs), which sum per pixel in the same
// order.

// #import dispatch
// #import splat
// #import splat_shading
// #import drawn_clip

@group(0) @binding(0) var<uniform> cam: Camera;
// #paged
@group(0) @binding(1) var<storage, read> splats: array<Splat>;
@group(0) @binding(10) var<uniform> tiles: TileParams;
@group(0) @binding(11) var<storage, read> tile_start: array<u32>;
@group(0) @binding(12) var<storage, read> tile_splats: array<u32>;
// splat_shade's radiance of each splat, for frames of baked direct light.
// #paged
@group(0) @binding(13) var<storage, read> shaded: array<vec4<f32>>;
@group(0) @binding(14) var radiance_sum: texture_storage_2d<rgba32float, write>;
@group(0) @binding(15) var geometry_sum: texture_storage_2d<rgba32float, write>;
@group(0) @binding(16) var diffuse_sum: texture_storage_2d<rgba32float, write>;
@group(0) @binding(17) var specular_sum: texture_storage_2d<rgba32float, write>;
// Where each surface's disks end (drawn_clip.wgsl).
@group(0) @binding(18) var<uniform> drawn_clips: array<SurfaceClip, DRAWN_CLIPS>;
// The environment light's map (lights.wgsl), which this pass does not read: its derived
// layout leaves it out.
@group(0) @binding(19) var<storage, read> sky: array<vec4<f32>>;

const WG: u32 = 64u;

// Whether a hit at p on splat s is drawn where its surface ends (as the raster passes test).
fn drawn(s: Splat, p: vec3<f32>) -> bool {
    let rows = clip_drawn_rows(drawn_clip(s), s);
    return rows_pass(rows[0], rows[1], p);
}

// Splat s's surface's clip as drawn (drawn_clip.wgsl).
fn drawn_clip(s: Splat) -> SurfaceClip {
    return drawn_clips[drawn_clip_index(s)];
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) num_wg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let t = linear_workgroup(wg, num_wg);
    if t >= tiles.tiles_x * tiles.tiles_y {
        return;
    }
    let corner = vec2<u32>(t % tiles.tiles_x, t / tiles.tiles_x) * TILE;
    let px = corner + vec2<u32>(lid % TILE, lid / TILE);
    let size = vec2<u32>(cam.size);
    if px.x >= size.x || px.y >= size.y {
        return;
    }
    let d = pixel_ray(cam, vec2<f32>(px) + 0.5);
    let z_of = dot(d, cam.forward);
    let baked = params.direct == DIRECT_BAKED;
    let begin = tile_start[t];
    let end = tile_start[t + 1u];
    // Pass 1: the nearest surface's depth, pushed back (reversed depth: greater is nearer),
    // and its normal: the first of the nearest, as the raster pass's `Greater` test keeps.
    var nearest = 0.0;
    var front = 0u;
    for (var k = begin; k < end; k++) {
        let s = splats_at(tile_splats[k]);
        let h = splat_hit(s, cam.eye, d);
        if covers(cam, h, d) && drawn(s, cam.eye + h.t * d) {
            let z = view_depth(cam, h.t * z_of + cam.depth_tolerance * s.radius);
            if z > nearest {
                nearest = z;
                front = oct_encode(s.normal);
            }
        }
    }
    // Pass 2: every splat within the tolerance, in draw order.
    var radiance = vec4<f32>(0.0);
    var geometry = vec4<f32>(0.0);
    var diffuse = vec4<f32>(0.0);
    var specular = vec4<f32>(0.0);
    for (var k = begin; k < end; k++) {
        let i = tile_splats[k];
        let s = splats_at(i);
        let h = splat_hit(s, cam.eye, d);
        if !covers(cam, h, d) || !drawn(s, cam.eye + h.t * d)
            || !(view_depth(cam, h.t * z_of) >= nearest)
            || !same_surface(front, s.normal) {
            continue;
        }
        let w = splat_weight(h.q);
        let m = materials[s.material];
        var l: vec3<f32>;
        if baked {
            l = shaded_at(i).xyz;
        } else {
            l = indirect(i, s, m, -d);
            let gloss = (m.specular.x + m.specular.y + m.specular.z) * (1.0 / 3.0);
            diffuse += w * vec4<f32>(s.diffuse, gloss * m.roughness);
            specular += w * vec4<f32>(m.specular, gloss);
        }
        radiance += w * vec4<f32>(l, 1.0);
        geometry += w * vec4<f32>(s.normal, h.t);
    }
    textureStore(radiance_sum, px, radiance);
    textureStore(geometry_sum, px, geometry);
    textureStore(diffuse_sum, px, diffuse);
    textureStore(specular_sum, px, specular);
}
