//! The photon pass on the host: settings, the lights prepared as emitters, the batch loop
//! with its growable store, and the statistics both the GPU and the CPU mirror report.

use crate::budget::Budget;
use crate::error::{Error, Result};
use crate::types::{Emitter, Light, Photon, TraceCounters, TraceParams, light_kind};
use serde::Deserialize;

/// Most photons one bake may emit: path indices are u32.
pub const MAX_PHOTONS: u64 = u32::MAX as u64;

/// Photon counts a bake accepts, for scene files and command-line overrides.
pub fn check_photon_count(photons: u64) -> std::result::Result<(), String> {
    if photons == 0 || photons > MAX_PHOTONS {
        return Err(format!(
            "photons must be within 1..={MAX_PHOTONS}, got {photons}"
        ));
    }
    Ok(())
}

/// Loop iterations (grid cells plus disk tests, summed over a path's bounces) one path may
/// spend. A path in a sane scene spends a few hundred; llvmpipe silently stops loops of an
/// invocation after about 65k iterations, so the budget keeps far below that and counts the
/// paths it stops (`aborted`) instead of losing them unseen.
pub const ITERATION_BUDGET: u32 = 16_384;

/// Emitted photons per dispatch.
pub const DEFAULT_BATCH: u32 = 1 << 20;

#[derive(Clone, Debug, PartialEq)]
pub struct PhotonConfig {
    pub photons: u64,
    pub seed: u32,
    pub max_depth: u32,
    pub store: StoreRange,
    pub batch: u32,
    pub iteration_budget: u32,
    /// Photon-store capacity of the first batch, in photons (0: about two per emitted photon).
    /// Tests set it small to exercise growth.
    pub initial_capacity: u64,
    /// Largest store page in photons (0: what the device's largest binding holds). Tests set
    /// it small to exercise new pages and smaller batches.
    pub page_limit: u64,
    /// The memory budget the stored photons must fit, with their copies through the bake
    /// (`STORED_PHOTON_BYTES` each): checked from the first batch's rate of stores on.
    pub memory: Budget,
}

/// What one stored photon costs through the bake: its record in the store, the read-back
/// copy and the binned copy, and its bin index; checked in `StorePlanner::check_budget`.
/// Measured: 92 B a stored photon on the mirror (peak RSS of `render scenes/cornell.toml
/// --cpu` at 64², 1 M against 4 M photons: 200 MB more for 2.18 M more stored).
pub const STORED_PHOTON_BYTES: u64 = 3 * size_of::<Photon>() as u64 + 8;

/// Which hits of a photon path store a photon.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum StoreRange {
    #[default]
    Indirect,
    All,
}

impl StoreRange {
    /// The smallest stored bounce count.
    pub fn min_bounce(self) -> u32 {
        match self {
            StoreRange::Indirect => 1,
            StoreRange::All => 0,
        }
    }
}

impl PhotonConfig {
    pub fn validate(&self) -> Result<()> {
        check_photon_count(self.photons).map_err(Error::Invalid)?;
        if self.max_depth == 0 || self.batch == 0 || self.iteration_budget == 0 {
            return Err(Error::Invalid(
                "max_depth, batch and iteration budget must be positive".into(),
            ));
        }
        Ok(())
    }

    /// The dispatch uniform of one batch.
    pub fn params(&self, emitters: &[Emitter], path_offset: u32, path_count: u32) -> TraceParams {
        TraceParams {
            seed: self.seed,
            path_offset,
            path_count,
            emitter_count: emitters.len() as u32,
            max_depth: self.max_depth,
            min_bounce: self.store.min_bounce(),
            iteration_budget: self.iteration_budget,
            _pad0: 0,
        }
    }
}

/// The power a light's photons share photons by: the mean of its RGB power.
fn light_weight(l: &Light) -> f64 {
    l.power.iter().map(|&p| p as f64).sum::<f64>() / 3.0
}

/// Mean of the smooth spot falloff over the cone it is sampled in (uniform in cos θ):
/// 1 on [cos_inner, 1], smoothstep on [cos_outer, cos_inner], whose mean is one half.
fn spot_falloff_mean(l: &Light) -> f32 {
    let (co, ci) = (l.cos_outer as f64, l.cos_inner as f64);
    if ci <= co {
        return 1.0;
    }
    (((ci - co) * 0.5 + (1.0 - ci)) / (1.0 - co)) as f32
}

