//! The splat grid's build: count, scan, scatter, rank, then the distance field and the
//! facing cones.

use crate::error::{Error, Result};
use crate::grid::SplatGrid;
use crate::grid::check_cell_len;
use crate::shaders::Stage;
use crate::types::{DistanceParams, GridParams};

use super::{Executor, exclusive_scan, groups};

/// A splat grid where it was built.
pub struct BuiltGrid<B> {
    /// The grid's settings, with the entry count the build found.
    pub params: GridParams,
    pub params_buf: B,
    /// `cell_count + 1` offsets into `cell_splats`.
    pub cell_start: B,
    pub cell_splats: B,
    /// Distance field for empty-space skipping (see `SplatGrid::cell_dist`).
    pub cell_dist: B,
}

impl<B> BuiltGrid<B> {
    /// The grid in host memory.
    pub fn read_back<E: Executor<Buffer = B>>(&self, ex: &mut E) -> Result<SplatGrid> {
        let cells = self.params.cell_count as usize;
        Ok(SplatGrid {
            params: self.params,
            cell_start: ex.read(&self.cell_start, cells + 1)?,
            cell_splats: ex.read(&self.cell_splats, self.params.entry_count as usize)?,
            cell_dist: ex.read(&self.cell_dist, cells)?,
        })
    }
}

/// The grid build: count → exclusive scan → (split: the entry total sizes the list, the
/// longest cell is checked) → scatter → rank → the distance field's passes x, y, z → the
/// listed cells' facing cones.
pub fn build_grid<E: Executor>(
    ex: &mut E,
    params: &GridParams,
    splats: &E::Buffer,
) -> Result<BuiltGrid<E::Buffer>> {
    let params_buf = ex.uniform("grid params", params)?;
    let cells = params.cell_count as u64;
    let cell_start = ex.zeroed("cell start", (cells + 1) * 4)?;
    let max_cell_len = ex.zeroed("grid max cell length", 4)?;
    let splat_groups = groups(Stage::GridCount, params.splat_count)?;
    let bindings = [&params_buf, splats, &cell_start, &max_cell_len];
    ex.dispatch(Stage::GridCount, &bindings, splat_groups)?;
    exclusive_scan(ex, &cell_start, params.cell_count + 1)?;
    // stats = [entry total (last scan value), longest cell list]
    let stats = ex.zeroed("grid stats", 8)?;
    ex.copy(&cell_start, cells * 4, &stats, 0, 4)?;
    ex.copy(&max_cell_len, 0, &stats, 4, 4)?;
    let (entries, max_cell_len) = match ex.read::<u32>(&stats, 2)?[..] {
        [e, m] => (e, m),
        _ => return Err(Error::Gpu("grid stats readback was short".into())),
    };
    check_cell_len(max_cell_len)?;

    let params = GridParams {
        entry_count: entries,
        ..*params
    };
    let params_buf = ex.uniform("grid params", &params)?;
    let bytes = entries as u64 * 4;
    let cursor = ex.zeroed("cell cursor", cells * 4)?;
    let scratch_splats = ex.zeroed("scratch splats", bytes)?;
    let scratch_cells = ex.zeroed("scratch cells", bytes)?;
    let cell_splats = ex.zeroed("cell splats", bytes)?;
    let bindings = [
        &params_buf,
        splats,
        &cell_start,
        &cursor,
        &scratch_splats,
        &scratch_cells,
    ];
    ex.dispatch(
        Stage::GridScatter,
        &bindings,
        groups(Stage::GridScatter, params.splat_count)?,
    )?;
    let bindings = [
        &params_buf,
        &cell_start,
        &scratch_splats,
        &scratch_cells,
        &cell_splats,
    ];
    ex.dispatch(
        Stage::GridRank,
        &bindings,
        groups(Stage::GridRank, entries)?,
    )?;
    let cell_dist = distance_field(ex, &params_buf, &params, &cell_start)?;
    let bindings = [&params_buf, splats, &cell_start, &cell_splats, &cell_dist];
    ex.dispatch(
        Stage::GridCone,
        &bindings,
        groups(Stage::GridCone, params.cell_count)?,
    )?;
    Ok(BuiltGrid {
        params,
        params_buf,
        cell_start,
        cell_splats,
        cell_dist,
    })
}

/// Passes x, y, z of `grid_distance`, ping-ponging between two buffers; returns the field.
fn distance_field<E: Executor>(
    ex: &mut E,
    grid: &E::Buffer,
    params: &GridParams,
    cell_start: &E::Buffer,
) -> Result<E::Buffer> {
    let bytes = params.cell_count as u64 * 4;
    let a = ex.zeroed("cell distance", bytes)?;
    let b = ex.zeroed("cell distance scratch", bytes)?;
    let groups = groups(Stage::GridDistance, params.cell_count)?;
    let passes: [(u32, &E::Buffer, &E::Buffer); 3] =
        [(0, cell_start, &a), (1, &a, &b), (2, &b, &a)];
    for (axis, src, dst) in passes {
        let pass = DistanceParams {
            axis,
            ..Default::default()
        };
        let pass = ex.uniform("distance pass", &pass)?;
        ex.dispatch(
            Stage::GridDistance,
            &[&pass, grid, cell_start, src, dst],
            groups,
        )?;
    }
    Ok(a)
}
