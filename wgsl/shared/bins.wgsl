// #import types

// The photon binning grid: cells of at least the search radius R, so the photons within R of
// a point lie in at most 3 cells per axis, and the cells of one x-run are contiguous in the
// binned list. Twin: src/shared/bins.rs.

// Entries of a cell list one bin_rank invocation compares against per dispatch.
const RANK_CHUNK: u32 = 8192u;

// A binned photon's power is (RGB, surface code): its EM weight, the mean of its RGB power
// (thesis section 3.5), is computed where it is read.
fn photon_weight(power: vec3<f32>) -> f32 {
    return (power.x + power.y + power.z) * (1.0 / 3.0);
}

// A photon counts for a splat only if it landed on a surface facing the same way, within 60
// degrees (surface_decode of its power's w against the splat's normal): near a corner, the
// perpendicular surface's photons lie within the slab too, and would count for both.
const SURFACE_COS_MIN: f32 = 0.5;

fn bin_coord(p: vec3<f32>, b: BinParams) -> vec3<u32> {
    let top = vec3<f32>(b.dims - vec3<u32>(1u));
    return vec3<u32>(clamp(floor((p - b.origin) * b.inv_cell_size), vec3<f32>(0.0), top));
}

fn bin_index(c: vec3<u32>, b: BinParams) -> u32 {
    return c.x + b.dims.x * (c.y + b.dims.y * c.z);
}

// The list of point `p`: its cell's sub^3 lists, then its sub-cell within the cell (x
// fastest). The cell is bin_coord's, so a photon lies in the cell the boxes count it in.
fn bin_of(p: vec3<f32>, b: BinParams) -> u32 {
    let c = bin_coord(p, b);
    let s = max(b.sub, 1u);
    let within = (p - b.origin) * b.inv_cell_size - vec3<f32>(c);
    let q = vec3<u32>(clamp(floor(within * f32(s)), vec3<f32>(0.0), vec3<f32>(f32(s - 1u))));
    return bin_index(c, b) * lists_per_cell(b) + q.x + s * (q.y + s * q.z);
}

// The lists of one cell: sub^3.
fn lists_per_cell(b: BinParams) -> u32 {
    let s = max(b.sub, 1u);
    return s * s * s;
}

// Most cells a box spans per axis, less one. The host makes cells a little larger than R/2,
// so the 2R-wide box around a point never spans more than 5 cells, rounding included.
const BIN_SPAN: u32 = 4u;

// The cells within `r` of `c`: the box of cells around it, whose rows along x are contiguous
// runs of the binned list, each trimmed to the cells that reach within `r` of `c` (a sphere
// fills half its box, so this halves the photons tested). Row k covers the lists
// [bin_row(box, k).x, bin_row(box, k).y) of its cells (sub^3 each), possibly none.
struct BinBox {
    lo: vec3<u32>,
    size: vec3<u32>,
    // `c` in cell units from the grid's origin, and (r in cell units)^2 with a margin.
    center: vec3<f32>,
    reach2: f32,
}

// Relative margin on the reach: a cell a rounding error too far still counts (the photons'
// own distance test is exact), so rows never depend on the last bit of a distance.
const BIN_REACH_MARGIN: f32 = 1.0001;

fn bin_box(c: vec3<f32>, r: f32, b: BinParams) -> BinBox {
    return bin_box_spanning(c, r, b, BIN_SPAN);
}

// bin_box for a ball wider than the bins were sized for: at most span + 1 cells per axis.
fn bin_box_spanning(c: vec3<f32>, r: f32, b: BinParams, span: u32) -> BinBox {
    var box: BinBox;
    box.lo = bin_coord(c - vec3<f32>(r), b);
    let hi = min(bin_coord(c + vec3<f32>(r), b), box.lo + vec3<u32>(span));
    box.size = hi - box.lo + vec3<u32>(1u);
    box.center = (c - b.origin) * b.inv_cell_size;
    let reach = r * b.inv_cell_size * BIN_REACH_MARGIN;
    box.reach2 = reach * reach;
    return box;
}

fn bin_row_count(box: BinBox) -> u32 {
    return box.size.y * box.size.z;
}

// Distance in cell units from `q` to cell `i` along one axis of `dim` cells; the outer cells
// reach to infinity, since points outside the grid clamp into them.
fn bin_axis_gap(i: u32, q: f32, dim: u32) -> f32 {
    let below = select(f32(i) - q, -1.0, i == 0u);
    let above = select(q - f32(i + 1u), -1.0, i + 1u == dim);
    return max(max(below, above), 0.0);
}

// Row `row` of the box untrimmed: the lists of all its cells, a superset of bin_row's, with no
// distance (a search whose rows are mostly empty tests emptiness here before trimming).
fn bin_row_untrimmed(box: BinBox, row: u32, b: BinParams) -> vec2<u32> {
    let yz = bin_row_cell(box, row);
    let first = bin_index(vec3<u32>(box.lo.x, yz.x, yz.y), b);
    let per_cell = lists_per_cell(b);
    return vec2<u32>(first * per_cell, (first + box.size.x) * per_cell);
}

// The y and z cell of row `row` of the box (rows run along x, y fastest).
fn bin_row_cell(box: BinBox, row: u32) -> vec2<u32> {
    return vec2<u32>(box.lo.y + row % box.size.y, box.lo.z + row / box.size.y);
}

fn bin_row(box: BinBox, row: u32, b: BinParams) -> vec2<u32> {
    let yz = bin_row_cell(box, row);
    let gy = bin_axis_gap(yz.x, box.center.y, b.dims.y);
    let gz = bin_axis_gap(yz.y, box.center.z, b.dims.z);
    let left = box.reach2 - gy * gy - gz * gz;
    var x0 = box.lo.x;
    var x1 = box.lo.x + box.size.x;
    // Trim cells out of reach from both ends; the rest is contiguous (the ball is convex).
    for (; x0 < x1; x0++) {
        let g = bin_axis_gap(x0, box.center.x, b.dims.x);
        if g * g <= left {
            break;
        }
    }
    for (; x1 > x0; x1--) {
        let g = bin_axis_gap(x1 - 1u, box.center.x, b.dims.x);
        if g * g <= left {
            break;
        }
    }
    let all = bin_row_untrimmed(box, row, b);
    let per_cell = lists_per_cell(b);
    return vec2<u32>(all.x + (x0 - box.lo.x) * per_cell, all.x + (x1 - box.lo.x) * per_cell);
}
