//! The GPU side: a headless device, compiled stage pipelines, buffer helpers, and the host code
//! that records each stage's dispatches.

pub mod bins;
pub mod em;
pub mod exec;
pub mod grid;
mod layout;
pub mod passes;
pub mod photon_view;
pub mod photons;
pub mod present;
pub mod reference;
pub mod renderer;
pub mod scan;
pub mod scene;

pub mod tone;

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bytemuck::Pod;
use wgpu::util::DeviceExt;

use crate::error::{Error, Result};
use crate::shaders::{MAX_PAGES, PAGE_BINDING_STEP, PagedArray, Paging};
use crate::shaders::{Pass, Stage};

/// Which graphics API to run on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum BackendChoice {
    /// `WGPU_BACKEND` if set, else Vulkan, else OpenGL (GLES via EGL).
    #[default]
    Auto,
    Vulkan,
    Gl,
}

const INSTALL_HINT: &str = "install a Vulkan driver; without a GPU, Mesa's software \
    rasterizer lavapipe works: `sudo apt-get install mesa-vulkan-drivers` (Debian/Ubuntu) or \
    `sudo dnf install mesa-vulkan-drivers` (Fedora); Mesa's OpenGL (EGL) is used as a fallback";

/// The window a device must present to: the instance description with its display (made
/// anew for each backend tried) and the window. Any windowing library's handles will do; the
/// viewer's are winit's.
type Window<'a> = (
    &'a dyn Fn() -> wgpu::InstanceDescriptor,
    &'a Arc<dyn wgpu::DisplayAndWindowHandle>,
);
type Surface = wgpu::Surface<'static>;

/// Compute pipelines compiled (WGSL to the driver's code) and the time they took.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Compiled {
    pub pipelines: u32,
    pub ms: f64,
}

/// A device (headless, or able to present to a window) and everything recorded on it.
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// Subgroup operations are enabled (`wgpu::Features::SUBGROUP`, where the device has it).
    pub subgroups: bool,
    /// Bytes of one page of a paged array (`shaders::Paging`): the largest storage binding,
    /// or less where a test makes small scenes page.
    page_bytes: u64,
    pipelines: Mutex<HashMap<String, wgpu::ComputePipeline>>,
    /// The compute pipelines compiled so far and their time, which the stages that first
    /// asked for them counted in theirs (a GPU driver's compile can outweigh a small bake).
    compiled: Mutex<Compiled>,
    /// The adapter the device came from (a window's surface asks it what it supports).
    pub adapter: wgpu::Adapter,
    /// First uncaptured device error, surfaced as an `Error` after the next wait
    /// (wgpu's default handler panics).
    error: Arc<Mutex<Option<String>>>,
}

