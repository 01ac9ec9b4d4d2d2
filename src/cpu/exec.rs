//! The CPU mirror's executor of `sequence`s: buffers are host words, and each dispatch runs
//! the stage's mirror at once, with the same bindings in the same order as its WGSL.

use std::cell::{Ref, RefCell, RefMut};
use std::rc::Rc;

use bytemuck::Pod;

use super::{
    bin_count, bin_place, bin_rank, bin_scatter, em_coverage, em_deposit, em_deposit_list, em_fit,
    em_gather, em_select, em_share,
};
use super::{
    direct_bake, final_gather, path_trace, photon_resolve, photon_trace, photon_view, scan_apply,
    scan_reduce, tonemap_apply, tonemap_reduce,
};
use super::{grid_count, grid_distance, grid_rank, grid_scatter, splat_tiles};
use crate::error::{Error, Result};
use crate::sequence::Executor;
use crate::shared::trace::Geometry;

/// A buffer in host memory: 4-byte words, so every record type views it in place.
pub type CpuBuffer = Rc<RefCell<Vec<u32>>>;

/// Runs sequences on the CPU; tracing stages read `geometry` as their bind group 1.
#[derive(Default)]
pub struct CpuExecutor<'g> {
    pub geometry: Option<Geometry<'g>>,
}

impl<'g> CpuExecutor<'g> {
    /// An executor whose tracing stages walk `geometry`.
    pub fn tracing(geometry: Geometry<'g>) -> CpuExecutor<'g> {
        CpuExecutor {
            geometry: Some(geometry),
        }
    }
}

fn words_for(bytes: u64) -> usize {
    (bytes.div_ceil(4) as usize).max(1)
}

impl Executor for CpuExecutor<'_> {
    type Buffer = CpuBuffer;

    fn zeroed(&mut self, _label: &'static str, bytes: u64) -> Result<CpuBuffer> {
        Ok(Rc::new(RefCell::new(vec![0; words_for(bytes)])))
    }

    fn upload<T: Pod>(&mut self, _label: &'static str, data: &[T]) -> Result<CpuBuffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut words = vec![0u32; words_for(bytes.len().max(size_of::<T>()) as u64)];
        bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
        Ok(Rc::new(RefCell::new(words)))
    }

    fn uniform<T: Pod>(&mut self, label: &'static str, value: &T) -> Result<CpuBuffer> {
        self.upload(label, std::slice::from_ref(value))
    }

    fn dispatch(&mut self, stage: &'static str, b: &[&CpuBuffer], groups: u32) -> Result<()> {
        run(stage, b, groups)
    }

    fn dispatch_traced(
        &mut self,
        stage: &'static str,
        b: &[&CpuBuffer],
        groups: u32,
    ) -> Result<()> {
        let geo = self
            .geometry
            .ok_or_else(|| Error::Internal(format!("{stage}: no scene geometry to trace")))?;
        run_traced(stage, b, &geo, groups)
    }

