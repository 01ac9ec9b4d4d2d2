//! Twin of `wgsl/shared/bins.wgsl`: the photon binning grid's cell of a point and the box of
//! cells within the search radius, as rows of contiguous cells.

use crate::types::BinParams;
use glam::{UVec2, UVec3, Vec3};

/// Most cells a box spans per axis, less one (`BIN_SPAN` in WGSL): cells are a little larger
/// than R/2, so the 2R-wide box around a point never spans more than 5.
pub const BIN_SPAN: u32 = 4;

/// Entries of a cell list one `bin_rank` invocation compares against per dispatch.
pub const RANK_CHUNK: u32 = 8192;

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

pub fn bin_of(p: Vec3, b: &BinParams) -> u32 {
    bin_index(bin_coord(p, b), b)
}

#[derive(Clone, Copy, Debug)]
pub struct BinBox {
    pub lo: UVec3,
    pub size: UVec3,
}

pub fn bin_box(c: Vec3, r: f32, b: &BinParams) -> BinBox {
    let lo = bin_coord(c - Vec3::splat(r), b);
    let hi = bin_coord(c + Vec3::splat(r), b).min(lo + UVec3::splat(BIN_SPAN));
    BinBox {
        lo,
        size: hi - lo + UVec3::ONE,
    }
}

pub fn bin_row_count(b: &BinBox) -> u32 {
    b.size.y * b.size.z
}

pub fn bin_row(bx: &BinBox, row: u32, b: &BinParams) -> UVec2 {
    let y = bx.lo.y + row % bx.size.y;
    let z = bx.lo.z + row / bx.size.y;
    let first = bin_index(UVec3::new(bx.lo.x, y, z), b);
    UVec2::new(first, first + bx.size.x)
}