impl Gpu {
    /// A shader module of this project's WGSL: bounds-checked, but without the counter wgpu
    /// otherwise adds to every loop against infinite ones. Every loop of these shaders ends:
    /// `for` loops run over a range, a list or a fixed count, and the grid walk's `loop` spends
    /// a step budget. On llvmpipe the counters made the lobe fit 1.9x slower.
    pub fn shader_module(&self, name: &str, source: String) -> wgpu::ShaderModule {
        let checks = wgpu::ShaderRuntimeChecks {
            force_loop_bounding: false,
            ..wgpu::ShaderRuntimeChecks::checked()
        };
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some(name),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        };
        // SAFETY: bounds checks stay on, and every loop terminates (above), which is all that
        // leaving out the loop counter asks.
        unsafe { self.device.create_shader_module_trusted(desc, checks) }
    }

    /// Opens a device on the chosen backend (see `BackendChoice`).
    pub fn new(choice: BackendChoice) -> Result<Gpu> {
        Self::choose(choice, None).map(|(gpu, _)| gpu)
    }

    /// A device that can present to `window` (the viewer), with the window's surface.
    pub fn for_window<D, W>(
        choice: BackendChoice,
        display: &D,
        window: &Arc<W>,
    ) -> Result<(Gpu, wgpu::Surface<'static>)>
    where
        D: wgpu::rwh::HasDisplayHandle + Clone + std::fmt::Debug + Send + Sync + 'static,
        W: wgpu::DisplayAndWindowHandle + 'static,
    {
        let instance = || {
            wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(display.clone()))
        };
        let window: Arc<dyn wgpu::DisplayAndWindowHandle> = window.clone();
        let (gpu, surface) = Self::choose(choice, Some((&instance, &window)))?;
        let surface = surface.ok_or_else(|| Error::Gpu("no surface for the window".into()))?;
        Ok((gpu, surface))
    }

    fn choose(choice: BackendChoice, window: Option<Window<'_>>) -> Result<(Gpu, Option<Surface>)> {
        let attempts: Vec<(&str, wgpu::Backends)> = match choice {
            BackendChoice::Vulkan => vec![("Vulkan", wgpu::Backends::VULKAN)],
            BackendChoice::Gl => vec![("GL", wgpu::Backends::GL)],
            BackendChoice::Auto => match wgpu::Backends::from_env() {
                Some(b) => vec![("WGPU_BACKEND", b)],
                None => vec![
                    ("Vulkan", wgpu::Backends::VULKAN),
                    ("GL", wgpu::Backends::GL),
                ],
            },
        };
        let mut tried = Vec::new();
        for (name, backends) in attempts {
            match Self::open(backends, window)? {
                Some(found) => return Ok(found),
                None => tried.push(name),
            }
        }
        let what = if window.is_some() {
            "that can present to the window"
        } else {
            "with compute shaders"
        };
        Err(Error::NoAdapter(format!(
            "no GPU adapter {what} found (tried: {}); {INSTALL_HINT}",
            tried.join(", ")
        )))
    }

    fn open(
        backends: wgpu::Backends,
        window: Option<Window<'_>>,
    ) -> Result<Option<(Gpu, Option<Surface>)>> {
        let mut desc = match window {
            Some((instance, _)) => instance(),
            None => wgpu::InstanceDescriptor::new_without_display_handle_from_env(),
        };
        desc.backends = backends;
        let instance = wgpu::Instance::new(desc);
        let surface =
            match window {
                Some((_, w)) => Some(instance.create_surface(w.clone()).map_err(|e| {
                    Error::Gpu(format!("cannot make a surface of the window: {e}"))
                })?),
                None => None,
            };
        let adapters = pollster::block_on(instance.enumerate_adapters(backends));
        let Some(adapter) = adapters
            .into_iter()
            .filter(|a| {
                a.get_downlevel_capabilities()
                    .flags
                    .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
                    && surface.as_ref().is_none_or(|s| a.is_surface_supported(s))
            })
            .min_by_key(|a| adapter_rank(a.get_info().device_type))
        else {
            return Ok(None);
        };
        let info = adapter.get_info();
        let limits = required_limits(&adapter.limits());
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lobelight"),
            // Subgroup operations where the device has them: stages then use a variant
            // (`// #ifdef subgroups`), with a portable one for the rest.
            // Float32 blending where the device has it: the splat passes then sum their
            // attributes in f32 rather than f16 (see `frame::accumulation_format`).
            required_features: adapter.features()
                & (wgpu::Features::SUBGROUP | wgpu::Features::FLOAT32_BLENDABLE),
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| {
            Error::Gpu(format!(
                "{} ({:?}): cannot open device: {e}",
                info.name, info.backend
            ))
        })?;
        let error = Arc::new(Mutex::new(None::<String>));
        let slot = error.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut s) = slot.lock() {
                s.get_or_insert_with(|| e.to_string());
            }
        }));
        let subgroups = device.features().contains(wgpu::Features::SUBGROUP);
        let page_bytes = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let gpu = Gpu {
            page_bytes,
            device,
            queue,
            info,
            limits,
            subgroups,
            pipelines: Mutex::new(HashMap::new()),
            compiled: Mutex::new(Compiled::default()),
            error,
            adapter,
        };
        Ok(Some((gpu, surface)))
    }

    /// The compute pipelines compiled so far (`Compiled`).
    pub fn compiled(&self) -> Compiled {
        self.compiled.lock().map(|c| *c).unwrap_or_default()
    }

    pub fn backend_name(&self) -> &'static str {
        match self.info.backend {
            wgpu::Backend::Vulkan => "vulkan",
            wgpu::Backend::Gl => "gl",
            wgpu::Backend::Metal => "metal",
            wgpu::Backend::Dx12 => "dx12",
            wgpu::Backend::BrowserWebGpu => "webgpu",
            wgpu::Backend::Noop => "noop",
        }
    }

    /// The compiled pipeline of a stage of `shaders::STAGES`, compiled on first use.
    pub fn pipeline(&self, stage: Stage) -> Result<wgpu::ComputePipeline> {
        self.specialized(stage, &[])
    }

    /// The pipeline of a stage with values for its pipeline-overridable constants (the
    /// compiler then sees them as literals: fixed loop counts unroll), compiled on first use.
    pub fn specialized(
        &self,
        stage: Stage,
        constants: &[(&str, f64)],
    ) -> Result<wgpu::ComputePipeline> {
        self.variant(stage, &[], constants)
    }

    /// `specialized`, from the stage's source with `defines` defined (see `shaders`).
    pub fn variant(
        &self,
        stage: Stage,
        defines: &[&str],
        constants: &[(&str, f64)],
    ) -> Result<wgpu::ComputePipeline> {
        self.variant_paged(stage, defines, constants, &Paging::default())
    }

    /// `variant`, with its paged arrays split as `paging` says (`Gpu::paging`).
    pub fn variant_paged(
        &self,
        stage: Stage,
        defines: &[&str],
        constants: &[(&str, f64)],
        paging: &Paging,
    ) -> Result<wgpu::ComputePipeline> {
        self.pass_pipeline(stage.into(), defines, constants, paging)
    }

    /// `variant_paged` of one entry point of the stage. A stage of several entry points gets
    /// the layout of every binding it declares (`layout::declared`), so that each pass binds
    /// the same buffers whichever of them it reads; so does a stage that traces, which binds
    /// the scene's whole geometry whichever parts of it (the sky) it reads.
    fn pass_pipeline(
        &self,
        pass: Pass,
        defines: &[&str],
        constants: &[(&str, f64)],
        paging: &Paging,
    ) -> Result<wgpu::ComputePipeline> {
        let stage = pass.stage;
        let key = constants.iter().fold(
            format!("{pass} [{}]{}", defines.join(","), paging.key()),
            |k, (c, v)| format!("{k} {c}={v}"),
        );
        let mut cache = self
            .pipelines
            .lock()
            .map_err(|_| Error::Gpu("pipeline cache poisoned".into()))?;
        if let Some(p) = cache.get(&key) {
            return Ok(p.clone());
        }
        let started = std::time::Instant::now();
        let source = crate::shaders::resolve_stage_paged(stage, defines, paging)?;
        let several = crate::shaders::stage_entries(stage)?.len() > 1;
        let layout = match several || crate::shaders::traces(stage) {
            false => None,
            true => Some(layout::declared(&self.device, stage, &source)?),
        };
        let module = self.shader_module(stage.name(), source);
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(stage.name()),
                layout: layout.as_ref(),
                module: &module,
                entry_point: Some(pass.entry),
                // Every stage writes its workgroup memory before it reads it, so WGSL's
                // zero-fill is wasted work (10 % of em_fit on llvmpipe).
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    zero_initialize_workgroup_memory: false,
                },
                cache: None,
            });
        self.check()?;
        cache.insert(key, pipeline.clone());
        if let Ok(mut c) = self.compiled.lock() {
            c.pipelines += 1;
            c.ms += started.elapsed().as_secs_f64() * 1e3;
        }
        Ok(pipeline)
    }

    /// Records one dispatch of `stage` over `groups` workgroups, binding `buffers` to group 0
    /// in binding order. Large counts are laid out in 2D (see `wgsl/shared/dispatch.wgsl`).
    pub fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        stage: Stage,
        buffers: &[&wgpu::Buffer],
        groups: u32,
    ) -> Result<()> {
        self.dispatch_groups(encoder, stage, &[buffers], groups)
    }

    /// Like `dispatch`, with one buffer list per bind group (group 1 is the traced geometry,
    /// see `wgsl/shared/trace.wgsl`).
    pub fn dispatch_groups(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pass: impl Into<Pass>,
        bind_groups: &[&[&wgpu::Buffer]],
        groups: u32,
    ) -> Result<()> {
        if groups == 0 {
            return Ok(());
        }
        let pass = pass.into();
        let paging = self.paging(pass.stage, bind_groups)?;
        let pipeline = self.pass_pipeline(pass, &[], &[], &paging)?;
        self.dispatch_pipeline(encoder, pass.stage, &pipeline, &paging, bind_groups, groups)
    }

    /// Like `dispatch` (of the stage's variant of `defines`), with the workgroup counts read on
    /// the device from `args` at `offset` (three u32s, as a stage before wrote them): a
    /// dispatch sized by what that stage found.
    pub fn dispatch_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (stage, defines): (Stage, &[&str]),
        bind_groups: &[&[&wgpu::Buffer]],
        (args, offset): (&wgpu::Buffer, u64),
    ) -> Result<()> {
        let paging = self.paging(stage, bind_groups)?;
        let pipeline = self.variant_paged(stage, defines, &[], &paging)?;
        let mut pass = self.bound_pass(encoder, stage, &pipeline, &paging, bind_groups)?;
        pass.dispatch_workgroups_indirect(args, offset);
        Ok(())
    }

    /// Records one dispatch of an already compiled (e.g. specialized) pipeline.
    pub fn dispatch_pipeline(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        stage: Stage,
        pipeline: &wgpu::ComputePipeline,
        paging: &Paging,
        bind_groups: &[&[&wgpu::Buffer]],
        groups: u32,
    ) -> Result<()> {
        if groups == 0 {
            return Ok(());
        }
        let (x, y) = self.dispatch_dims(groups)?;
        let mut pass = self.bound_pass(encoder, stage, pipeline, paging, bind_groups)?;
        pass.dispatch_workgroups(x, y, 1);
        Ok(())
    }

    /// A compute pass of `stage` with `pipeline` set and `bind_groups` bound (one buffer list
    /// per group, paged as `paging` says), ready for its dispatch.
    fn bound_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        stage: Stage,
        pipeline: &wgpu::ComputePipeline,
        paging: &Paging,
        bind_groups: &[&[&wgpu::Buffer]],
    ) -> Result<wgpu::ComputePass<'e>> {
        let mut made = Vec::with_capacity(bind_groups.len());
        for (g, buffers) in bind_groups.iter().enumerate() {
            let entries = self.paged_entries(stage, g as u32, buffers, paging)?;
            made.push(self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(stage.name()),
                layout: &pipeline.get_bind_group_layout(g as u32),
                entries: &entries,
            }));
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(stage.name()),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        for (g, bind_group) in made.iter().enumerate() {
            pass.set_bind_group(g as u32, bind_group, &[]);
        }
        Ok(pass)
    }

    /// Splits a workgroup count into (x, y) within the per-dimension limit; shaders bound-check
    /// the few extra workgroups of the last row.
    pub fn dispatch_dims(&self, groups: u32) -> Result<(u32, u32)> {
        let max = self.limits.max_compute_workgroups_per_dimension;
        let x = groups.min(max);
        let y = groups.div_ceil(x);
        if y > max {
            return Err(Error::DeviceLimit(format!(
                "dispatch of {groups} workgroups exceeds this device's {max}² limit"
            )));
        }
        Ok((x, y))
    }

    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        self.device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }

    /// Records `what` into a fresh encoder labelled `label`, submits it and waits: one
    /// submission of the host's `draw`s (their `record`s record into a caller's encoder).
    pub fn record_and_wait<T>(
        &self,
        label: &str,
        what: impl FnOnce(&mut wgpu::CommandEncoder) -> Result<T>,
    ) -> Result<T> {
        let mut encoder = self.encoder(label);
        let recorded = what(&mut encoder)?;
        self.submit_and_wait(encoder)?;
        Ok(recorded)
    }

    /// Submits and waits until the device is idle, then reports any device error.
    pub fn submit_and_wait(&self, encoder: wgpu::CommandEncoder) -> Result<()> {
        self.queue.submit(Some(encoder.finish()));
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the device: {e}")))?;
        self.check()
    }

    fn check(&self) -> Result<()> {
        match self.error.lock() {
            Ok(mut e) => match e.take() {
                Some(msg) => Err(Error::Gpu(msg)),
                None => Ok(()),
            },
            Err(_) => Err(Error::Gpu("error slot poisoned".into())),
        }
    }

    /// A storage buffer holding `data`; empty data gives one zeroed element (at least 4
    /// bytes): empty bindings are invalid, and an array binding needs one whole element.
    pub fn storage<T: Pod>(&self, label: &str, data: &[T]) -> Result<wgpu::Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        self.check_size(label, bytes.len() as u64)?;
        let one_zeroed = vec![0u8; size_of::<T>().max(4)];
        let contents = if bytes.is_empty() { &one_zeroed } else { bytes };
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            }))
    }

    /// A zeroed storage buffer of `bytes` bytes (rounded up to 4, at least 4).
    pub fn storage_zeroed(&self, label: &str, bytes: u64) -> Result<wgpu::Buffer> {
        self.check_size(label, bytes)?;
        Ok(self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.max(4).next_multiple_of(4),
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        }))
    }

    pub fn uniform<T: Pod>(&self, label: &str, value: &T) -> wgpu::Buffer {
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::bytes_of(value),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            })
    }

    /// Largest storage binding this device allows, in bytes: every capacity derives from it.
    pub fn max_binding_bytes(&self) -> u64 {
        self.limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
    }

    /// A 2D texture of one mip level and one sample.
    pub fn texture_2d(
        &self,
        label: &str,
        (width, height): (u32, u32),
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> wgpu::Texture {
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    }

    /// Refuses an image this device cannot hold in one HDR binding (16 bytes a pixel), before
    /// any work: the frame stages bind the whole image.
    pub fn check_image(&self, width: u32, height: u32) -> Result<()> {
        let bytes = width as u64 * height as u64 * 16;
        let max = self.max_binding_bytes();
        if bytes > max {
            return Err(Error::DeviceLimit(format!(
                "a {width}×{height} image needs {bytes} bytes of HDR pixels, more than this \
                 device's largest storage binding ({max} bytes, about {} pixels): render \
                 smaller",
                max / 16
            )));
        }
        Ok(())
    }

    /// Refuses a buffer larger than the device allows, or than a paged array can take (its
    /// bindings are checked when bound, `paged_entries`).
    fn check_size(&self, label: &str, bytes: u64) -> Result<()> {
        let max = self
            .limits
            .max_buffer_size
            .min(self.max_binding_bytes() * MAX_PAGES as u64);
        if bytes > max {
            return Err(Error::DeviceLimit(format!(
                "{label}: {bytes} bytes exceed the most this device holds in one array ({max} \
                 bytes: at most {MAX_PAGES} storage bindings of {} bytes, within its largest \
                 buffer)",
                self.max_binding_bytes()
            )));
        }
        Ok(())
    }

    /// Bytes of the largest paged array of `stride`-byte elements: `MAX_PAGES` pages, within
    /// the largest buffer.
    pub fn max_array_bytes(&self, stride: u64) -> u64 {
        let stride = stride.max(1);
        let page = stride << (self.page_bytes / stride).max(1).ilog2();
        (page * MAX_PAGES as u64).min(self.limits.max_buffer_size)
    }

    /// Bytes of the largest array that binds as one page (arrays of 16-byte records).
    pub fn page_bytes(&self) -> u64 {
        self.page_bytes
    }

    /// Whether the adapter is a software rasterizer (lavapipe, llvmpipe's GL), which runs the
    /// stages on the CPU's cores.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Makes arrays of more than `bytes` bytes page (tests of paging on small scenes); at most
    /// the largest storage binding, at least 64 KiB (pages of records up to 64 bytes then start
    /// at multiples of 4 KiB, aligned for any device's binding offsets).
    pub fn with_page_bytes(mut self, bytes: u64) -> Gpu {
        self.page_bytes = bytes.clamp(1 << 16, self.max_binding_bytes());
        self
    }

    /// How `stage`'s paged arrays split, bound to `bind_groups` (one buffer list per group, in
    /// binding order): an array larger than one page takes windows of 2^shift elements, the
    /// most that fit a page.
    pub fn paging(&self, stage: Stage, bind_groups: &[&[&wgpu::Buffer]]) -> Result<Paging> {
        self.paging_by(stage, |group, binding| {
            bind_groups
                .get(group as usize)?
                .get(binding as usize)
                .copied()
        })
    }

    /// `paging` of a stage whose buffers `buffer(group, binding)` finds.
    pub fn paging_by<'b>(
        &self,
        stage: Stage,
        buffer: impl Fn(u32, u32) -> Option<&'b wgpu::Buffer>,
    ) -> Result<Paging> {
        let mut arrays = Vec::new();
        for p in crate::shaders::paged_bindings(stage)? {
            let Some(buffer) = buffer(p.group, p.binding) else {
                continue;
            };
            let size = buffer.size();
            if size <= self.page_bytes {
                continue;
            }
            let per_page = self.page_bytes / p.stride.max(1) as u64;
            let shift = per_page.max(1).ilog2();
            let page = (p.stride as u64) << shift;
            let pages = size.div_ceil(page) as u32;
            if pages > MAX_PAGES {
                return Err(Error::DeviceLimit(format!(
                    "{stage}: '{}' holds {size} bytes, more than the {MAX_PAGES} pages of \
                     {page} bytes a paged array is bound as on this device",
                    p.name
                )));
            }
            arrays.push(PagedArray {
                name: p.name,
                pages,
                shift,
            });
        }
        Ok(Paging { arrays })
    }

    /// Bind group entries of group `group` of `stage` for `buffers` in binding order: a paged
    /// array's pages as windows of its buffer (`paging`), every other buffer whole, which
    /// must fit one storage binding.
    pub fn paged_entries<'a>(
        &self,
        stage: Stage,
        group: u32,
        buffers: &[&'a wgpu::Buffer],
        paging: &Paging,
    ) -> Result<Vec<wgpu::BindGroupEntry<'a>>> {
        let numbered: Vec<_> = (0u32..).zip(buffers.iter().copied()).collect();
        self.paged_entries_at(stage, group, &numbered, paging)
    }

    /// `paged_entries` for buffers at the bindings given with them, for an entry point that
    /// binds some of its module's bindings.
    pub fn paged_entries_at<'a>(
        &self,
        stage: Stage,
        group: u32,
        buffers: &[(u32, &'a wgpu::Buffer)],
        paging: &Paging,
    ) -> Result<Vec<wgpu::BindGroupEntry<'a>>> {
        let paged = crate::shaders::paged_bindings(stage)?;
        let mut entries = Vec::with_capacity(buffers.len());
        for &(binding, buffer) in buffers {
            let name = paged
                .iter()
                .find(|p| p.group == group && p.binding == binding)
                .map(|p| (p.name.as_str(), p.stride));
            let Some((layout, stride)) = name.and_then(|(n, s)| paging.of(n).map(|l| (l, s)))
            else {
                if buffer.size() > self.max_binding_bytes() {
                    return Err(Error::DeviceLimit(format!(
                        "{stage}: binding {group}.{binding} holds {} bytes, more than this \
                         device's largest storage binding ({} bytes)",
                        buffer.size(),
                        self.max_binding_bytes()
                    )));
                }
                entries.push(wgpu::BindGroupEntry {
                    binding,
                    resource: buffer.as_entire_binding(),
                });
                continue;
            };
            let page = (stride as u64) << layout.shift;
            for k in 0..layout.pages {
                let offset = k as u64 * page;
                // A page past the buffer's end (never indexed) binds the first page again.
                let (offset, size) = match buffer.size().checked_sub(offset) {
                    Some(left) if left > 0 => (offset, left.min(page)),
                    _ => (0, page.min(buffer.size())),
                };
                entries.push(wgpu::BindGroupEntry {
                    binding: binding + k * PAGE_BINDING_STEP,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer,
                        offset,
                        size: wgpu::BufferSize::new(size),
                    }),
                });
            }
        }
        Ok(entries)
    }

    /// Copies `count` elements of `buffer` back to the host.
    pub fn read<T: Pod>(&self, buffer: &wgpu::Buffer, count: usize) -> Result<Vec<T>> {
        let bytes = (count * std::mem::size_of::<T>()) as u64;
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: bytes.next_multiple_of(4),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.encoder("readback");
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes.next_multiple_of(4));
        self.submit_and_wait(encoder)?;
        let (tx, rx) = std::sync::mpsc::channel();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for readback: {e}")))?;
        rx.recv()
            .map_err(|_| Error::Gpu("readback callback dropped".into()))?
            .map_err(|e| Error::Gpu(format!("mapping readback buffer: {e}")))?;
        let view = staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| Error::Gpu(format!("reading mapped buffer: {e}")))?;
        let out = bytemuck::pod_collect_to_vec(&view[..bytes as usize]);
        drop(view);
        staging.unmap();
        Ok(out)
    }
}

