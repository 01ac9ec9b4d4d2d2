//! The uniform splat grid shared by grid build, photon tracing and shadow rays: its parameters
//! (chosen on the host from the scene bounds and splat count) and the cell range of a disk,
//! the Rust twin of `wgsl/shared/grid.wgsl`.

use crate::error::{Error, Result};
use crate::types::{GridParams, Splat};
use glam::{IVec3, UVec3, Vec2, Vec3};
use rayon::prelude::*;

/// How the grid resolution is chosen.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct GridConfig {
    /// Target number of cells per splat: the cell edge is `cbrt(volume / (cells_per_splat * N))`.
    pub cells_per_splat: f32,
    /// Cap on cells along any axis. Memory is bounded by `MAX_GRID_CELLS` in all, so a flat
    /// scene (a terrain, a facade) may have fine cells along its two long axes.
    pub max_dim: u32,
}

impl Default for GridConfig {
    fn default() -> Self {
        GridConfig {
            cells_per_splat: 8.0,
            max_dim: 1024,
        }
    }
}

/// Most cells a grid has: 256³, four arrays of a u32 per cell (64 MiB each) while it is built.
/// Past it the cells grow. With 256 cells per axis instead, a 10 M-splat terrain had 150
/// splats in a cell, and its photons and shadow rays tested them all (docs/measurements.md,
/// "Scale").
pub const MAX_GRID_CELLS: u64 = 1 << 24;

/// A splat every stage can work with: finite, a positive radius, a unit normal, a finite
/// non-negative albedo.
pub fn splat_is_sane(s: &Splat) -> bool {
    let n = glam::Vec3::from(s.normal);
    glam::Vec3::from(s.center).is_finite()
        && s.radius.is_finite()
        && s.radius > 0.0
        && n.is_finite()
        && (n.length() - 1.0).abs() < 1e-3
        && s.diffuse.iter().all(|c| c.is_finite() && *c >= 0.0)
}

/// Half extents of a disk's axis-aligned bounding box: `r * sqrt(1 - n_i²)` along axis i.
pub fn disk_half_extent(s: &Splat) -> Vec3 {
    let n = Vec3::from(s.normal);
    let one_minus = (Vec3::ONE - n * n).max(Vec3::ZERO);
    s.radius * Vec3::new(one_minus.x.sqrt(), one_minus.y.sqrt(), one_minus.z.sqrt())
}

/// Inclusive range of cells touched by a splat's bounding box, clamped to the grid.
/// Same operations in the same order as `disk_cell_range` in WGSL, so both round alike.
pub fn disk_cell_range(s: &Splat, g: &GridParams) -> (UVec3, UVec3) {
    let half = disk_half_extent(s);
    let c = Vec3::from(s.center);
    let origin = Vec3::from(g.origin);
    let inv = g.inv_cell_size;
    let lo_f = ((c - half - origin) * inv).floor();
    let hi_f = ((c + half - origin) * inv).floor();
    let top = (UVec3::from(g.dims) - UVec3::ONE).as_vec3();
    let lo = lo_f.clamp(Vec3::ZERO, top).as_uvec3();
    let hi = hi_f.clamp(Vec3::ZERO, top).as_uvec3();
    (lo, hi)
}

/// The cell that holds point `p`, unclamped: outside the grid where `p` is.
pub fn point_cell(p: Vec3, g: &GridParams) -> IVec3 {
    floor_cell((p - Vec3::from(g.origin)) * g.inv_cell_size)
}

/// `v.floor().as_ivec3()`, the same for every f32 (NaN to 0, saturating past i32), without a
/// call to `floorf` a lane: x86-64's baseline has no rounding instruction, and the mirror's
/// rays step cells with it (4 % of the bunny's render went to `floorf`).
pub fn floor_cell(v: Vec3) -> IVec3 {
    let floor = |x: f32| {
        let t = x as i32;
        if x < t as f32 { t.saturating_sub(1) } else { t }
    };
    IVec3::new(floor(v.x), floor(v.y), floor(v.z))
}

pub fn cell_index(c: UVec3, g: &GridParams) -> u32 {
    c.x + g.dims[0] * (c.y + g.dims[1] * c.z)
}

