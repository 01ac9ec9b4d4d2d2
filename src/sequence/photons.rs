//! The photon pass (pages of stored photons, grown or opened on overflow) and the photon
//! view.

use crate::error::{Error, Result};
use crate::photons::{
    PhotonConfig, PhotonMap, PhotonStats, StoreAction, StorePlanner, first_capacity,
};
use crate::shaders::Stage;
use crate::timing::ms_since;
use crate::types::{Camera, Emitter, Photon, PhotonViewParams, TraceCounters};

use super::{Executor, groups};

/// The photon view of `cam` (`width × height` from `cam.size`): `photon_view` once per photon
/// page (a buffer and its photon count) into fixed-point sums with integer atomics, then
/// `photon_resolve` into an HDR image (`vec4<f32>` per pixel, rows from the top).
pub fn photon_image<E: Executor>(
    ex: &mut E,
    materials: &E::Buffer,
    pages: &[(&E::Buffer, u32)],
    cam: &Camera,
    scale: f32,
) -> Result<E::Buffer> {
    let (width, height) = (cam.size[0] as u32, cam.size[1] as u32);
    let pixels = width * height;
    let sums = ex.zeroed("photon view sums", pixels.max(1) as u64 * 12)?;
    let cam_buf = ex.uniform("camera", cam)?;
    for &(page, count) in pages.iter().filter(|p| p.1 > 0) {
        let params = PhotonViewParams {
            count,
            width,
            height,
            scale,
        };
        let params_buf = ex.uniform("photon view params", &params)?;
        let bindings = [&params_buf, &cam_buf, materials, page, &sums];
        ex.dispatch_traced(
            Stage::PhotonView,
            &bindings,
            groups(Stage::PhotonView, count)?,
        )?;
    }
    let hdr = ex.zeroed("photon view", pixels.max(1) as u64 * 16)?;
    let params = PhotonViewParams {
        count: pixels,
        width,
        height,
        scale,
    };
    let params = ex.uniform("photon resolve params", &params)?;
    let bindings = [&params, &sums, &hdr];
    ex.dispatch(
        Stage::PhotonResolve,
        &bindings,
        groups(Stage::PhotonResolve, pixels)?,
    )?;
    Ok(hdr)
}

const PHOTON_BYTES: u64 = size_of::<Photon>() as u64;

/// One photon store buffer and how many photons it holds.
pub struct Page<B> {
    pub buffer: B,
    pub capacity: u64,
    pub count: u64,
}

/// Stored photons where they were traced: the pages in order, and the pass's figures.
pub struct Traced<B> {
    pub pages: Vec<Page<B>>,
    pub stats: PhotonStats,
}

impl<B> Traced<B> {
    /// All stored photons in host memory, sorted by `Photon::key`.
    pub fn read_back<E: Executor<Buffer = B>>(&self, ex: &mut E) -> Result<PhotonMap> {
        let mut photons = Vec::with_capacity(self.stats.stored as usize);
        for page in &self.pages {
            photons.extend(ex.read::<Photon>(&page.buffer, page.count as usize)?);
        }
        let mut map = PhotonMap {
            photons,
            stats: self.stats.clone(),
        };
        map.sort();
        Ok(map)
    }
}

/// The photon pass: batches of `photon_trace` appending to a store of pages of at most
/// `max_page` photons. Each batch ends in a split point, the counters read back: on overflow
/// (the counter counts every store attempt, so it tells how much room the batch needed) the
/// page grows, or a new page starts at `max_page`, and the batch runs again; nothing is
/// written out of bounds and nothing is dropped. Before each batch the `StorePlanner` makes
/// room for what the batch will likely store, so reruns are rare. `progress` hears (paths
/// done, total).
pub fn trace_photons<E: Executor>(
    ex: &mut E,
    emitters: &[Emitter],
    materials: &E::Buffer,
    cfg: &PhotonConfig,
    max_page: u64,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<Traced<E::Buffer>> {
    cfg.validate()?;
    let t = std::time::Instant::now();
    let emitter_buf = ex.upload("emitters", emitters)?;
    let mut planner = StorePlanner::new(max_page, cfg.photons);
    let mut pages = Vec::new();
    let mut page = new_page(ex, first_capacity(cfg, max_page))?;
    let mut stats = PhotonStats::default();
    let mut batch = cfg.batch;
    let mut done = 0u64;
    while done < cfg.photons {
        let paths = (cfg.photons - done).min(batch as u64) as u32;
        let action = planner.before(page.count, page.capacity, paths, done);
        apply(ex, action, &mut pages, &mut page)?;
        let before = page.count as u32;
        let params = ex.uniform("trace params", &cfg.params(emitters, done as u32, paths))?;
        let start = TraceCounters {
            stored: before,
            capacity: page.capacity as u32,
            ..Default::default()
        };
        let counters_buf = ex.upload("trace counters", &[start])?;
        let bindings = [
            &params,
            &emitter_buf,
            materials,
            &page.buffer,
            &counters_buf,
        ];
        ex.dispatch_traced(
            Stage::PhotonTrace,
            &bindings,
            groups(Stage::PhotonTrace, paths)?,
        )?;
        let counters = ex
            .read::<TraceCounters>(&counters_buf, 1)?
            .pop()
            .ok_or_else(|| Error::Gpu("trace counters readback was short".into()))?;
        if counters.overflow == 0 {
            page.count = counters.stored as u64;
            stats.add_batch(paths, before, &counters);
            planner.record(paths, (counters.stored - before) as u64);
            planner.check_budget(&cfg.memory)?;
            done += paths as u64;
            progress(done, cfg.photons);
            continue;
        }
        stats.reruns += 1;
        let need = (counters.stored - before) as u64;
        match planner.after_overflow(page.count, page.capacity, need, paths, done) {
            StoreAction::HalveBatch if paths > 1 => batch = paths / 2,
            StoreAction::HalveBatch => {
                return Err(Error::DeviceLimit(format!(
                    "one photon path stores more photons than the largest store page holds \
                     ({max_page})"
                )));
            }
            action => apply(ex, action, &mut pages, &mut page)?,
        }
    }
    if page.count > 0 || pages.is_empty() {
        pages.push(page);
    }
    stats.pages = pages.len() as u32;
    stats.trace_ms = ms_since(t);
    Ok(Traced { pages, stats })
}

fn new_page<E: Executor>(ex: &mut E, capacity: u64) -> Result<Page<E::Buffer>> {
    Ok(Page {
        buffer: ex.zeroed("photons", capacity * PHOTON_BYTES)?,
        capacity,
        count: 0,
    })
}

/// Makes the room `action` asks for: a larger page holding the photons so far, or a new one.
fn apply<E: Executor>(
    ex: &mut E,
    action: StoreAction,
    pages: &mut Vec<Page<E::Buffer>>,
    page: &mut Page<E::Buffer>,
) -> Result<()> {
    match action {
        StoreAction::Keep | StoreAction::HalveBatch => {}
        StoreAction::Grow(capacity) => {
            let grown = new_page(ex, capacity)?;
            ex.copy(&page.buffer, 0, &grown.buffer, 0, page.count * PHOTON_BYTES)?;
            *page = Page {
                count: page.count,
                ..grown
            };
        }
        StoreAction::NewPage(capacity) => {
            let full = std::mem::replace(page, new_page(ex, capacity)?);
            pages.push(full);
        }
    }
    Ok(())
}