    fn dispatch_variant(
        &mut self,
        stage: &'static str,
        _defines: &[&'static str],
        _constants: &[(&'static str, f64)],
        b: &[&CpuBuffer],
        groups: u32,
    ) -> Result<()> {
        // The mirrors read the lobe count, family and the rest from the stage's parameters.
        run(stage, b, groups)
    }

    fn copy(
        &mut self,
        src: &CpuBuffer,
        src_offset: u64,
        dst: &CpuBuffer,
        dst_offset: u64,
        bytes: u64,
    ) -> Result<()> {
        let data: Vec<u8> = {
            let src = src.borrow();
            let src: &[u8] = bytemuck::cast_slice(&src);
            let range = src_offset as usize..(src_offset + bytes) as usize;
            src.get(range)
                .ok_or_else(|| Error::Internal("copy past the end of a buffer".into()))?
                .to_vec()
        };
        let mut dst = dst.borrow_mut();
        let dst: &mut [u8] = bytemuck::cast_slice_mut(&mut dst);
        let range = dst_offset as usize..(dst_offset + bytes) as usize;
        dst.get_mut(range)
            .ok_or_else(|| Error::Internal("copy past the end of a buffer".into()))?
            .copy_from_slice(&data);
        Ok(())
    }

    fn read<T: Pod>(&mut self, buffer: &CpuBuffer, count: usize) -> Result<Vec<T>> {
        let words = buffer.borrow();
        let values = view::<T>(&words);
        values
            .get(..count)
            .map(<[T]>::to_vec)
            .ok_or_else(|| Error::Internal("readback past the end of a buffer".into()))
    }
}

/// The whole elements of `T` the words hold.
fn view<T: Pod>(words: &[u32]) -> &[T] {
    let bytes: &[u8] = bytemuck::cast_slice(words);
    bytemuck::cast_slice(&bytes[..bytes.len() / size_of::<T>() * size_of::<T>()])
}

fn view_mut<T: Pod>(words: &mut [u32]) -> &mut [T] {
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(words);
    let whole = bytes.len() / size_of::<T>() * size_of::<T>();
    bytemuck::cast_slice_mut(&mut bytes[..whole])
}

/// Binding `i` of a dispatch, read-only.
fn get<'a>(stage: &str, b: &'a [&CpuBuffer], i: usize) -> Result<Ref<'a, Vec<u32>>> {
    b.get(i)
        .ok_or_else(|| Error::Internal(format!("{stage}: no binding {i}")))?
        .try_borrow()
        .map_err(|_| Error::Internal(format!("{stage}: binding {i} is also written")))
}

/// Binding `i` of a dispatch, written.
fn get_mut<'a>(stage: &str, b: &'a [&CpuBuffer], i: usize) -> Result<RefMut<'a, Vec<u32>>> {
    b.get(i)
        .ok_or_else(|| Error::Internal(format!("{stage}: no binding {i}")))?
        .try_borrow_mut()
        .map_err(|_| Error::Internal(format!("{stage}: binding {i} is bound twice")))
}

/// A uniform binding's value.
fn param<T: Pod>(stage: &str, b: &[&CpuBuffer], i: usize) -> Result<T> {
    view::<T>(&get(stage, b, i)?)
        .first()
        .copied()
        .ok_or_else(|| Error::Internal(format!("{stage}: binding {i} is too short")))
}

/// Refuses a dispatch whose bindings are not the ones `stage`'s WGSL declares in group 0.
fn check_bindings(stage: &str, b: &[&CpuBuffer]) -> Result<()> {
    let declared = crate::shaders::stage_shape(stage)?.bindings[0];
    if b.len() != declared as usize {
        return Err(Error::Invalid(format!(
            "{stage}: {} bindings passed, its WGSL declares {declared}",
            b.len()
        )));
    }
    Ok(())
}