/// Longest cell list the grid build accepts. Each `grid_rank` invocation loops over one list,
/// and llvmpipe (Mesa's software rasterizer, our CI device) silently ends an invocation's
/// loops after about 65k iterations in total; longer lists only arise when thousands of
/// splats coincide, which is a broken scene rather than a large one.
pub const MAX_CELL_LEN: u32 = 4096;

/// Cap of the grid's distance field (in cells), as `DIST_CAP` in `wgsl/shared/grid.wgsl`.
pub const DIST_CAP: u32 = 16;

/// The low bits of a cell's distance word that hold its distance (`SplatGrid::cell_dist`); a
/// listed cell's upper 24 bits hold its facing cone (`cone_faces_away`).
pub const DIST_MASK: u32 = 0xff;

/// Steps of the facing cone's axis (per octahedral axis) and of its bound, as in
/// `wgsl/shared/grid.wgsl`.
pub const CONE_STEPS: f32 = 255.0;

/// How far past its bound a ray's direction must lie before a cone turns it away, and how much
/// the cone's widest cosine is lowered when it is made: room for rounding on either side.
pub const CONE_MARGIN: f32 = 1e-3;

fn cone_sign(p: Vec2) -> Vec2 {
    Vec2::new(
        if p.x >= 0.0 { 1.0 } else { -1.0 },
        if p.y >= 0.0 { 1.0 } else { -1.0 },
    )
}

/// The facing cone's axis bits (8-23 of the word) for a nonzero direction `m`.
pub fn cone_axis_encode(m: Vec3) -> u32 {
    let p = Vec2::new(m.x, m.y) / (m.x.abs() + m.y.abs() + m.z.abs());
    let q = if m.z < 0.0 {
        (Vec2::ONE - Vec2::new(p.y, p.x).abs()) * cone_sign(p)
    } else {
        p
    };
    // WGSL's round() takes ties to even.
    let u = (q.clamp(Vec2::splat(-1.0), Vec2::ONE) * 0.5 + 0.5) * CONE_STEPS;
    ((u.x.round_ties_even() as u32) << 8) | ((u.y.round_ties_even() as u32) << 16)
}

/// The facing cone's axis in a cell's distance word.
pub fn cone_axis(word: u32) -> Vec3 {
    let u = Vec2::new(((word >> 8) & 0xff) as f32, ((word >> 16) & 0xff) as f32);
    let p = u * (2.0 / CONE_STEPS) - 1.0;
    let z = 1.0 - p.x.abs() - p.y.abs();
    let fold = (-z).max(0.0);
    let xy = p - fold * cone_sign(p);
    Vec3::new(xy.x, xy.y, z).normalize()
}

/// Whether every disk of the listed cell whose distance word is `word` faces away from `d`
/// (`wgsl/shared/grid.wgsl`): one-sided disks a ray cannot hit, none of them read.
pub fn cone_faces_away(word: u32, d: Vec3) -> bool {
    let open = word >> 24;
    open != 0 && cone_axis(word).dot(d) > 1.0 - open as f32 / CONE_STEPS + CONE_MARGIN
}

pub fn check_cell_len(max_cell_len: u32) -> Result<()> {
    if max_cell_len > MAX_CELL_LEN {
        return Err(Error::Invalid(format!(
            "{max_cell_len} splats overlap one grid cell (at most {MAX_CELL_LEN}): the scene has \
             many coincident or oversized splats"
        )));
    }
    Ok(())
}

/// Bounds of all splat disks (their bounding boxes).
pub fn splat_bounds(splats: &[Splat]) -> Option<(Vec3, Vec3)> {
    let mut it = splats.iter();
    let first = it.next()?;
    let h = disk_half_extent(first);
    let c = Vec3::from(first.center);
    let init = (c - h, c + h);
    Some(it.fold(init, |(lo, hi), s| {
        let h = disk_half_extent(s);
        let c = Vec3::from(s.center);
        (lo.min(c - h), hi.max(c + h))
    }))
}

