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
