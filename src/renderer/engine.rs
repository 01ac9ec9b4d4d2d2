//! The engine stages run on, chosen once (`Engine::open`), and the bake's passes from host
//! data to host data on it (`host`), the same calls on the device and the mirror.

use std::sync::Arc;

use crate::bins::{DepositBins, PhotonBins};
use crate::cpu::CpuExecutor;
use crate::em::{EmConfig, FitShape, LobeMap};
use crate::error::{Error, Result};
use crate::gpu::exec::GpuExecutor;
use crate::gpu::{BackendChoice, Compiled, Gpu};
use crate::host::{self, FitFrom, PhotonPages};
use crate::plan::BakeLimits;
use crate::types::{BinParams, DepositParams, GridParams, Material, Splat};

/// Which engine to run on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum EngineChoice {
    /// The device, but the CPU mirror where none is found, or where the device is a software
    /// rasterizer (lavapipe, llvmpipe) and no backend was named: there the mirror bakes and
    /// draws still images in about half the time (docs/measurements.md).
    #[default]
    Auto,
    /// The CPU mirrors.
    Mirror,
    /// The device, a software rasterizer too; the CPU mirror where none is found and no
    /// backend was named.
    Device,
}

/// Why `Engine::open` gave the mirror where a device was asked for or preferred.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Fallback {
    /// No adapter was found (why).
    NoDevice(String),
    /// The adapter (named) is a software rasterizer, which the mirror outruns.
    Software(String),
}

impl std::fmt::Display for Fallback {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fallback::NoDevice(why) => write!(f, "running on the CPU mirror (slower): {why}"),
            Fallback::Software(name) => write!(
                f,
                "{name} is a software rasterizer: the bake and the image run on the CPU mirror \
                 ({} threads), faster here",
                rayon::current_num_threads()
            ),
        }
    }
}

/// The engine stages run on: a device, or the CPU mirrors.
#[derive(Clone)]
pub enum Engine {
    Mirror,
    Device(Arc<Gpu>),
}

impl Engine {
    /// Opens the engine `choice` names on `backend`, and why it is the mirror where the
    /// device was asked for or preferred. A backend named that has no adapter stays an error.
    pub fn open(
        choice: EngineChoice,
        backend: BackendChoice,
    ) -> Result<(Engine, Option<Fallback>)> {
        if choice == EngineChoice::Mirror {
            return Ok((Engine::Mirror, None));
        }
        let gpu = match Gpu::new(backend) {
            Ok(gpu) => gpu,
            Err(Error::NoAdapter(why)) if backend == BackendChoice::Auto => {
                return Ok((Engine::Mirror, Some(Fallback::NoDevice(why))));
            }
            Err(e) => return Err(e),
        };
        if choice == EngineChoice::Auto && backend == BackendChoice::Auto && gpu.is_software() {
            let software = Fallback::Software(gpu.info.name.clone());
            return Ok((Engine::Mirror, Some(software)));
        }
        Ok((Engine::Device(Arc::new(gpu)), None))
    }

    /// The device, where this engine is one.
    pub fn gpu(&self) -> Option<&Gpu> {
        match self {
            Engine::Device(gpu) => Some(gpu),
            Engine::Mirror => None,
        }
    }

    /// Whether this engine is a device (the mirror is not).
    pub fn is_device(&self) -> bool {
        matches!(self, Engine::Device(_))
    }

    /// Whether this engine is a software rasterizer (lavapipe, llvmpipe).
    pub fn is_software(&self) -> bool {
        self.gpu().is_some_and(Gpu::is_software)
    }

    /// The adapter's name, or "CPU mirror".
    pub fn adapter(&self) -> String {
        self.gpu()
            .map_or_else(|| "CPU mirror".to_string(), |g| g.info.name.clone())
    }

    /// The adapter's name, or the CPU mirror with its threads (the benchmarks' `adapter`).
    pub fn adapter_and_threads(&self) -> String {
        match self {
            Engine::Device(_) => self.adapter(),
            Engine::Mirror => format!("CPU mirror ({} threads)", rayon::current_num_threads()),
        }
    }