/// Chooses the grid for a set of splats: cubic cells, about `cells_per_splat` cells per splat,
/// no smaller than the mean splat radius, at most `max_dim` cells along any axis.
pub fn grid_params(splats: &[Splat], cfg: &GridConfig) -> Result<GridParams> {
    if !(cfg.cells_per_splat > 0.0 && cfg.cells_per_splat.is_finite()) {
        return Err(Error::Invalid(format!(
            "grid.cells_per_splat must be a positive number, got {}",
            cfg.cells_per_splat
        )));
    }
    if cfg.max_dim == 0 || cfg.max_dim > 2048 {
        return Err(Error::Invalid(format!(
            "grid.max_dim must be in 1..=2048, got {}",
            cfg.max_dim
        )));
    }
    // Every stage assumes sane splats: a NaN or zero normal, or a radius of 0, stops here
    // with the splat's index, on the device's path and the CPU's alike.
    if let Some(i) = splats.iter().position(|s| !splat_is_sane(s)) {
        let s = &splats[i];
        return Err(Error::Invalid(format!(
            "splat {i} is degenerate (centre {:?}, radius {}, normal {:?}): every splat needs a \
             finite centre, a positive radius and a unit normal",
            s.center, s.radius, s.normal
        )));
    }
    let (lo, hi) =
        splat_bounds(splats).ok_or_else(|| Error::Invalid("the scene has no splats".into()))?;
    if !lo.is_finite() || !hi.is_finite() {
        return Err(Error::Invalid("splat bounds are not finite".into()));
    }
    // Pad relative to the coordinates' magnitude so that no disk sits exactly on the far face,
    // also for scenes far from the origin where one ulp is large.
    let magnitude = lo
        .abs()
        .max(hi.abs())
        .max_element()
        .max((hi - lo).max_element());
    let pad = Vec3::splat(magnitude.max(f32::MIN_POSITIVE) * 1e-5);
    let (lo, hi) = (lo - pad, hi + pad);
    let extent = hi - lo;
    let max_dim = cfg.max_dim as f32;
    // Flat scenes have zero volume along an axis: treat each extent as at least one cell of the
    // finest grid allowed, so the volume estimate stays meaningful.
    let floor = extent.max_element() / max_dim;
    let clamped = extent.max(Vec3::splat(floor));
    let volume = clamped.x as f64 * clamped.y as f64 * clamped.z as f64;
    let target_cells = cfg.cells_per_splat as f64 * splats.len() as f64;
    // Cells no smaller than the mean splat radius: a disk then touches a few cells per axis,
    // and coincident splats cannot multiply into thousands of cells that each list them all.
    let mean_radius =
        (splats.iter().map(|s| s.radius as f64).sum::<f64>() / splats.len() as f64) as f32;
    let mut cell = (volume / target_cells).cbrt() as f32;
    cell = cell.max(mean_radius).max(floor).max(f32::MIN_POSITIVE);
    let dims_of = |cell: f32| {
        (extent / cell)
            .ceil()
            .max(Vec3::ONE)
            .min(Vec3::splat(max_dim))
            .as_uvec3()
    };
    let count = |d: UVec3| d.x as u64 * d.y as u64 * d.z as u64;
    let mut dims = dims_of(cell);
    // Coarser cells until the grid fits its cap (each step by the cube root of the excess,
    // plus a little: the rounding up of each axis can keep it just over).
    for _ in 0..64 {
        if count(dims) <= MAX_GRID_CELLS {
            break;
        }
        cell *= (count(dims) as f32 / MAX_GRID_CELLS as f32).cbrt() * 1.01;
        dims = dims_of(cell);
    }
    let cell_count = count(dims);
    if cell_count > MAX_GRID_CELLS {
        return Err(Error::Invalid(format!(
            "grid of {cell_count} cells is too large"
        )));
    }
    Ok(GridParams {
        origin: lo.into(),
        cell_size: cell,
        dims: dims.into(),
        cell_count: cell_count as u32,
        inv_cell_size: 1.0 / cell,
        splat_count: splats.len() as u32,
        entry_count: 0,
        _pad0: 0,
    })
}

