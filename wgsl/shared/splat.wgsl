// Surface splatting (docs/design.md section 8): the triangle a splat is drawn as, a pixel's view
// ray, the ray-disk hit with its radial weight, the reversed depth, and a lobe's width in the
// form the shading takes (section 7). Twin: src/shared/splat.rs.
//
// Depth is reversed, near / z (1 at the near plane, towards 0 at infinity): a float's
// relative precision then holds at every distance, and there is no far plane to clip at.
// The rasterizer's interpolated depth of a splat's triangle is the depth of the disk's plane
// at each pixel, since near / z is affine in screen space across a plane.

// #import types
// #import sampling
// #import ward
// #import lobes
// #import octahedral

// The radial kernel exp(-KERNEL_SHARPNESS q) of q = d^2 / r^2: 1 at the centre, e^-2 at
// the rim, so a pixel that only rims cover still gets a well-defined normalised value.
const KERNEL_SHARPNESS: f32 = 2.0;

// A fragment blends into a pixel only where its splat's normal is within 60 degrees of the
// normal of the pixel's nearest splat (the visibility pass's second output): the surface the
// pixel sees. Without it, disks that overhang a face's edge blended the light of the face
// across the edge into its neighbour (+4.6 % direct light on the small block of the default
// scene, docs/measurements.md). Twin: src/shared/splat.rs.
const FRONT_COS_MIN: f32 = 0.5;

fn same_surface(front: u32, n: vec3<f32>) -> bool {
    return dot(oct_decode(front), n) >= FRONT_COS_MIN;
}

// Shadow rays spend at most this many grid steps and disk tests (see trace.wgsl).
const SHADOW_RAY_BUDGET: u32 = 16384u;

// Light terms a frame shows (ShadeParams.show): direct diffuse and specular (shadow rays),
// indirect diffuse (total irradiance) and specular (the lobes).
const SHOW_DIRECT_DIFFUSE: u32 = 1u;
const SHOW_DIRECT_SPECULAR: u32 = 2u;
const SHOW_INDIRECT_DIFFUSE: u32 = 4u;
const SHOW_INDIRECT_SPECULAR: u32 = 8u;
const SHOW_ALL: u32 = 15u;

// What the attribute pass blends into its four targets (and the reference pass writes with
// w = 1): weighted sums, w the kernel weight, rho_s the mean specular albedo.
struct Attributes {
    // (w L_indirect, w)
    @location(0) radiance: vec4<f32>,
    // (w n, w t): normal and distance along the view ray
    @location(1) geometry: vec4<f32>,
    // (w rho_d, w rho_s alpha): the roughness is blended by specular weight
    @location(2) diffuse: vec4<f32>,
    // (w rho_s RGB, w rho_s)
    @location(3) specular: vec4<f32>,
}

// What the raster passes' vertices pass on: the splat's index, and what its fragments test
// and blend, flat. A fragment then loads nothing but the clip rows of the few disks a surface's
// edge cuts: reading its splat from the (paged) splat array cost the baked frames 13 % of their
// time at 1280x720 (docs/measurements.md).
struct SplatVertex {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) splat: u32,
    @location(1) @interpolate(flat) center: vec3<f32>,
    @location(2) @interpolate(flat) radius: f32,
    @location(3) @interpolate(flat) normal: vec3<f32>,
    // The radiance splat_shade gave the splat (the baked attribute pass), else 0.
    @location(4) @interpolate(flat) radiance: vec3<f32>,
    // Which rows of its surface's clip cut the disk, and the surface (drawn_clip.wgsl's
    // clipped_vertex); 0 where none does.
    @location(5) @interpolate(flat) clip: u32,
}

// Corners of the splat's primitive: the equilateral triangle circumscribing its disk
// (inradius 1, in units of the radius). One triangle, not a two-triangle quad: it has 30 %
// more area, but a software rasterizer such as llvmpipe spends more per triangle than per
// fragment on primitives a few pixels wide, and the raster passes ran 20 % faster.
const SPLAT_CORNERS: u32 = 3u;
const SQRT_3: f32 = 1.7320508;