/// Shares `photons` among the lights in proportion to power (largest remainders, so the counts
/// sum exactly) and prepares each light with a share for emission. Lights without power emit
/// nothing and are left out.
pub fn emitters(lights: &[Light], photons: u64) -> Result<Vec<Emitter>> {
    let total: f64 = lights.iter().map(light_weight).sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(Error::Invalid(
            "the scene's lights emit no power: photon tracing has nothing to trace".into(),
        ));
    }
    let exact: Vec<f64> = lights
        .iter()
        .map(|l| photons as f64 * light_weight(l) / total)
        .collect();
    let mut counts: Vec<u64> = exact.iter().map(|&x| x.floor() as u64).collect();
    let mut short = photons - counts.iter().sum::<u64>();
    let mut order: Vec<usize> = (0..lights.len()).collect();
    order.sort_by(|&a, &b| {
        let (ra, rb) = (exact[a] - exact[a].floor(), exact[b] - exact[b].floor());
        rb.total_cmp(&ra).then(a.cmp(&b))
    });
    for &i in order.iter().cycle() {
        if short == 0 {
            break;
        }
        if light_weight(&lights[i]) > 0.0 {
            counts[i] += 1;
            short -= 1;
        }
    }
    let mut out = Vec::new();
    let mut first = 0u64;
    for (light, &count) in lights.iter().zip(&counts) {
        if count == 0 {
            continue;
        }
        let falloff_norm = if light.kind == light_kind::SPOT {
            1.0 / spot_falloff_mean(light)
        } else {
            1.0
        };
        out.push(Emitter {
            light: *light,
            first: first as u32,
            count: count as u32,
            photon_power: light.power.map(|p| p / count as f32),
            falloff_norm,
            ..Default::default()
        });
        first += count;
    }
    Ok(out)
}

/// How the photon pass went: counts summed over batches, and timings.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PhotonStats {
    pub emitted: u64,
    pub stored: u64,
    pub escaped: u64,
    pub absorbed: u64,
    pub depth_capped: u64,
    /// Paths stopped by the iteration budget (0 in any sane scene).
    pub aborted: u64,
    pub batches: u32,
    /// Batches traced again after the store overflowed and grew.
    pub reruns: u32,
    /// Separate store buffers (each at most the device's largest binding).
    pub pages: u32,
    pub trace_ms: f64,
}

impl PhotonStats {
    pub fn add_batch(&mut self, paths: u32, before: u32, c: &TraceCounters) {
        self.emitted += paths as u64;
        self.stored += (c.stored - before) as u64;
        self.escaped += c.escaped as u64;
        self.absorbed += c.absorbed as u64;
        self.depth_capped += c.depth_capped as u64;
        self.aborted += c.aborted as u64;
        self.batches += 1;
    }

    pub fn stored_ratio(&self) -> f64 {
        self.stored as f64 / self.emitted.max(1) as f64
    }
}

/// Stored photons on the host, with how they were made.
#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    pub photons: Vec<Photon>,
    pub stats: PhotonStats,
}

impl PhotonMap {
    /// Sorts by `Photon::key`: the GPU's slot order depends on scheduling, this order does not.
    pub fn sort(&mut self) {
        self.photons.sort_unstable_by_key(|p| p.key());
    }
}

/// Photons one store page may hold: the device's limit, or the configured one if smaller.
pub fn page_photons(cfg: &PhotonConfig, device_limit: u64) -> u64 {
    match cfg.page_limit {
        0 => device_limit,
        n => n.min(device_limit),
    }
}

/// Store capacity (in photons) to try first.
pub fn first_capacity(cfg: &PhotonConfig, max_page: u64) -> u64 {
    let guess = if cfg.initial_capacity > 0 {
        cfg.initial_capacity
    } else {
        2 * cfg.photons.min(cfg.batch as u64)
    };
    guess.clamp(1, max_page.max(1))
}

/// What the batch loop does with the photon store.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoreAction {
    Keep,
    /// Grow the current page to this many photons, keeping its contents.
    Grow(u64),
    /// Close the current page and start one of this many photons.
    NewPage(u64),
    /// Even an empty page cannot hold the batch: trace half as many paths at a time.
    HalveBatch,
}

/// Sizes the store from the rate of stores per path seen so far, so that batches rarely
/// overflow: before each batch it makes room for what the batch will likely store, and after
/// an overflow (which tells exactly what the batch needed) it makes room for that.
#[derive(Clone, Debug)]
pub struct StorePlanner {
    /// Largest page, in photons.
    pub max_page: u64,
    pub total_paths: u64,
    paths_seen: u64,
    stores_seen: u64,
}