/// Runs `stage`'s mirror over `groups` workgroups with the dispatch's bindings.
fn run(stage: &str, b: &[&CpuBuffer], groups: u32) -> Result<()> {
    check_bindings(stage, b)?;
    match stage {
        "scan_reduce" => {
            let p = param(stage, b, 0)?;
            let values = get(stage, b, 1)?;
            let mut sums = get_mut(stage, b, 2)?;
            scan_reduce::scan_reduce(&p, &values, &mut sums, groups);
        }
        "scan_apply" => {
            let p = param(stage, b, 0)?;
            let mut values = get_mut(stage, b, 1)?;
            let offsets = get(stage, b, 2)?;
            scan_apply::scan_apply(&p, &mut values, &offsets, groups);
        }
        "tonemap_reduce" => {
            let p = param(stage, b, 0)?;
            let hdr = get(stage, b, 1)?;
            let sums_in = get(stage, b, 2)?;
            let mut sums_out = get_mut(stage, b, 3)?;
            let out = view_mut(&mut sums_out);
            tonemap_reduce::tonemap_reduce(&p, view(&hdr), view(&sums_in), out, groups);
        }
        "tonemap_apply" => {
            let p = param(stage, b, 0)?;
            let hdr = get(stage, b, 1)?;
            let log_sum = get(stage, b, 2)?;
            let mut rgba = get_mut(stage, b, 3)?;
            tonemap_apply::tonemap_apply(&p, view(&hdr), view(&log_sum), &mut rgba);
        }
        "grid_count" => {
            let p = param(stage, b, 0)?;
            let splats = get(stage, b, 1)?;
            let mut counts = get_mut(stage, b, 2)?;
            let mut max_len = get_mut(stage, b, 3)?;
            grid_count::grid_count(&p, view(&splats), &mut counts, &mut max_len[0], groups);
        }
        "splat_tile_count" => {
            let cam = param(stage, b, 0)?;
            let p = param(stage, b, 1)?;
            let splats = get(stage, b, 2)?;
            let mut counts = get_mut(stage, b, 3)?;
            splat_tiles::splat_tile_count(&cam, &p, view(&splats), &mut counts);
        }
        "splat_tile_scatter" => {
            let cam = param(stage, b, 0)?;
            let p = param(stage, b, 1)?;
            let splats = get(stage, b, 2)?;
            let tile_start = get(stage, b, 3)?;
            let mut cursor = get_mut(stage, b, 4)?;
            let mut scratch_splats = get_mut(stage, b, 5)?;
            let mut scratch_tiles = get_mut(stage, b, 6)?;
            splat_tiles::splat_tile_scatter(
                &cam,
                &p,
                view(&splats),
                &tile_start,
                &mut cursor,
                &mut scratch_splats,
                &mut scratch_tiles,
            );
        }
        "grid_scatter" => {
            let p = param(stage, b, 0)?;
            let splats = get(stage, b, 1)?;
            let cell_start = get(stage, b, 2)?;
            let mut cursor = get_mut(stage, b, 3)?;
            let mut scratch_splats = get_mut(stage, b, 4)?;
            let mut scratch_cells = get_mut(stage, b, 5)?;
            grid_scatter::grid_scatter(
                &p,
                view(&splats),
                &cell_start,
                &mut cursor,
                &mut scratch_splats,
                &mut scratch_cells,
                groups,
            );
        }
        "grid_rank" => {
            let p = param(stage, b, 0)?;
            let cell_start = get(stage, b, 1)?;
            let scratch_splats = get(stage, b, 2)?;
            let scratch_cells = get(stage, b, 3)?;
            let mut cell_splats = get_mut(stage, b, 4)?;
            grid_rank::grid_rank(
                &p,
                &cell_start,
                &scratch_splats,
                &scratch_cells,
                &mut cell_splats,
                groups,
            );
        }
        "grid_distance" => {
            let pass = param(stage, b, 0)?;
            let grid = param(stage, b, 1)?;
            let cell_start = get(stage, b, 2)?;
            let src = get(stage, b, 3)?;
            let mut dst = get_mut(stage, b, 4)?;
            grid_distance::grid_distance(&pass, &grid, &cell_start, &src, &mut dst, groups);
        }
        "bin_count" => {
            let p = param(stage, b, 0)?;
            let photons = get(stage, b, 1)?;
            let mut cell_start = get_mut(stage, b, 2)?;
            let mut chunks = get_mut(stage, b, 3)?;
            let photons = view(&photons);
            bin_count::bin_count(&p, photons, &mut cell_start, &mut chunks[0], groups);
        }
        "bin_scatter" => {
            let p = param(stage, b, 0)?;
            let photons = get(stage, b, 1)?;
            let cell_start = get(stage, b, 2)?;
            let mut cursor = get_mut(stage, b, 3)?;
            let mut keys = get_mut(stage, b, 4)?;
            let mut cells = get_mut(stage, b, 5)?;
            let mut geom = get_mut(stage, b, 6)?;
            let mut power = get_mut(stage, b, 7)?;
            let splats = get(stage, b, 8)?;
            bin_scatter::bin_scatter(
                &p,
                view(&photons),
                &cell_start,
                &mut cursor,
                view_mut(&mut keys),
                &mut cells,
                view_mut(&mut geom),
                view_mut(&mut power),
                view(&splats),
                groups,
            );
        }
        "bin_rank" => {
            let p = param(stage, b, 0)?;
            let cell_start = get(stage, b, 1)?;
            let keys = get(stage, b, 2)?;
            let cells = get(stage, b, 3)?;
            let mut slots = get_mut(stage, b, 4)?;
            bin_rank::bin_rank(&p, &cell_start, view(&keys), &cells, &mut slots, groups);
        }
        "bin_place" => {
            let p = param(stage, b, 0)?;
            let slots = get(stage, b, 1)?;
            let keys = get(stage, b, 2)?;
            let geom = get(stage, b, 3)?;
            let power = get(stage, b, 4)?;
            let mut out_keys = get_mut(stage, b, 5)?;
            let mut out_geom = get_mut(stage, b, 6)?;
            let mut out_power = get_mut(stage, b, 7)?;
            bin_place::bin_place(
                &p,
                &slots,
                view(&keys),
                view(&geom),
                view(&power),
                view_mut(&mut out_keys),
                view_mut(&mut out_geom),
                view_mut(&mut out_power),
                groups,
            );
        }
        "em_select" => {
            let em = param(stage, b, 0)?;
            let bins = param(stage, b, 1)?;
            let splats = get(stage, b, 2)?;
            let materials = get(stage, b, 3)?;
            let cell_start = get(stage, b, 4)?;
            let mut active = get_mut(stage, b, 5)?;
            let mut counters = get_mut(stage, b, 6)?;
            let mut gather_list = get_mut(stage, b, 7)?;
            let counters: &mut [u32; 4] = counters
                .get_mut(..4)
                .and_then(|c| c.try_into().ok())
                .ok_or_else(|| Error::Internal(format!("{stage}: counters too short")))?;
            let (splats, materials) = (view(&splats), view(&materials));
            em_select::em_select(
                &em,
                &bins,
                splats,
                materials,
                &cell_start,
                view_mut(&mut active),
                counters,
                &mut gather_list,
                groups,
            );
        }
        "em_deposit" => {
            let p = param(stage, b, 0)?;
            let photons = get(stage, b, 1)?;
            let splats = get(stage, b, 2)?;
            let mut deposits = get_mut(stage, b, 3)?;
            em_deposit::em_deposit(&p, view(&photons), view(&splats), &mut deposits, groups);
        }
        "em_deposit_list" => {
            let p = param(stage, b, 0)?;
            let splats = get(stage, b, 1)?;
            let deposits = get(stage, b, 2)?;
            let mut list = get_mut(stage, b, 3)?;
            let mut spread = get_mut(stage, b, 4)?;
            let mut listed = get_mut(stage, b, 5)?;
            let listed = listed
                .first_mut()
                .ok_or_else(|| Error::Internal(format!("{stage}: no list counter")))?;
            em_deposit_list::em_deposit_list(
                &p,
                view(&splats),
                &deposits,
                view_mut(&mut list),
                view_mut(&mut spread),
                listed,
                groups,
            );
        }
        "em_share" => {
            let em = param(stage, b, 0)?;
            let deposit = param(stage, b, 1)?;
            let bins = param(stage, b, 2)?;
            let splats = get(stage, b, 3)?;
            let materials = get(stage, b, 4)?;
            let mut counters = get_mut(stage, b, 5)?;
            let cell_start = get(stage, b, 6)?;
            let keys = get(stage, b, 7)?;
            let geom = get(stage, b, 8)?;
            let power = get(stage, b, 9)?;
            let spread = get(stage, b, 10)?;
            let mut light = get_mut(stage, b, 11)?;
            let counters: &mut [u32; 4] = counters
                .get_mut(..4)
                .and_then(|c| c.try_into().ok())
                .ok_or_else(|| Error::Internal(format!("{stage}: counters too short")))?;
            let binned = em_share::BinnedDeposits {
                cell_start: &cell_start,
                keys: view(&keys),
                geom: view(&geom),
                power: view(&power),
                spread: view(&spread),
            };
            em_share::em_share(
                &em,
                &deposit,
                &bins,
                view(&splats),
                &binned,
                view(&materials),
                view_mut(&mut light),
                counters,
                groups,
            );
        }
        "em_gather" => {
            let em = param(stage, b, 0)?;
            let bins = param(stage, b, 1)?;
            let splats = get(stage, b, 2)?;
            let gather_list = get(stage, b, 3)?;
            let cell_start = get(stage, b, 4)?;
            let geom = get(stage, b, 5)?;
            let power = get(stage, b, 6)?;
            let mut light = get_mut(stage, b, 7)?;
            em_gather::em_gather(
                &em,
                &bins,
                view(&splats),
                &gather_list,
                &cell_start,
                view(&geom),
                view(&power),
                view_mut(&mut light),
                groups,
            );
        }
        "em_fit" => {
            let em = param(stage, b, 0)?;
            let bins = param(stage, b, 1)?;
            let splats = get(stage, b, 2)?;
            let fit_list = get(stage, b, 3)?;
            let cell_start = get(stage, b, 4)?;
            let geom = get(stage, b, 5)?;
            let power = get(stage, b, 6)?;
            let mut lobes = get_mut(stage, b, 7)?;
            let mut light = get_mut(stage, b, 8)?;
            em_fit::em_fit(
                &em,
                &bins,
                view(&splats),
                view(&fit_list),
                &cell_start,
                view(&geom),
                view(&power),
                view_mut(&mut lobes),
                view_mut(&mut light),
                groups,
            );
        }
        "photon_resolve" => {
            let p = param(stage, b, 0)?;
            let sums = get(stage, b, 1)?;
            let mut hdr = get_mut(stage, b, 2)?;
            photon_resolve::photon_resolve(&p, &sums, view_mut(&mut hdr));
        }
        _ => {
            return Err(Error::Invalid(format!(
                "stage '{stage}' has no CPU executor entry (its mirror is called directly)"
            )));
        }
    }
    Ok(())
}

