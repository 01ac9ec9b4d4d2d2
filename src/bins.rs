//! Photon binning (docs/design.md §5): stored photons sorted into a uniform grid whose cells are a
//! little over half the search radius, each cell's list in photon-key order `(path, bounce)`.
//! Count → exclusive scan → scatter → rank → place (`sequence::bin_photons`), on the device
//! and on the CPU mirror, which give identical lists.
//!
//! Half-radius cells keep lists short (the rank pass costs the square of a list's length)
//! and bound the gather tighter than radius-sized cells: the 2R box around a splat covers at
//! most 5 cells per axis, 25 contiguous rows of the binned list.

use glam::Vec3;

use crate::error::{Error, Result};
use crate::types::{BinParams, BinnedPhoton, DepositParams, GridParams};

/// Bin cells per search radius along an axis.
pub const CELLS_PER_RADIUS: f32 = 2.0;
/// Most photon lists (cells × sub-cells) the binning splits into: 64 MiB of list starts.
pub const MAX_BIN_LISTS: u64 = 1 << 24;
/// Most lists per stored photon: past it, splitting cells would cost the scan over mostly
/// empty lists more than it saves the ranking.
pub const LISTS_PER_PHOTON: u64 = 4;
/// Most bin cells along an axis; larger radii ratios coarsen the cells (still at least R/2).
pub const MAX_BIN_DIM: u32 = 256;
/// Bytes of one binned photon across the binned arrays (geometry, power, key).
pub const BINNED_BYTES: u64 = 16 + 16 + 8;

/// The binning grid over the splat grid's box for search radius `radius`, for `stored`
/// photons: cells are split into 2³, 3³ or 4³ sub-cell lists while there are at most
/// `LISTS_PER_PHOTON` lists a photon (ranking a list costs the square of its length; a list
/// that stays empty costs one entry of the scan), up to `MAX_BIN_LISTS`.
pub fn bin_params(grid: &GridParams, radius: f32, stored: u64) -> Result<BinParams> {
    crate::em::check_radius(radius).map_err(Error::Invalid)?;
    let extent = *grid.dims.iter().max().unwrap_or(&1) as f32 * grid.cell_size;
    // A hair over R/2, so that rounding never stretches a 2R box past 5 cells.
    let cell = (radius / CELLS_PER_RADIUS * 1.001).max(extent / MAX_BIN_DIM as f32);
    let size = glam::UVec3::from(grid.dims).as_vec3() * grid.cell_size;
    let dims = (size / cell)
        .ceil()
        .clamp(Vec3::ONE, Vec3::splat(MAX_BIN_DIM as f32))
        .as_uvec3();
    let cell_count = dims.x * dims.y * dims.z;
    let lists = |sub: u64| cell_count as u64 * sub.pow(3);
    let sub = [4u32, 3, 2]
        .into_iter()
        .find(|&s| {
            let n = lists(s as u64);
            n <= MAX_BIN_LISTS && n <= stored.saturating_mul(LISTS_PER_PHOTON)
        })
        .unwrap_or(1);
    Ok(BinParams {
        origin: grid.origin,
        cell_size: cell,
        dims: dims.into(),
        cell_count,
        inv_cell_size: 1.0 / cell,
        sub,
        ..Default::default()
    })
}

/// Binned photons on the host: `cell_start` has `list_count + 1` offsets into the parallel
/// arrays (`shared::bins::list_count`), each list's run sorted by key.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonBins {
    pub params: BinParams,
    pub cell_start: Vec<u32>,
    pub keys: Vec<[u32; 2]>,
    pub geom: Vec<BinnedPhoton>,
    pub power: Vec<[f32; 4]>,
}

impl PhotonBins {
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }
}

/// Checks that `photons` binned photons fit the largest array of 16-byte records the device
/// holds (`max_bytes`, over several bindings: `Gpu::max_array_bytes`).
pub fn check_binned(photons: u64, max_bytes: u64) -> Result<()> {
    if photons * 16 > max_bytes {
        return Err(Error::DeviceLimit(format!(
            "{photons} stored photons exceed what the binning's buffers hold on this device \
             ({} photons): emit fewer photons",
            max_bytes / 16
        )));
    }
    Ok(())
}

/// Photon deposits on the host (`sequence::deposit_photons`): the records binned, each
/// splat's spread and count, and the passes' settings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DepositBins {
    pub params: DepositParams,
    pub bins: PhotonBins,
    pub spread: Vec<[f32; 2]>,
}