// Splats drawn by one instance of the raster passes' draw: SPLATS_PER_INSTANCE triangles of
// SPLAT_CORNERS vertices each, the last instance's surplus hidden (surplus_vertex). llvmpipe
// shades the vertices of an instance together and pays a fixed cost per instance, so one
// triangle an instance left most of its SIMD lanes idle: batches of 32 made the bunny's
// 512^2 frame 15 % faster (89 -> 76 ms) and the full dragon's 17 % (306-318 -> 258 ms);
// batches above a few hundred were slower again (docs/measurements.md).
const SPLATS_PER_INSTANCE: u32 = 32u;

// Level of detail of moving frames (Camera.lod, in pixels): neighbouring splats are drawn
// merged into one disk wherever that disk projects within so many pixels in radius. The merge
// tree (SplatLod, src/lod.rs) has LOD_MAX_LEVEL levels above the splats; splat_select draws each
// splat at the coarsest of its levels that fits, or not at all where its parent's may fit, and
// writes the radius for the raster passes. Twin: src/shared/splat.rs.
const LOD_MAX_LEVEL: u32 = 5u;
// Whether the visibility pass draws splat_list's list (frames of baked direct light) or every
// splat (frames of shadow rays); the host builds a pipeline of each, so that neither runs the
// other's branch (llvmpipe runs both sides of a branch on a uniform).
override LISTED: bool = true;

// What a ray that meets splat s brings back per unit of its irradiance, times pi (final
// gathering, glossy rays): its diffuse albedo, and a glossy disk's specular albedo as if it
// spread that light evenly (its lobes, which would say where, are not at hand there).
fn hit_albedo(s: Splat, m: Material) -> vec3<f32> {
    return s.diffuse + m.specular;
}

// Splat s at the radius splat_select chose for it (its own, or its merged disk's).
fn drawn_splat(s: Splat, radius: f32) -> Splat {
    var out = s;
    out.radius = radius;
    return out;
}

// Whether a disk of radius extent at depth projects within the level of detail. Products, no
// quotient, so that the device and the mirror decide alike.
fn lod_fits(cam: Camera, extent: f32, depth: f32) -> bool {
    return depth > cam.near && extent * cam.size.y <= cam.lod * 2.0 * cam.tan_y * depth;
}

// The radius splat s is drawn with this frame at its level (lod_level): that level's disk, its
// own radius with the level of detail off, or 0 where its parent's disk may project within it
// too (and then covers it).
fn lod_radius(cam: Camera, s: Splat, lod: SplatLod, level: u32) -> f32 {
    if !(cam.lod > 0.0) {
        return s.radius;
    }
    // The parent lies at least parent_gap nearer: if its disk fits even there, it fits.
    let z = dot(s.center - cam.eye, cam.forward);
    if level == lod.top && lod.parent_extent > 0.0
        && lod_fits(cam, lod.parent_extent, z - lod.parent_gap) {
        return 0.0;
    }
    if level == 0u {
        return s.radius;
    }
    return lod.extent[level - 1u];
}

// The level of the merge tree splat s is drawn at this frame: the coarsest of its levels whose
// disk projects within cam.lod pixels; 0 (its own disk) with the level of detail off.
fn lod_level(cam: Camera, s: Splat, lod: SplatLod) -> u32 {
    if !(cam.lod > 0.0) {
        return 0u;
    }
    let z = dot(s.center - cam.eye, cam.forward);
    var level = 0u;
    for (var k = 1u; k <= min(lod.top, LOD_MAX_LEVEL); k++) {
        if lod_fits(cam, lod.extent[k - 1u], z) {
            level = k;
        }
    }
    return level;
}

// The unit of the spread in a level's word of a splat's merged normals (LodSpread in
// src/types.rs: a word a level 1 to 5, its lowest byte the spread, its upper 24 bits the mean
// direction, the octahedral code's two snorm16 cut to 12 bits): a byte of 255 is this much Ward
// roughness.
const LOD_SPREAD_SCALE: f32 = 255.0;

// The Ward roughness a glossy splat of roughness alpha is shaded with where it is drawn at the
// level whose word is `word` (0 at level 0): its own, widened by the spread of the normals its
// disk stands for there (src/lod.rs, normal_spread), as the slopes' variances add.
fn lod_roughness(alpha: f32, word: u32) -> f32 {
    let widen = f32(word & 0xffu) / LOD_SPREAD_SCALE;
    return sqrt(alpha * alpha + widen * widen);
}