    /// The graphics API's name, or "cpu".
    pub fn backend(&self) -> &'static str {
        self.gpu().map_or("cpu", Gpu::backend_name)
    }

    /// Refuses an image the engine cannot hold (a device's texture and buffer limits).
    pub fn check_image(&self, width: u32, height: u32) -> Result<()> {
        match self.gpu() {
            Some(gpu) => gpu.check_image(width, height),
            None => Ok(()),
        }
    }

    /// The compute pipelines the device compiled so far, and their time (none on the mirror).
    pub fn compiled(&self) -> Option<Compiled> {
        self.gpu().map(Gpu::compiled)
    }
}

/// Runs `$body` with `$ex` a fresh executor of `$engine` (on the device recording into an
/// encoder labelled `$label`, submitted by the body's last readback) and `$limits` its
/// `BakeLimits`: the one place a host pass meets each engine.
macro_rules! on_executor {
    ($engine:expr, $label:literal, |$ex:ident, $limits:ident| $body:expr) => {
        match $engine {
            Engine::Mirror => {
                let $limits = &BakeLimits::host();
                let $ex = &mut CpuExecutor::default();
                $body
            }
            Engine::Device(gpu) => {
                let $limits = &gpu.bake_limits();
                let mut encoder = gpu.encoder($label);
                let $ex = &mut GpuExecutor::new(gpu, &mut encoder);
                $body
            }
        }
    };
}

/// The bake's passes from host data to host data on this engine (`host`): what the parity
/// tests compare between the device and the mirror, the same code on both.
impl Engine {
    /// What this engine holds of a bake: a device's binding limits and fit shape, or the
    /// mirror's one page of everything.
    pub fn bake_limits(&self) -> BakeLimits {
        match self {
            Engine::Mirror => BakeLimits::host(),
            Engine::Device(gpu) => gpu.bake_limits(),
        }
    }

    /// Bins the photons of `pages`, which landed on `splats` (`host::bin_photons`).
    pub fn bin_photons(
        &self,
        params: &BinParams,
        pages: PhotonPages,
        splats: &[Splat],
    ) -> Result<PhotonBins> {
        on_executor!(self, "binning", |ex, limits| host::bin_photons(
            ex, limits, params, pages, splats
        ))
    }

    /// The deposits of the photons of `pages`, which landed on `splats`, binned over `grid`'s
    /// box (`host::deposit_photons`).
    pub fn deposit_photons(
        &self,
        params: &DepositParams,
        pages: PhotonPages,
        on: (&[Splat], &GridParams),
    ) -> Result<DepositBins> {
        on_executor!(self, "deposits", |ex, limits| host::deposit_photons(
            ex, limits, params, pages, on
        ))
    }

    /// The photon fit of `splats` (with their `materials`) to `from` in `shape`
    /// (`host::fit_lobes`): the mirror runs the device's sum order in any shape, a device
    /// refuses a shape it cannot run. Final gathering traces a scene: `Renderer::fit_lobes`.
    pub fn fit_lobes(
        &self,
        cfg: &EmConfig,
        from: FitFrom,
        of: (&[Splat], &[Material]),
        shape: FitShape,
    ) -> Result<LobeMap> {
        self.check_shape(shape)?;
        on_executor!(self, "lobe fit", |ex, limits| {
            let limits = &BakeLimits {
                fit_shape: shape,
                ..*limits
            };
            host::fit_lobes(ex, limits, cfg, from, of, None)
        })
    }

    /// Refuses a fit shape the device cannot run (the mirror runs every shape).
    pub(super) fn check_shape(&self, shape: FitShape) -> Result<()> {
        match self {
            Engine::Device(gpu)
                if shape.subgroup_reduce && !gpu.bake_limits().fit_shape.subgroup_reduce =>
            {
                Err(Error::DeviceLimit(
                    "this device cannot reduce the fit's sums with subgroup operations".into(),
                ))
            }
            _ => Ok(()),
        }
    }
}
