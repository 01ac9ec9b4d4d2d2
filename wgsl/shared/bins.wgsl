// #import types

// The photon binning grid: cells of at least the search radius R, so the photons within R of
// a point lie in at most 3 cells per axis, and the cells of one x-run are contiguous in the
// binned list. Twin: src/shared/bins.rs.

// Entries of a cell list one bin_rank invocation compares against per dispatch.
const RANK_CHUNK: u32 = 8192u;

fn bin_coord(p: vec3<f32>, b: BinParams) -> vec3<u32> {
    let top = vec3<f32>(b.dims - vec3<u32>(1u));
    return vec3<u32>(clamp(floor((p - b.origin) * b.inv_cell_size), vec3<f32>(0.0), top));
}

fn bin_index(c: vec3<u32>, b: BinParams) -> u32 {
    return c.x + b.dims.x * (c.y + b.dims.y * c.z);
}

fn bin_of(p: vec3<f32>, b: BinParams) -> u32 {
    return bin_index(bin_coord(p, b), b);
}

// Most cells a box spans per axis, less one. The host makes cells a little larger than R/2,
// so the 2R-wide box around a point never spans more than 5 cells, rounding included.
const BIN_SPAN: u32 = 4u;

// The cells within `r` of `c`. Its rows along x are contiguous
// runs of the binned list: row k covers cells [bin_row(box, k).x, bin_row(box, k).y).
struct BinBox {
    lo: vec3<u32>,
    size: vec3<u32>,
}

fn bin_box(c: vec3<f32>, r: f32, b: BinParams) -> BinBox {
    var box: BinBox;
    box.lo = bin_coord(c - vec3<f32>(r), b);
    let hi = min(bin_coord(c + vec3<f32>(r), b), box.lo + vec3<u32>(BIN_SPAN));
    box.size = hi - box.lo + vec3<u32>(1u);
    return box;
}

fn bin_row_count(box: BinBox) -> u32 {
    return box.size.y * box.size.z;
}

fn bin_row(box: BinBox, row: u32, b: BinParams) -> vec2<u32> {
    let y = box.lo.y + row % box.size.y;
    let z = box.lo.z + row / box.size.y;
    let first = bin_index(vec3<u32>(box.lo.x, y, z), b);
    return vec2<u32>(first, first + box.size.x);
}