/// A built grid: `cell_splats[cell_start[c]..cell_start[c + 1]]` lists the splats touching
/// cell `c`, in increasing splat index. `cell_start` has `cell_count + 1` entries.
/// `cell_dist[c] & DIST_MASK` is the Chebyshev distance in cells from `c` to the nearest cell
/// with a non-empty list, capped at `DIST_CAP` (0 for such cells): rays skip empty space with
/// it. A listed cell's upper 24 bits hold its facing cone (`cone_faces_away`, `grid_cone`).
#[derive(Clone, Debug, PartialEq)]
pub struct SplatGrid {
    pub params: GridParams,
    pub cell_start: Vec<u32>,
    pub cell_splats: Vec<u32>,
    pub cell_dist: Vec<u32>,
}

impl SplatGrid {
    pub fn cell(&self, c: u32) -> &[u32] {
        let (b, e) = (self.cell_start[c as usize], self.cell_start[c as usize + 1]);
        &self.cell_splats[b as usize..e as usize]
    }

    /// Number of cells that list at least one splat.
    pub fn occupied_cells(&self) -> usize {
        self.cell_start.windows(2).filter(|w| w[1] > w[0]).count()
    }

    pub fn max_cell_len(&self) -> u32 {
        self.cell_start
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0)
    }
}

/// The order in which the direct bake's invocations take the splats: along a Morton curve of
/// their centres (10 bits an axis over the splats' bounds), ties in splat order. Each splat's
/// result depends on its index alone, so any order gives the same bytes; this one gives a SIMD
/// group of invocations neighbouring splats, whose shadow rays walk the same cells. A cloud
/// whose points come in no order in space (a Fibonacci sphere, merged or thinned scans) took
/// lavapipe's direct bake 1.7–2.5× longer in its own order (docs/measurements.md).
pub fn splat_order(splats: &[Splat]) -> Vec<u32> {
    let (lo, hi) = splats.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), s| {
            let c = Vec3::from(s.center);
            (lo.min(c), hi.max(c))
        },
    );
    let scale = 1023.0 / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let mut keyed: Vec<(u32, u32)> = (0..splats.len())
        .into_par_iter()
        .map(|i| {
            let q = ((Vec3::from(splats[i].center) - lo) * scale)
                .clamp(Vec3::ZERO, Vec3::splat(1023.0))
                .as_uvec3();
            let key = spread_bits(q.x) | spread_bits(q.y) << 1 | spread_bits(q.z) << 2;
            (key, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// The 10 low bits of `x` spread to every third bit.
fn spread_bits(x: u32) -> u32 {
    let mut x = x & 0x3ff;
    x = (x | x << 16) & 0x030000ff;
    x = (x | x << 8) & 0x0300f00f;
    x = (x | x << 4) & 0x030c30c3;
    (x | x << 2) & 0x09249249
}

/// The cell lists of `splats` over `params`, built on the host, with no distance field and no
/// facing cones (every ray steps cell by cell and reads every list it meets): for the few
/// rays the host traces at load (`scene::sides`), where building the stages' grid would cost
/// more than the rays.
pub fn host_lists(params: &GridParams, splats: &[Splat]) -> SplatGrid {
    let cells = params.cell_count as usize;
    let mut cell_start = vec![0u32; cells + 1];
    for s in splats {
        each_cell(s, params, |c| cell_start[c + 1] += 1);
    }
    for c in 0..cells {
        cell_start[c + 1] += cell_start[c];
    }
    let mut next = cell_start.clone();
    let mut cell_splats = vec![0u32; cell_start[cells] as usize];
    // Splat by splat in index order, so that every list is sorted as the stages' lists are.
    for (i, s) in splats.iter().enumerate() {
        each_cell(s, params, |c| {
            cell_splats[next[c] as usize] = i as u32;
            next[c] += 1;
        });
    }
    let cell_dist = (0..cells)
        .map(|c| u32::from(cell_start[c + 1] == cell_start[c]))
        .collect();
    SplatGrid {
        params: GridParams {
            entry_count: cell_start[cells],
            ..*params
        },
        cell_start,
        cell_splats,
        cell_dist,
    }
}

/// Calls `f` with the index of every cell splat `s`'s bounding box touches.
fn each_cell(s: &Splat, params: &GridParams, mut f: impl FnMut(usize)) {
    let (lo, hi) = disk_cell_range(s, params);
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                f(cell_index(UVec3::new(x, y, z), params) as usize);
            }
        }
    }
}
