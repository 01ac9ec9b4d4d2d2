//! The photon pass on the device: batches of `photon_trace` dispatches appending to a store
//! of pages. After each batch the host reads the counters; on overflow (the counter counts
//! every store attempt, so it tells exactly how much room the batch needed) the page grows,
//! or a new page starts when the device's largest binding is reached, and the batch runs
//! again. Nothing is written out of bounds and nothing is dropped. Before each batch the
//! `StorePlanner` makes room for what the batch will likely store, so reruns are rare.

use std::time::Instant;

use super::Gpu;
use super::scene::GpuScene;
use crate::error::{Error, Result};
use crate::photons::{
    PhotonConfig, PhotonMap, PhotonStats, StoreAction, StorePlanner, emitters, first_capacity,
    ms_since, page_photons,
};
use crate::scene::Scene;
use crate::types::{Emitter, Photon, TraceCounters};

const PHOTON_BYTES: u64 = std::mem::size_of::<Photon>() as u64;

/// One store buffer and how many photons it holds.
pub struct PhotonPage {
    pub buffer: wgpu::Buffer,
    pub capacity: u64,
    pub count: u64,
}

/// Stored photons on the device.
pub struct GpuPhotons {
    pub pages: Vec<PhotonPage>,
    pub stats: PhotonStats,
}

impl GpuPhotons {
    /// All stored photons, sorted by `Photon::key`.
    pub fn download(&self, gpu: &Gpu) -> Result<PhotonMap> {
        let mut photons = Vec::with_capacity(self.stats.stored as usize);
        for page in &self.pages {
            photons.extend(gpu.read::<Photon>(&page.buffer, page.count as usize)?);
        }
        let mut map = PhotonMap {
            photons,
            stats: self.stats.clone(),
        };
        map.sort();
        Ok(map)
    }
}

impl GpuPhotons {
    /// One page holding `photons` (for tests and for binning photons traced elsewhere).
    pub fn upload(gpu: &Gpu, map: &PhotonMap) -> Result<GpuPhotons> {
        let count = map.photons.len() as u64;
        Ok(GpuPhotons {
            pages: vec![PhotonPage {
                buffer: gpu.storage("photons", &map.photons)?,
                capacity: count,
                count,
            }],
            stats: map.stats.clone(),
        })
    }
}

fn new_page(gpu: &Gpu, capacity: u64) -> Result<PhotonPage> {
    Ok(PhotonPage {
        buffer: gpu.storage_zeroed("photons", capacity * PHOTON_BYTES)?,
        capacity,
        count: 0,
    })
}

/// Traces `cfg.photons` photons from the scene's lights. `progress` hears (paths done, total).
pub fn trace_photons(
    gpu: &Gpu,
    scene: &Scene,
    on_gpu: &GpuScene,
    cfg: &PhotonConfig,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<GpuPhotons> {
    cfg.validate()?;
    let t = Instant::now();
    let emitters = emitters(&scene.lights, cfg.photons)?;
    let emitter_buf = gpu.storage("emitters", &emitters)?;
    let counters_buf = gpu.storage_zeroed("trace counters", 32)?;
    let max_page = page_photons(cfg, gpu.max_binding_bytes() / PHOTON_BYTES);
    let mut planner = StorePlanner::new(max_page, cfg.photons);
    let mut store = Store {
        pages: Vec::new(),
        page: new_page(gpu, first_capacity(cfg, max_page))?,
    };
    let mut stats = PhotonStats::default();
    let mut batch = cfg.batch;
    let mut done = 0u64;
    while done < cfg.photons {
        let paths = (cfg.photons - done).min(batch as u64) as u32;
        let page = &store.page;
        store.apply(gpu, planner.before(page.count, page.capacity, paths, done))?;
        let before = store.page.count as u32;
        let counters = run_batch(
            gpu,
            cfg,
            &emitters,
            &emitter_buf,
            &counters_buf,
            on_gpu,
            &store.page,
            done,
            paths,
        )?;
        if counters.overflow == 0 {
            store.page.count = counters.stored as u64;
            stats.add_batch(paths, before, &counters);
            planner.record(paths, (counters.stored - before) as u64);
            done += paths as u64;
            progress(done, cfg.photons);
            continue;
        }
        stats.reruns += 1;
        let need = (counters.stored - before) as u64;
        let page = &store.page;
        match planner.after_overflow(page.count, page.capacity, need, paths, done) {
            StoreAction::HalveBatch if paths > 1 => batch = paths / 2,
            StoreAction::HalveBatch => {
                return Err(Error::Invalid(format!(
                    "one photon path stores more photons than the device's largest buffer \
                     binding holds ({max_page})"
                )));
            }
            action => store.apply(gpu, action)?,
        }
    }
    let mut pages = store.pages;
    if store.page.count > 0 || pages.is_empty() {
        pages.push(store.page);
    }
    stats.pages = pages.len() as u32;
    stats.trace_ms = ms_since(t);
    Ok(GpuPhotons { pages, stats })
}

/// The pages closed so far and the one being filled.
struct Store {
    pages: Vec<PhotonPage>,
    page: PhotonPage,
}

impl Store {
    fn apply(&mut self, gpu: &Gpu, action: StoreAction) -> Result<()> {
        match action {
            StoreAction::Keep | StoreAction::HalveBatch => {}
            StoreAction::Grow(capacity) => {
                let grown = new_page(gpu, capacity)?;
                let mut encoder = gpu.encoder("grow photon store");
                let bytes = self.page.count * PHOTON_BYTES;
                encoder.copy_buffer_to_buffer(&self.page.buffer, 0, &grown.buffer, 0, bytes);
                gpu.submit_and_wait(encoder)?;
                self.page = PhotonPage {
                    count: self.page.count,
                    ..grown
                };
            }
            StoreAction::NewPage(capacity) => {
                let full = std::mem::replace(&mut self.page, new_page(gpu, capacity)?);
                self.pages.push(full);
            }
        }
        Ok(())
    }
}

/// One `photon_trace` dispatch of `paths` paths from path `done`; returns the counters.
#[allow(clippy::too_many_arguments)]
fn run_batch(
    gpu: &Gpu,
    cfg: &PhotonConfig,
    emitters: &[Emitter],
    emitter_buf: &wgpu::Buffer,
    counters_buf: &wgpu::Buffer,
    on_gpu: &GpuScene,
    page: &PhotonPage,
    done: u64,
    paths: u32,
) -> Result<TraceCounters> {
    let params_buf = gpu.uniform("trace params", &cfg.params(emitters, done as u32, paths));
    let start = TraceCounters {
        stored: page.count as u32,
        capacity: page.capacity as u32,
        ..Default::default()
    };
    gpu.queue
        .write_buffer(counters_buf, 0, bytemuck::bytes_of(&start));
    let mut encoder = gpu.encoder("photon trace");
    gpu.dispatch_groups(
        &mut encoder,
        "photon_trace",
        &[
            &[
                &params_buf,
                emitter_buf,
                &on_gpu.materials,
                &page.buffer,
                counters_buf,
            ],
            &on_gpu.geometry(),
        ],
        gpu.groups("photon_trace", paths)?,
    )?;
    gpu.submit_and_wait(encoder)?;
    gpu.read::<TraceCounters>(counters_buf, 1)?
        .pop()
        .ok_or_else(|| Error::Gpu("trace counters readback was short".into()))
}
