//! The photon pass on the device: batches of `photon_trace` dispatches appending to a store
//! of pages. After each batch the host reads the counters; on overflow (the counter counts
//! every store attempt, so it tells exactly how much room the batch needed) the page grows,
//! or a new page starts when the device's largest binding is reached, and the batch runs
//! again. Nothing is written out of bounds and nothing is dropped.

use std::time::Instant;

use super::Gpu;
use super::scene::GpuScene;
use crate::cpu::{groups_for, photon_trace};
use crate::error::{Error, Result};
use crate::photons::{
    PhotonConfig, PhotonMap, PhotonStats, emitters, first_capacity, grown_capacity, ms_since,
    page_photons,
};
use crate::scene::Scene;
use crate::types::{Photon, TraceCounters};

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
    let mut pages = Vec::new();
    let mut page = new_page(gpu, first_capacity(cfg, max_page))?;
    let mut stats = PhotonStats::default();
    let mut batch = cfg.batch;
    let mut done = 0u64;
    while done < cfg.photons {
        let paths = (cfg.photons - done).min(batch as u64) as u32;
        let params = cfg.params(&emitters, done as u32, paths);
        let params_buf = gpu.uniform("trace params", &params);
        let before = page.count as u32;
        let start = TraceCounters {
            stored: before,
            capacity: page.capacity as u32,
            ..Default::default()
        };
        gpu.queue
            .write_buffer(&counters_buf, 0, bytemuck::bytes_of(&start));
        let mut encoder = gpu.encoder("photon trace");
        gpu.dispatch_groups(
            &mut encoder,
            "photon_trace",
            &[
                &[
                    &params_buf,
                    &emitter_buf,
                    &on_gpu.materials,
                    &page.buffer,
                    &counters_buf,
                ],
                &on_gpu.geometry(),
            ],
            groups_for(paths, photon_trace::WG),
        )?;
        gpu.submit_and_wait(encoder)?;
        let counters = gpu
            .read::<TraceCounters>(&counters_buf, 1)?
            .pop()
            .ok_or_else(|| Error::Gpu("trace counters readback was short".into()))?;
        if counters.overflow == 0 {
            page.count = counters.stored as u64;
            stats.add_batch(paths, before, &counters);
            done += paths as u64;
            progress(done, cfg.photons);
            continue;
        }
        stats.reruns += 1;
        let needed = counters.stored as u64;
        if needed <= max_page {
            // Room in one binding: grow this page, keeping what it holds.
            let capacity = grown_capacity(needed, done + paths as u64, cfg.photons, max_page);
            let grown = new_page(gpu, capacity)?;
            let mut encoder = gpu.encoder("grow photon store");
            encoder.copy_buffer_to_buffer(
                &page.buffer,
                0,
                &grown.buffer,
                0,
                page.count * PHOTON_BYTES,
            );
            gpu.submit_and_wait(encoder)?;
            page = PhotonPage {
                count: page.count,
                ..grown
            };
        } else if page.count > 0 {
            // This page is full enough: close it and run the batch into a fresh one.
            let rest = needed - page.count;
            pages.push(std::mem::replace(
                &mut page,
                new_page(gpu, rest.min(max_page))?,
            ));
        } else if paths > 1 {
            // One batch alone overflows a whole binding: trace fewer paths at a time.
            batch = paths / 2;
        } else {
            return Err(Error::Invalid(format!(
                "one photon path stores more photons than the device's largest buffer binding \
                 holds ({max_page})"
            )));
        }
    }
    if page.count > 0 || pages.is_empty() {
        pages.push(page);
    }
    stats.pages = pages.len() as u32;
    stats.trace_ms = ms_since(t);
    Ok(GpuPhotons { pages, stats })
}