// The normal a glossy splat of normal `own` is shaded with at the level whose word is `word`: the
// mean direction of the normals its disk stands for, where they spread; else its own.
fn lod_normal(word: u32, own: vec3<f32>) -> vec3<f32> {
    if (word & 0xffu) == 0u {
        return own;
    }
    let x = ((word >> 8u) & 0xfffu) << 4u;
    let y = (word >> 20u) << 4u;
    return oct_decode(x | (y << 16u));
}

// The radius splat s is drawn with in a frame of baked direct light (splat_select) at its
// level (lod_level): that level's disk where the level of detail is on, 0 where it faces away,
// lies outside the view or its parent's disk stands in for it.
fn drawn_radius(cam: Camera, s_in: Splat, lod: SplatLod, level: u32) -> f32 {
    var s = s_in;
    if cam.lod > 0.0 {
        s.radius = lod_radius(cam, s, lod, level);
    }
    let shown = faces_camera(s, cam.eye) && s.radius > 0.0 && in_view(cam, s);
    return select(0.0, s.radius, shown);
}

// Levels of the merge tree, the splats' own included.
const LOD_LEVELS: u32 = 6u;
// Children a node of the chunks' hierarchy holds (lod::NODE_FANOUT).
const NODE_FANOUT: u32 = 16u;

// The levels of chunk ch whose splats a frame visits (bit t: those whose top level is t), or of
// a node of chunks whose subtree's splats it may visit: not levels it holds none of, not
// those that lie outside the view, and with the level of detail on, not those whose parents'
// disks project within it even at the chunk's nearest depth, and their own top-level disks too
// (then lod_radius gives every one of them 0). Conservative: a splat drawn_radius draws is
// always visited (in_view's test holds for a sphere that holds its splats' with the margin its
// gradient asks for, a small slack for rounding). Twin: shared::splat::chunk_visits.
fn chunk_visits(cam: Camera, ch: SplatChunk) -> u32 {
    let c = ch.center - cam.eye;
    let z = dot(c, cam.forward);
    let d = ch.centre_reach;
    let nearest = z - d - 1e-4 * (abs(z) + d);
    let ax = cam.tan_x * (1.0 + 2.0 / cam.size.x);
    let ay = cam.tan_y * (1.0 + 2.0 / cam.size.y);
    var visits = 0u;
    for (var t = 0u; t < LOD_LEVELS; t++) {
        // A level it holds no splat of is never visited, so that a node whose subtree holds
        // none rules it out for all of it.
        if ch.ends[t] == select(0u, ch.ends[max(t, 1u) - 1u], t > 0u) {
            continue;
        }
        // Level t's splats are drawn no wider than their disk at level t.
        let r = 2.0 * ch.level_fit[t];
        let slack = 1e-4 * (abs(z) + d + r);
        let shown = z + d + slack >= cam.near - r
            && abs(dot(c, cam.right)) - ax * z
                <= r * sqrt(1.0 + cam.tan_x * cam.tan_x) + d * sqrt(1.0 + ax * ax) + slack
            && abs(dot(c, cam.up)) - ay * z
                <= r * sqrt(1.0 + cam.tan_y * cam.tan_y) + d * sqrt(1.0 + ay * ay) + slack;
        let covered = cam.lod > 0.0
            && ch.parent_fit[t] > 0.0
            && (t == 0u || lod_fits(cam, ch.level_fit[t], nearest))
            && lod_fits(cam, ch.parent_fit[t], nearest - ch.parent_gap[t]);
        if shown && !covered {
            visits |= 1u << t;
        }
    }
    return visits;
}

// Corner `i` (0..2) of the triangle in the splat's plane that bounds its disk: its
// projection bounds the projected disk, even where clipping cuts it.
fn splat_corner(s: Splat, i: u32) -> vec3<f32> {
    let f = frame_of(s.normal);
    let x = select(select(SQRT_3, -SQRT_3, i == 1u), 0.0, i == 0u);
    let y = select(-1.0, 2.0, i == 0u);
    return s.center + s.radius * (x * f.t + y * f.b);
}