impl StorePlanner {
    pub fn new(max_page: u64, total_paths: u64) -> StorePlanner {
        StorePlanner {
            max_page,
            total_paths,
            paths_seen: 0,
            stores_seen: 0,
        }
    }

    /// A batch of `paths` paths stored `stores` photons.
    pub fn record(&mut self, paths: u32, stores: u64) {
        self.paths_seen += paths as u64;
        self.stores_seen += stores;
    }

    /// Refuses a bake whose photons, at the rate of stores per path seen so far, would take
    /// more than `budget` (`STORED_PHOTON_BYTES` each), naming the photon count that fits.
    pub fn check_budget(&self, budget: &Budget) -> Result<()> {
        let Some(rate) = self.rate() else {
            return Ok(());
        };
        let stored = rate * self.total_paths as f64;
        let bytes = (stored * STORED_PHOTON_BYTES as f64).min(u64::MAX as f64) as u64;
        let what = format!(
            "{} photon paths, storing {rate:.2} photons each so far,",
            self.total_paths
        );
        budget
            .check(&what, bytes, |factor| {
                let fits = (self.total_paths as f64 / factor).floor() as u64;
                format!("lower `photons` to {fits} or fewer")
            })
            .map_err(Error::Invalid)
    }

    /// Stores per path so far, once a batch has completed.
    fn rate(&self) -> Option<f64> {
        (self.paths_seen > 0).then(|| self.stores_seen as f64 / self.paths_seen as f64)
    }

    /// Photons the paths from `done` on will store, with 5 % to spare.
    fn projected_rest(&self, rate: f64, done: u64) -> u64 {
        (rate * (self.total_paths - done) as f64 * 1.05).ceil() as u64
    }

    fn room_for(&self, count: u64, capacity: u64, need: u64, rest: u64) -> Option<StoreAction> {
        if count + need <= capacity {
            Some(StoreAction::Keep)
        } else if count + need <= self.max_page {
            Some(StoreAction::Grow(
                (count + rest.max(need)).min(self.max_page),
            ))
        } else if count > 0 {
            Some(StoreAction::NewPage(rest.max(need).min(self.max_page)))
        } else {
            None
        }
    }

    /// Before a batch of `paths` starting at path `done`, into a page holding `count` of
    /// `capacity` photons.
    pub fn before(&self, count: u64, capacity: u64, paths: u32, done: u64) -> StoreAction {
        let Some(rate) = self.rate() else {
            return StoreAction::Keep;
        };
        let rest = self.projected_rest(rate, done);
        let need = (rate * paths as f64 * 1.1).ceil() as u64;
        self.room_for(count, capacity, need, rest)
            .unwrap_or(StoreAction::Keep)
    }

    /// After a batch of `paths` starting at `done` overflowed, needing `need` slots.
    pub fn after_overflow(
        &self,
        count: u64,
        capacity: u64,
        need: u64,
        paths: u32,
        done: u64,
    ) -> StoreAction {
        // Before any batch completed, the overflowing batch's own rate is the best guess.
        let rate = self.rate().unwrap_or(need as f64 / paths as f64);
        let rest = self.projected_rest(rate, done);
        match self.room_for(count, capacity, need, rest) {
            Some(action) => action,
            None => StoreAction::HalveBatch,
        }
    }
}

/// Number of stored photons within `radius` of each splat's centre (a CPU counting sort into
/// cells of edge `radius`; for statistics, not for the bake).
pub fn photons_within(splats: &[crate::types::Splat], photons: &[Photon], radius: f32) -> Vec<u32> {
    use glam::{IVec3, Vec3};
    use rayon::prelude::*;
    use std::collections::HashMap;
    let cell = |p: Vec3| (p / radius).floor().as_ivec3();
    let mut cells: HashMap<IVec3, Vec<Vec3>> = HashMap::new();
    for p in photons {
        let p = Vec3::from(p.position);
        cells.entry(cell(p)).or_default().push(p);
    }
    let r2 = radius * radius;
    splats
        .par_iter()
        .map(|s| {
            let c = Vec3::from(s.center);
            let home = cell(c);
            let mut n = 0u32;
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        if let Some(list) = cells.get(&(home + IVec3::new(dx, dy, dz))) {
                            n += list.iter().filter(|p| p.distance_squared(c) <= r2).count() as u32;
                        }
                    }
                }
            }
            n
        })
        .collect()
}