/// Runs a tracing stage's mirror, its bind group 1 being `geo`.
fn run_traced(stage: &str, b: &[&CpuBuffer], geo: &Geometry, groups: u32) -> Result<()> {
    check_bindings(stage, b)?;
    match stage {
        "photon_view" => {
            let p = param(stage, b, 0)?;
            let cam = param(stage, b, 1)?;
            let materials = get(stage, b, 2)?;
            let photons = get(stage, b, 3)?;
            let mut sums = get_mut(stage, b, 4)?;
            let (materials, photons) = (view(&materials), view(&photons));
            photon_view::photon_view(&p, &cam, materials, photons, &mut sums, geo);
        }
        "path_trace" => {
            let p = param(stage, b, 0)?;
            let cam = param(stage, b, 1)?;
            let materials = get(stage, b, 2)?;
            let lights = get(stage, b, 3)?;
            let mut hdr = get_mut(stage, b, 4)?;
            let (materials, lights) = (view(&materials), view(&lights));
            path_trace::path_trace(&p, &cam, materials, lights, view_mut(&mut hdr), geo);
        }
        "direct_bake" => {
            let p = param(stage, b, 0)?;
            let lights = get(stage, b, 1)?;
            let mut direct = get_mut(stage, b, 2)?;
            let mut visibility = get_mut(stage, b, 3)?;
            let (direct, visibility) = (view_mut(&mut direct), view_mut(&mut visibility));
            direct_bake::direct_bake(&p, view(&lights), direct, visibility, geo);
        }
        "em_coverage" => {
            let em = param(stage, b, 0)?;
            let mut light = get_mut(stage, b, 1)?;
            em_coverage::em_coverage(&em, view_mut(&mut light), geo, groups);
        }
        "final_gather" => {
            let p = param(stage, b, 0)?;
            let list = get(stage, b, 1)?;
            let light = get(stage, b, 2)?;
            let direct = get(stage, b, 3)?;
            let mut samples = get_mut(stage, b, 4)?;
            let materials = get(stage, b, 5)?;
            let lights = get(stage, b, 6)?;
            let (list, light, direct) = (view(&list), view(&light), view(&direct));
            let (samples, materials) = (view_mut(&mut samples), view(&materials));
            let lights = view(&lights);
            final_gather::final_gather(&p, list, light, direct, samples, materials, lights, geo);
        }
        "photon_trace" => {
            let p = param(stage, b, 0)?;
            let emitters = get(stage, b, 1)?;
            let materials = get(stage, b, 2)?;
            let mut store = get_mut(stage, b, 3)?;
            let mut counters = get_mut(stage, b, 4)?;
            let counters = view_mut(&mut counters)
                .first_mut()
                .ok_or_else(|| Error::Internal(format!("{stage}: counters too short")))?;
            let (emitters, materials) = (view(&emitters), view(&materials));
            let store = view_mut(&mut store);
            photon_trace::photon_trace(&p, emitters, materials, store, counters, geo, groups);
        }
        _ => {
            return Err(Error::Invalid(format!(
                "tracing stage '{stage}' has no CPU executor entry"
            )));
        }
    }
    Ok(())
}
