// #import types

// The cells touched by a splat's disk: the disk's axis-aligned bounding box (half extent along
// axis i is r * sqrt(1 - n_i^2)), clamped to the grid. Mirrored by `grid::disk_cell_range`.
struct CellRange {
    lo: vec3<u32>,
    hi: vec3<u32>,
}

fn disk_cell_range(s: Splat, g: GridParams) -> CellRange {
    let n2 = s.normal * s.normal;
    let half = s.radius * sqrt(max(vec3<f32>(0.0), vec3<f32>(1.0) - n2));
    let inv = g.inv_cell_size;
    let lo_f = floor((s.center - half - g.origin) * inv);
    let hi_f = floor((s.center + half - g.origin) * inv);
    let top = vec3<f32>(g.dims - vec3<u32>(1u));
    var r: CellRange;
    r.lo = vec3<u32>(clamp(lo_f, vec3<f32>(0.0), top));
    r.hi = vec3<u32>(clamp(hi_f, vec3<f32>(0.0), top));
    return r;
}

// The cell that holds point p, unclamped: outside the grid where p is. Mirrored by
// `grid::point_cell`.
fn point_cell(p: vec3<f32>, g: GridParams) -> vec3<i32> {
    return vec3<i32>(floor((p - g.origin) * g.inv_cell_size));
}

fn cell_index(c: vec3<u32>, g: GridParams) -> u32 {
    return c.x + g.dims.x * (c.y + g.dims.y * c.z);
}

// The distance field saturates here (in cells): a ray in an empty cell at distance d from the
// nearest listed cell may skip the (2d - 1)^3 empty cells around it in one step.
const DIST_CAP: u32 = 16u;

// A listed cell's facing cone (grid_cone.wgsl), in the upper 24 bits of its distance word (the
// distance, 0 for a listed cell, in the low 8): an axis a, octahedral at 8 bits an axis, and at
// bits 24-31 `open`, with 1 - open / CONE_STEPS >= sin(theta), theta the widest angle between
// a and a listed disk's normal. A ray with dot(a, d) > 1 - open / CONE_STEPS + CONE_MARGIN
// meets every disk of the cell from behind (dot(n, d) > 0): disks are one-sided, so it can hit
// none of them. An empty cone (open 0) turns no ray away. Mirrored in src/grid.rs.
const DIST_MASK: u32 = 0xffu;
const CONE_STEPS: f32 = 255.0;
const CONE_MARGIN: f32 = 1e-3;

fn cone_sign(p: vec2<f32>) -> vec2<f32> {
    return select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
}

// The axis's 16 bits (at bits 8-23 of the word) for a nonzero direction m.
fn cone_axis_encode(m: vec3<f32>) -> u32 {
    let p = m.xy / (abs(m.x) + abs(m.y) + abs(m.z));
    var q = p;
    if m.z < 0.0 {
        q = (vec2<f32>(1.0) - abs(p.yx)) * cone_sign(p);
    }
    let u = round((clamp(q, vec2<f32>(-1.0), vec2<f32>(1.0)) * 0.5 + 0.5) * CONE_STEPS);
    return (u32(u.x) << 8u) | (u32(u.y) << 16u);
}

fn cone_axis(word: u32) -> vec3<f32> {
    let u = vec2<f32>(f32((word >> 8u) & 0xffu), f32((word >> 16u) & 0xffu));
    let p = u * (2.0 / CONE_STEPS) - 1.0;
    let z = 1.0 - abs(p.x) - abs(p.y);
    let fold = max(-z, 0.0);
    return normalize(vec3<f32>(p - fold * cone_sign(p), z));
}

// Whether every disk of the listed cell whose distance word is `word` faces away from d.
fn cone_faces_away(word: u32, d: vec3<f32>) -> bool {
    let open = word >> 24u;
    return open != 0u && dot(cone_axis(word), d) > 1.0 - f32(open) / CONE_STEPS + CONE_MARGIN;
}
