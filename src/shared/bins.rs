//! Twin of `wgsl/shared/bins.wgsl`: the photon binning grid's cell of a point and the box of
//! cells within the search radius, as rows of contiguous cells.

use crate::types::BinParams;
use glam::{UVec2, UVec3, Vec3};

/// Most cells a box spans per axis, less one (`BIN_SPAN` in WGSL): cells are a little larger
/// than R/2, so the 2R-wide box around a point never spans more than 5.
pub const BIN_SPAN: u32 = 4;

/// Entries of a cell list one `bin_rank` invocation compares against per dispatch.
pub const RANK_CHUNK: u32 = 8192;

/// A binned photon's EM weight: the mean of its RGB power (its power's w holds its surface).
pub fn photon_weight(power: [f32; 4]) -> f32 {
    (power[0] + power[1] + power[2]) * (1.0 / 3.0)
}

/// Least cosine between a photon's surface and a splat's normal for it to count
/// (`SURFACE_COS_MIN` in WGSL).
pub const SURFACE_COS_MIN: f32 = 0.5;

pub fn bin_coord(p: Vec3, b: &BinParams) -> UVec3 {
    let top = (UVec3::from(b.dims) - UVec3::ONE).as_vec3();
    ((p - Vec3::from(b.origin)) * b.inv_cell_size)
        .floor()
        .clamp(Vec3::ZERO, top)
        .as_uvec3()
}

pub fn bin_index(c: UVec3, b: &BinParams) -> u32 {
    c.x + b.dims[0] * (c.y + b.dims[1] * c.z)
}

/// The list of point `p`: its cell's `sub³` lists, then its sub-cell within the cell (x
/// fastest). The cell is `bin_coord`'s, so a photon lies in the cell the boxes count it in.
pub fn bin_of(p: Vec3, b: &BinParams) -> u32 {
    let c = bin_coord(p, b);
    let s = b.sub.max(1);
    let within = (p - Vec3::from(b.origin)) * b.inv_cell_size - c.as_vec3();
    let q = (within * s as f32)
        .floor()
        .clamp(Vec3::ZERO, Vec3::splat((s - 1) as f32))
        .as_uvec3();
    bin_index(c, b) * lists_per_cell(b) + q.x + s * (q.y + s * q.z)
}

/// The lists of one cell: `sub³`.
pub fn lists_per_cell(b: &BinParams) -> u32 {
    b.sub.max(1).pow(3)
}

/// Lists of the binned photons.
pub fn list_count(b: &BinParams) -> u32 {
    b.cell_count * lists_per_cell(b)
}

/// Relative margin on a box's reach (`BIN_REACH_MARGIN` in WGSL): a cell a rounding error
/// too far still counts, so rows never depend on the last bit of a distance.
pub const BIN_REACH_MARGIN: f32 = 1.0001;

/// The cells within `r` of a point: a box whose rows along x are trimmed to the cells within
/// reach (see `bin_row`).
#[derive(Clone, Copy, Debug)]
pub struct BinBox {
    pub lo: UVec3,
    pub size: UVec3,
    /// The point in cell units from the grid's origin.
    pub center: Vec3,
    /// (r in cell units)², with the margin.
    pub reach2: f32,
}

pub fn bin_box(c: Vec3, r: f32, b: &BinParams) -> BinBox {
    bin_box_spanning(c, r, b, BIN_SPAN)
}

/// `bin_box` for a ball wider than the bins were sized for: at most `span` + 1 cells per axis.
pub fn bin_box_spanning(c: Vec3, r: f32, b: &BinParams, span: u32) -> BinBox {
    let lo = bin_coord(c - Vec3::splat(r), b);
    let hi = bin_coord(c + Vec3::splat(r), b).min(lo + UVec3::splat(span));
    let reach = r * b.inv_cell_size * BIN_REACH_MARGIN;
    BinBox {
        lo,
        size: hi - lo + UVec3::ONE,
        center: (c - Vec3::from(b.origin)) * b.inv_cell_size,
        reach2: reach * reach,
    }
}

pub fn bin_row_count(b: &BinBox) -> u32 {
    b.size.y * b.size.z
}

/// Distance in cell units from `q` to cell `i` along an axis of `dim` cells; the outer cells
/// reach to infinity, since points outside the grid clamp into them.
pub fn bin_axis_gap(i: u32, q: f32, dim: u32) -> f32 {
    let below = if i == 0 { -1.0 } else { i as f32 - q };
    let above = if i + 1 == dim {
        -1.0
    } else {
        q - (i + 1) as f32
    };
    below.max(above).max(0.0)
}

/// Row `row` of the box untrimmed: the lists [x, y) of all its cells, a superset of
/// `bin_row`'s. One index and no distance: a search whose rows are mostly empty (a flat scan
/// in a box of 9 × 9 rows) tests emptiness here before trimming.
pub fn bin_row_untrimmed(bx: &BinBox, row: u32, b: &BinParams) -> UVec2 {
    let (y, z) = bin_row_cell(bx, row);
    let first = bin_index(UVec3::new(bx.lo.x, y, z), b);
    let per_cell = lists_per_cell(b);
    UVec2::new(first * per_cell, (first + bx.size.x) * per_cell)
}

/// The y and z cell of row `row` of the box (rows run along x, y fastest).
fn bin_row_cell(bx: &BinBox, row: u32) -> (u32, u32) {
    (bx.lo.y + row % bx.size.y, bx.lo.z + row / bx.size.y)
}

/// Row `row` of the box: the lists [x, y) of its cells, trimmed at both ends to the cells
/// within reach (the rest is contiguous: the ball is convex); possibly empty.
pub fn bin_row(bx: &BinBox, row: u32, b: &BinParams) -> UVec2 {
    let (y, z) = bin_row_cell(bx, row);
    let gy = bin_axis_gap(y, bx.center.y, b.dims[1]);
    let gz = bin_axis_gap(z, bx.center.z, b.dims[2]);
    let left = bx.reach2 - gy * gy - gz * gz;
    let within = |x: u32| {
        let g = bin_axis_gap(x, bx.center.x, b.dims[0]);
        g * g <= left
    };
    let mut x0 = bx.lo.x;
    let mut x1 = bx.lo.x + bx.size.x;
    while x0 < x1 && !within(x0) {
        x0 += 1;
    }
    while x1 > x0 && !within(x1 - 1) {
        x1 -= 1;
    }
    let all = bin_row_untrimmed(bx, row, b);
    let per_cell = lists_per_cell(b);
    UVec2::new(
        all.x + (x0 - bx.lo.x) * per_cell,
        all.x + (x1 - bx.lo.x) * per_cell,
    )
}