/// Bind group entries for `buffers`, bound whole at bindings 0, 1, 2…
pub(crate) fn buffer_entries<'a>(buffers: &[&'a wgpu::Buffer]) -> Vec<wgpu::BindGroupEntry<'a>> {
    buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect()
}

/// Lower is better: a real GPU before a software one.
fn adapter_rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// WebGPU's downlevel defaults (what every backend we target offers), raised only where our
/// stages benefit: buffer sizes and dispatch dimensions up to what the adapter allows.
fn required_limits(adapter: &wgpu::Limits) -> wgpu::Limits {
    let base = wgpu::Limits::downlevel_defaults();
    wgpu::Limits {
        max_buffer_size: adapter.max_buffer_size,
        max_storage_buffer_binding_size: adapter.max_storage_buffer_binding_size,
        // The compute splatter binds 11 (`gpu::passes::SPLAT_COMPUTE_BUFFERS`); where the adapter
        // offers fewer, it is not used. A paged array takes one a page (`Gpu::paging`).
        max_storage_buffers_per_shader_stage: adapter.max_storage_buffers_per_shader_stage.min(32),
        max_storage_textures_per_shader_stage: adapter.max_storage_textures_per_shader_stage.min(4),
        max_compute_workgroups_per_dimension: adapter.max_compute_workgroups_per_dimension,
        // The attribute pass writes four RGBA float targets.
        max_color_attachment_bytes_per_sample: adapter.max_color_attachment_bytes_per_sample,
        ..base
    }
}