// Disks are one-sided, as for tracing: only their front shows.
fn faces_camera(s: Splat, eye: vec3<f32>) -> bool {
    return dot(s.normal, eye - s.center) > 0.0;
}

// Whether splat s may cover a pixel of the view: its disk's bounding sphere (the triangle's,
// radius 2r, to be safe) reaches past no side of the view frustum widened by a pixel (the
// jitter moves the image by at most half a pixel) and not wholly behind the near plane.
fn in_view(cam: Camera, s: Splat) -> bool {
    let v = s.center - cam.eye;
    let r = 2.0 * s.radius;
    let z = dot(v, cam.forward);
    let x_edge = cam.tan_x * (1.0 + 2.0 / cam.size.x) * z;
    let y_edge = cam.tan_y * (1.0 + 2.0 / cam.size.y) * z;
    return z >= cam.near - r
        && abs(dot(v, cam.right)) - x_edge <= r * sqrt(1.0 + cam.tan_x * cam.tan_x)
        && abs(dot(v, cam.up)) - y_edge <= r * sqrt(1.0 + cam.tan_y * cam.tan_y);
}

fn clip_position(cam: Camera, p: vec3<f32>) -> vec4<f32> {
    let v = p - cam.eye;
    let z = dot(v, cam.forward);
    // The jitter moves the image under the pixel grid, so that the pixel centre the
    // rasterizer samples lies on the jittered ray `pixel_ray` casts.
    let shift = cam.jitter * 2.0 / cam.size;
    return vec4<f32>(dot(v, cam.right) / cam.tan_x - shift.x * z,
                     dot(v, cam.up) / cam.tan_y + shift.y * z, cam.near, z);
}

// A vertex outside the view: a triangle of three of them costs no fragments.
const OUTSIDE: vec4<f32> = vec4<f32>(2.0, 2.0, 0.5, 1.0);

// The vertex of both raster passes: corner `corner` of splat `i`'s triangle (s at the radius
// it is drawn with); a back-facing splat, or one the level of detail leaves out (radius 0),
// puts all its corners on one point outside the view, so it costs no fragments.
fn splat_vertex(cam: Camera, s: Splat, i: u32, corner: u32) -> SplatVertex {
    var out: SplatVertex;
    out.splat = i;
    out.position = select(OUTSIDE, clip_position(cam, splat_corner(s, corner)),
                          faces_camera(s, cam.eye) && s.radius > 0.0);
    out.center = s.center;
    out.normal = s.normal;
    out.radius = s.radius;
    out.radiance = vec3<f32>(0.0);
    out.clip = 0u;
    return out;
}

// The splat that vertex `vertex` of draw instance `instance` belongs to (SPLATS_PER_INSTANCE),
// and the corner it is of that splat's triangle.
fn instance_splat(vertex: u32, instance: u32) -> u32 {
    return instance * SPLATS_PER_INSTANCE + vertex / SPLAT_CORNERS;
}

fn instance_corner(vertex: u32) -> u32 {
    return vertex % SPLAT_CORNERS;
}

// The vertex of the last instance's surplus splats, past the end of the array.
fn surplus_vertex(i: u32) -> SplatVertex {
    var out: SplatVertex;
    out.splat = i;
    out.position = OUTSIDE;
    return out;
}

// The splat of a fragment, from its vertex's flat values (all a ray-disk hit needs).
fn vertex_splat(v: SplatVertex) -> Splat {
    var s: Splat;
    s.center = v.center;
    s.radius = v.radius;
    s.normal = v.normal;
    return s;
}

fn view_depth(cam: Camera, z: f32) -> f32 {
    return cam.near / z;
}

// The unit view ray through a point of the image (pixel centres at +0.5, rows from the top),
// moved by the frame's sub-pixel jitter.
fn pixel_ray(cam: Camera, pixel: vec2<f32>) -> vec3<f32> {
    let at = pixel + cam.jitter;
    let ndc = vec2<f32>(at.x / cam.size.x * 2.0 - 1.0, 1.0 - at.y / cam.size.y * 2.0);
    return normalize(cam.forward + (ndc.x * cam.tan_x) * cam.right + (ndc.y * cam.tan_y) * cam.up);
}

// Where world point p lies in the image of `cam` without its jitter: the point of the image
// in pixels (as pixel_ray takes it: pixel_ray(cam, xy - cam.jitter) points at p) and the view
// depth z (z <= 0: at or behind the eye, and xy means nothing).
fn project_point(cam: Camera, p: vec3<f32>) -> vec3<f32> {
    let v = p - cam.eye;
    let z = dot(v, cam.forward);
    let ndc = vec2<f32>(dot(v, cam.right) / cam.tan_x, dot(v, cam.up) / cam.tan_y) / z;
    return vec3<f32>((ndc.x * 0.5 + 0.5) * cam.size.x, (0.5 - ndc.y * 0.5) * cam.size.y, z);
}

// Where ray (o, d) meets a splat's plane: t, and q = |hit - centre|^2 / r^2 (inside: q <= 1;
// NaN or above 1 for a ray along the plane).
struct SplatHit {
    t: f32,
    q: f32,
}

fn splat_hit(s: Splat, o: vec3<f32>, d: vec3<f32>) -> SplatHit {
    var h: SplatHit;
    h.t = dot(s.normal, s.center - o) / dot(s.normal, d);
    let v = o + h.t * d - s.center;
    h.q = dot(v, v) / (s.radius * s.radius);
    return h;
}

// A fragment of the splat: inside its disk and in front of the near plane.
fn covers(cam: Camera, h: SplatHit, d: vec3<f32>) -> bool {
    return h.q <= 1.0 && h.t * dot(d, cam.forward) >= cam.near;
}

fn splat_weight(q: f32) -> f32 {
    return exp(-KERNEL_SHARPNESS * q);
}

// beta^2 of a lobe in the thesis's exp(-tan^2 / beta^2) form: Ward-like lobes store 1 / beta^2;
// a vMF lobe exp(k (cos - 1)) ~ exp(-k theta^2 / 2) matches the Ward-like form's
// exp(-(theta / 2)^2 / beta^2) (its half-vector angle is half the deviation) at 1 / (2 k).
fn lobe_beta2(family: u32, sharpness: f32) -> f32 {
    return select(0.5, 1.0, family == FAMILY_WARD) / sharpness;
}

// The compute splatter's tiles: TILE x TILE pixels, one workgroup each.
const TILE: u32 = 8u;

// The tiles whose pixel centres splat s's triangle may cover, as (x0, y0, x1, y1) inclusive;
// x0 > x1 when none (a back-facing splat, or one wholly behind the near plane or outside the
// image). A triangle with a corner behind the near plane projects without bound: all tiles.
fn tile_rect(cam: Camera, s: Splat, tiles_x: u32, tiles_y: u32) -> vec4<u32> {
    let none = vec4<u32>(1u, 0u, 0u, 0u);
    if !faces_camera(s, cam.eye) {
        return none;
    }
    var lo = vec2<f32>(3.0e38);
    var hi = vec2<f32>(-3.0e38);
    var behind = 0u;
    for (var k = 0u; k < SPLAT_CORNERS; k++) {
        let c = clip_position(cam, splat_corner(s, k));
        if !(c.w >= cam.near) {
            behind += 1u;
            continue;
        }
        let ndc = c.xy / c.w;
        let p = vec2<f32>((ndc.x * 0.5 + 0.5) * cam.size.x, (0.5 - ndc.y * 0.5) * cam.size.y);
        lo = min(lo, p);
        hi = max(hi, p);
    }
    if behind == SPLAT_CORNERS {
        return none;
    }
    let last = vec2<f32>(f32(tiles_x * TILE) - 1.0, f32(tiles_y * TILE) - 1.0);
    if behind > 0u {
        lo = vec2<f32>(0.0);
        hi = last + 0.5;
    }
    // Pixels whose centre p + 0.5 lies in [lo, hi], with a margin for rounding.
    let first = max(ceil(lo - 0.5 - 1e-3), vec2<f32>(0.0));
    let end = min(floor(hi - 0.5 + 1e-3), last);
    if first.x > end.x || first.y > end.y {
        return none;
    }
    return vec4<u32>(vec2<u32>(first) / TILE, vec2<u32>(end) / TILE);
}
