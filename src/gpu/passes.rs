//! The splat passes on the device (docs/design.md §8): `splat_visibility` and `splat_attributes`
//! as render passes over instanced triangles, then `shade` as a compute pass over the blended
//! targets. The pipelines are built once per device; the targets once per image size, so a
//! viewer or a benchmark draws frame after frame with nothing but a new camera uniform.

use super::exec::GpuExecutor;
use super::exec::{GEOMETRY_BINDINGS, GeometryBuffers};
use super::scene::GpuScene;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use super::Gpu;
use crate::em::LobeMap;
use crate::error::{Error, Result};
use crate::frame::{Direct, FramePlan, Splatter, Splatting};
use crate::scene::Scene;
use crate::sequence::{DirectBake, TileLists, bin_splat_tiles};
use crate::shaders::Stage;
use crate::shaders::{PAGE_BINDING_STEP, Paging};
use crate::shared::splat::{SPLAT_CORNERS, SPLATS_PER_INSTANCE, instances};
use crate::types::{Camera, ShadeParams, SplatChunk};

/// The format of the blended targets: f32 where the device can blend it, else f16.
pub fn accumulation_format(gpu: &Gpu) -> wgpu::TextureFormat {
    if gpu
        .device
        .features()
        .contains(wgpu::Features::FLOAT32_BLENDABLE)
    {
        wgpu::TextureFormat::Rgba32Float
    } else {
        wgpu::TextureFormat::Rgba16Float
    }
}

const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The visibility pass's front target: the nearest splat's normal, octahedral.
const FRONT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// The attribute pass's binding of the front target.
const FRONT_BINDING: u32 = 10;
/// `fs_baked`'s binding of the splats' shaded radiance (`splat_shade`'s output).
const SHADED_BINDING: u32 = 11;
/// `vs_baked`'s binding of the radius `splat_select` chose for each splat; the list's length
/// and entries follow it.
const DRAWN_BINDING: u32 = 12;
/// The drawing passes' bindings of the surfaces' clips (`drawn_clips`, each after the pass's
/// own: `splat_visibility`'s, `splat_attributes`' and `splat_compute`'s).
const VISIBILITY_CLIP_BINDING: u32 = 5;
const ATTRIBUTES_CLIP_BINDING: u32 = 15;
const COMPUTE_CLIP_BINDING: u32 = 18;
/// The bindings of `wgsl/shared/splat_shading.wgsl` that only the direct bake's shading reads
/// (the lights, the baked light and visibility): `splat_shade` binds them, the fragment
/// shading of the other passes does not, so their derived layouts lack them.
const DIRECT_BAKE_BINDINGS: std::ops::Range<u32> = 7..10;
const TARGETS: usize = 4;
/// The vertices of one instance of the raster passes' draw (a triangle list).
const SPLAT_VERTICES: std::ops::Range<u32> = 0..SPLAT_CORNERS * SPLATS_PER_INSTANCE;

/// What the splat passes read of a baked scene, all on the device.
pub struct PassBuffers<'a> {
    pub splats: &'a wgpu::Buffer,
    pub splat_count: u32,
    pub materials: &'a wgpu::Buffer,
    pub splat_light: &'a wgpu::Buffer,
    pub lobes: &'a wgpu::Buffer,
    /// `lobe_norms::lobe_norms()`, the table the shading divides each lobe by.
    pub lobe_norms: &'a wgpu::Buffer,
    pub lights: &'a wgpu::Buffer,
    /// The direct bake (`sequence::DirectBake`): per-splat irradiance and light visibility.
    pub direct: &'a wgpu::Buffer,
    pub visibility: &'a wgpu::Buffer,
    /// Bind group 1 of tracing stages (`GpuScene::geometry`).
    pub geometry: GeometryBuffers<'a>,
    /// Where each surface's disks end, as the drawing passes read it (`GpuScene::drawn_clips`).
    pub clips: &'a wgpu::Buffer,
    /// The sky's map where the scene has one: `splat_shade` binds it then (the define `sky`).
    pub sky: Option<&'a wgpu::Buffer>,
    /// What `splat_shade` writes for frames of baked direct light: per splat, the radiance
    /// it sends towards the eye.
    pub shaded: &'a wgpu::Buffer,
    /// `splat_list`'s list of the splats a frame draws and shades: its length, and the
    /// indices, chunk by chunk.
    pub selected_count: &'a wgpu::Buffer,
    pub selected: &'a wgpu::Buffer,
    /// `splat_select`'s count per chunk (scanned into `splat_list`'s offsets) and the levels
    /// each visited, and the raster passes' indirect draw of the list and `splat_shade`'s
    /// dispatch.
    pub group_counts: &'a wgpu::Buffer,
    pub visits: &'a wgpu::Buffer,
    pub draw_args: &'a wgpu::Buffer,
    /// What `splat_select` walks (`lod::LodTree`): the merge tree once built, else the
    /// splats' chunks without it; and the radius it chose for each splat this frame.
    pub tree: Option<&'a TreeBuffers>,
    pub drawn: &'a wgpu::Buffer,
    /// Per splat, the word of its merged normals at the level it is drawn at (`LodSpread`).
    pub drawn_normals: &'a wgpu::Buffer,
}

/// A `lod::LodTree` on the device.
pub struct TreeBuffers {
    pub lods: wgpu::Buffer,
    pub spreads: wgpu::Buffer,
    pub chunks: wgpu::Buffer,
    pub order: wgpu::Buffer,
    /// The hierarchy over the chunks (`LodTree::nodes`: the level above the chunks first);
    /// above the top, one word that visits all.
    pub nodes: Vec<NodeLevel>,
    pub visit_all: wgpu::Buffer,
    /// Whether it holds the merge tree (`LodTree::build`) or the chunks alone (`flat`).
    pub merged: bool,
}

/// One level of `lod::LodTree::nodes` on the device.
pub struct NodeLevel {
    pub nodes: wgpu::Buffer,
    pub count: u32,
    /// The levels each node visits in the frame being drawn (`splat_nodes`).
    pub visits: wgpu::Buffer,
}

impl TreeBuffers {
    fn upload(gpu: &Gpu, tree: &crate::lod::LodTree) -> Result<TreeBuffers> {
        let level = |nodes: &Vec<SplatChunk>| -> Result<NodeLevel> {
            Ok(NodeLevel {
                nodes: gpu.storage("chunks' nodes", nodes)?,
                count: nodes.len() as u32,
                visits: gpu.storage_zeroed("levels visited per node", nodes.len() as u64 * 4)?,
            })
        };
        Ok(TreeBuffers {
            lods: gpu.storage("level of detail", &tree.lods)?,
            spreads: gpu.storage("level of detail's normal spread", &tree.spreads)?,
            chunks: gpu.storage("splat chunks", &tree.chunks)?,
            order: gpu.storage("splats by chunk", &tree.order)?,
            nodes: tree.nodes.iter().map(level).collect::<Result<_>>()?,
            visit_all: gpu.storage("levels visited above the top", &[u32::MAX])?,
            merged: tree.merged,
        })
    }
}

impl<'a> PassBuffers<'a> {
    /// Bindings 0–9 of the passes that shade fragments (`splat_attributes`, `splat_compute`):
    /// the camera and the splats, then the eight `wgsl/shared/splat_shading.wgsl` declares.
    fn shading(&self, cam: &'a wgpu::Buffer, params: &'a wgpu::Buffer) -> [&'a wgpu::Buffer; 10] {
        [
            cam,
            self.splats,
            params,
            self.materials,
            self.splat_light,
            self.lobes,
            self.lobe_norms,
            self.lights,
            self.direct,
            self.visibility,
        ]
    }
}

/// The passes of a frame, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplatPass {
    Visibility,
    Attributes,
    Shade,
}

impl SplatPass {
    pub const ALL: [SplatPass; 3] = [
        SplatPass::Visibility,
        SplatPass::Attributes,
        SplatPass::Shade,
    ];

    /// The stage (WGSL file) the pass runs.
    pub fn stage(self) -> Stage {
        match self {
            SplatPass::Visibility => Stage::SplatVisibility,
            SplatPass::Attributes => Stage::SplatAttributes,
            SplatPass::Shade => Stage::Shade,
        }
    }

    pub fn name(self) -> &'static str {
        self.stage().name()
    }
}

/// The bake's result and the lights on the device, for frame after frame.
pub struct FrameScene {
    pub splat_light: wgpu::Buffer,
    pub lobes: wgpu::Buffer,
    pub lobe_norms: wgpu::Buffer,
    pub lights: wgpu::Buffer,
    /// The direct bake of `lights` (zeroed until `FrameRenderer::bake_direct`).
    pub direct: DirectBake<wgpu::Buffer>,
    /// The order the device's direct bake takes the splats in (`grid::splat_order`), made
    /// for its first bake.
    pub direct_order: Option<wgpu::Buffer>,
    /// Per splat, the radiance towards the eye of the frame being drawn (`splat_shade`).
    pub shaded: wgpu::Buffer,
    /// The splats a frame of baked direct light draws and shades (`splat_list`): how many, and
    /// which, chunk by chunk.
    pub selected_count: wgpu::Buffer,
    pub selected: wgpu::Buffer,
    /// `splat_select`'s count per chunk of splats, scanned in place into `splat_list`'s
    /// offsets, the levels each visited, and the raster passes' indirect draw of the list
    /// and `splat_shade`'s dispatch (`splat_list` writes both).
    pub group_counts: wgpu::Buffer,
    pub visits: wgpu::Buffer,
    pub draw_args: wgpu::Buffer,
    /// The level of detail's tree (`lod::LodTree::build`), built for the first frame of baked
    /// direct light that draws with it (`ensure_tree`), or the splats' chunks alone for one
    /// without it; and per splat the radius `splat_select` chose for the frame being drawn.
    pub tree: OnceLock<TreeBuffers>,
    pub flat: OnceLock<TreeBuffers>,
    pub drawn: wgpu::Buffer,
    pub drawn_normals: wgpu::Buffer,
}

impl FrameScene {
    pub fn upload(gpu: &Gpu, scene: &Scene, lobes: &LobeMap) -> Result<FrameScene> {
        let splats = scene.splats.len().max(1) as u64;
        let visibility = splats * scene.lights.len().max(1) as u64 * 4;
        let chunks = splats.div_ceil(crate::lod::CHUNK as u64);
        Ok(FrameScene {
            splat_light: gpu.storage("splat light", &lobes.light)?,
            lobes: gpu.storage("lobes", &lobes.lobes)?,
            lobe_norms: gpu.storage("lobe norms", crate::lobe_norms::lobe_norms())?,
            lights: gpu.storage("lights", &scene.lights)?,
            direct: DirectBake {
                direct: gpu.storage_zeroed("direct light", splats * 16)?,
                visibility: gpu.storage_zeroed("light visibility", visibility)?,
            },
            direct_order: None,
            shaded: gpu.storage_zeroed("shaded splats", splats * 16)?,
            selected_count: gpu.storage_zeroed("selected splat count", 4)?,
            selected: gpu.storage_zeroed("selected splats", splats * 4)?,
            group_counts: gpu.storage_zeroed("selected per chunk", chunks * 4)?,
            visits: gpu.storage_zeroed("levels visited per chunk", chunks * 4)?,
            draw_args: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("listed splats' draw and shading"),
                size: 32,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
                mapped_at_creation: false,
            }),
            tree: OnceLock::new(),
            flat: OnceLock::new(),
            drawn: gpu.storage_zeroed("drawn radii", splats * 4)?,
            // Read for glossy splats alone (`lod::merge_tree`).
            drawn_normals: gpu.storage_zeroed(
                "drawn merged normals",
                if scene.has_glossy() { splats * 4 } else { 4 },
            )?,
        })
    }

    /// Builds what `splat_select` walks for frames with the level of detail on (`merged`: the
    /// merge tree and its chunks) or off (the chunks alone), and uploads it, once each.
    pub fn ensure_tree(&self, gpu: &Gpu, scene: &Scene, merged: bool) -> Result<()> {
        let slot = if merged { &self.tree } else { &self.flat };
        if slot.get().is_none() {
            let start = std::time::Instant::now();
            let tree = scene.lod_tree(merged);
            let ms = crate::timing::ms_since(start);
            log::info!(
                "level of detail: {} of {} splats in {ms:.0} ms",
                match (merged, tree.normals) {
                    (true, true) => "merge tree and merged normals",
                    (true, false) => "merge tree",
                    (false, _) => "chunks",
                },
                tree.order.len()
            );
            // Set once: a second caller's tree would be the same.
            let _ = slot.set(TreeBuffers::upload(gpu, &tree)?);
        }
        Ok(())
    }

    /// What the passes bind, with the scene's splats, materials and grid; `merged`: the
    /// level of detail's tree for `splat_select` (else the chunks alone), where built.
    pub fn buffers<'a>(&'a self, on_gpu: &'a GpuScene, merged: bool) -> PassBuffers<'a> {
        PassBuffers {
            splats: &on_gpu.splats,
            splat_count: on_gpu.grid.params.splat_count,
            materials: &on_gpu.materials,
            splat_light: &self.splat_light,
            lobes: &self.lobes,
            lobe_norms: &self.lobe_norms,
            lights: &self.lights,
            direct: &self.direct.direct,
            visibility: &self.direct.visibility,
            geometry: on_gpu.geometry(),
            clips: &on_gpu.drawn_clips,
            sky: on_gpu.has_sky.then_some(&on_gpu.sky),
            shaded: &self.shaded,
            selected_count: &self.selected_count,
            selected: &self.selected,
            group_counts: &self.group_counts,
            visits: &self.visits,
            draw_args: &self.draw_args,
            tree: if merged { &self.tree } else { &self.flat }.get(),
            drawn: &self.drawn,
            drawn_normals: &self.drawn_normals,
        }
    }
}

/// A frame's uniforms on the device, and which passes they ask for.
struct Uniforms {
    camera: Camera,
    cam: wgpu::Buffer,
    params: wgpu::Buffer,
    /// `ShadeParams::direct`.
    direct: u32,
    /// The compute splatter or the raster passes, and the splatter's tile lists once binned.
    splatting: Splatting,
    tiles: std::cell::RefCell<Option<TileLists<wgpu::Buffer>>>,
}

/// The compiled splat passes of one device.
pub struct SplatPipelines {
    format: wgpu::TextureFormat,
    /// The raster passes by the paging of the arrays they bind (`shaders::Paging`): the
    /// unpaged ones, built with the rest, serve every scene whose arrays fit one binding each.
    raster: Mutex<HashMap<(Raster, Paging, bool), wgpu::RenderPipeline>>,
    /// The shade pass by the paging of the scene's geometry and whether it casts shadow rays.
    shade: Mutex<HashMap<(Paging, Direct), ShadePipeline>>,
    /// The device can run the compute splatter's tile pass (`compute_splatter_fits`).
    splat_compute: bool,
    /// The device draws from a buffer's arguments (`draw_indirect`). Without, the raster
    /// passes draw as many instances as every splat needs, and those past the list's length
    /// draw nothing: the same image, slower.
    indirect: bool,
}

/// The targets of one image size, and the HDR image the frame ends in.
pub struct FrameTargets {
    pub width: u32,
    pub height: u32,
    depth: wgpu::TextureView,
    /// The nearest splat's normal per pixel (`FRONT`).
    front: wgpu::TextureView,
    sums: Vec<wgpu::TextureView>,
    /// Linear HDR radiance, one `vec4<f32>` per pixel, rows from the top.
    pub hdr: wgpu::Buffer,
    /// The surface each pixel shows (normal, distance from the eye; `shade`'s output).
    pub surface: wgpu::Buffer,
    /// The moving frames' history, made by the first frame with the temporal pass.
    history: OnceLock<TemporalImages>,
}

/// The moving frames' resolved images and the surfaces they kept (`temporal`), one pair the
/// last frame's, the other the next's: which is which, `FrameRenderer`'s history knows.
pub struct TemporalImages {
    pub image: [wgpu::Buffer; 2],
    pub surface: [wgpu::Buffer; 2],
}

impl FrameTargets {
    /// The temporal pass's history buffers, made on first use (four images: frames without
    /// the pass need none).
    pub fn history(&self, gpu: &Gpu) -> Result<&TemporalImages> {
        if self.history.get().is_none() {
            let pixels = self.width as u64 * self.height as u64;
            let image = |label| gpu.storage_zeroed(label, pixels * 16);
            let made = TemporalImages {
                image: [image("temporal history")?, image("temporal history")?],
                surface: [
                    image("temporal history surface")?,
                    image("temporal history surface")?,
                ],
            };
            // One thread draws a renderer's frames: the cell is empty here.
            let _ = self.history.set(made);
        }
        self.history
            .get()
            .ok_or_else(|| Error::internal("the temporal history was not kept"))
    }

    /// The attribute targets as colour attachments cleared to zero.
    pub(super) fn cleared_sums(&self) -> Vec<Option<wgpu::RenderPassColorAttachment<'_>>> {
        self.sums
            .iter()
            .map(|view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect()
    }
}

fn module(gpu: &Gpu, stage: Stage, paging: &Paging) -> Result<wgpu::ShaderModule> {
    let source = crate::shaders::resolve_stage_paged(stage, &[], paging)?;
    Ok(gpu.shader_module(stage.name(), source))
}

pub(super) fn raster_pipeline(
    gpu: &Gpu,
    stage: Stage,
    depth: Option<wgpu::DepthStencilState>,
    targets: &[Option<wgpu::ColorTargetState>],
) -> Result<wgpu::RenderPipeline> {
    let entries = ["vs_main", "fs_main"];
    raster_pipeline_at(gpu, stage, entries, depth, targets, &Paging::default(), &[])
}

/// `raster_pipeline` with the vertex and fragment entry points `[vertex, fragment]` and the
/// shader's pipeline constants (`override`s) set to `constants`.
pub(super) fn raster_pipeline_at(
    gpu: &Gpu,
    stage: Stage,
    [vertex, fragment]: [&'static str; 2],
    depth: Option<wgpu::DepthStencilState>,
    targets: &[Option<wgpu::ColorTargetState>],
    paging: &Paging,
    constants: &[(&str, f64)],
) -> Result<wgpu::RenderPipeline> {
    let module = module(gpu, stage, paging)?;
    let compilation_options = wgpu::PipelineCompilationOptions {
        constants,
        ..Default::default()
    };
    Ok(gpu
        .device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(stage.name()),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some(vertex),
                compilation_options: compilation_options.clone(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                ..Default::default()
            },
            depth_stencil: depth,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(fragment),
                compilation_options,
                targets,
            }),
            multiview_mask: None,
            cache: None,
        }))
}

fn layout_entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty,
        count: None,
    }
}

fn buffer_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    layout_entry(
        binding,
        wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
    )
}

const UNIFORM: wgpu::BufferBindingType = wgpu::BufferBindingType::Uniform;
const READ: wgpu::BufferBindingType = wgpu::BufferBindingType::Storage { read_only: true };
const READ_WRITE: wgpu::BufferBindingType = wgpu::BufferBindingType::Storage { read_only: false };

/// `shade`'s bind group layouts, spelled out: a derived layout would ask for filterable
/// textures, which f32 targets are not. The geometry's paged arrays take a binding a page.
fn shade_layouts(gpu: &Gpu, paging: &Paging) -> Result<[wgpu::BindGroupLayout; 2]> {
    let texture = |binding| {
        layout_entry(
            binding,
            wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
        )
    };
    let mut frame = vec![buffer_entry(0, UNIFORM), buffer_entry(1, UNIFORM)];
    frame.extend((2..6).map(texture));
    frame.extend([buffer_entry(6, READ), buffer_entry(7, READ_WRITE)]);
    frame.extend([8, 9, 10].map(|binding| buffer_entry(binding, READ)));
    frame.push(buffer_entry(11, READ_WRITE));
    let mut geometry = vec![buffer_entry(0, UNIFORM)];
    for p in crate::shaders::paged_bindings(Stage::Shade)? {
        let pages = paging.of(&p.name).map_or(1, |l| l.pages);
        let more = (1..pages).map(|k| buffer_entry(p.binding + k * PAGE_BINDING_STEP, READ));
        match p.group {
            0 => frame.extend(more),
            _ => geometry.extend(more),
        }
    }
    geometry.extend((1..GEOMETRY_BINDINGS as u32).map(|b| buffer_entry(b, READ)));
    Ok([frame, geometry].map(|entries| {
        gpu.device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(Stage::Shade.name()),
                entries: &entries,
            })
    }))
}

/// The shade pass of one paging of the scene's geometry, with its layouts.
#[derive(Clone)]
struct ShadePipeline {
    pipeline: wgpu::ComputePipeline,
    layouts: [wgpu::BindGroupLayout; 2],
}

impl ShadePipeline {
    /// `direct`: with `Direct::Rays` the pipeline can cast shadow rays (`SHADOW_RAYS` in the
    /// WGSL). Frames of baked direct light take the one without: llvmpipe paid for the shadow-ray code even where the
    /// frame's uniform skipped it (the shade pass of the bunny at 512² took 15.6 ms with it,
    /// 4.9 ms without; docs/measurements.md).
    fn new(gpu: &Gpu, paging: &Paging, direct: Direct) -> Result<ShadePipeline> {
        let rays = direct == Direct::Rays;
        let layouts = shade_layouts(gpu, paging)?;
        let layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(Stage::Shade.name()),
                bind_group_layouts: &[Some(&layouts[0]), Some(&layouts[1])],
                immediate_size: 0,
            });
        let module = module(gpu, Stage::Shade, paging)?;
        let pipeline = gpu
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(Stage::Shade.name()),
                layout: Some(&layout),
                module: &module,
                entry_point: Some("main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &[("SHADOW_RAYS", f64::from(u8::from(rays)))],
                    zero_initialize_workgroup_memory: false,
                },
                cache: None,
            });
        gpu.check()?;
        Ok(ShadePipeline { pipeline, layouts })
    }
}

/// The raster passes' pipelines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Raster {
    Visibility,
    Attributes,
    /// `fs_baked`: the attribute pass with baked direct light, two targets.
    AttributesBaked,
}

impl Raster {
    /// The stage (WGSL file) the pipeline is built from.
    fn stage(self) -> Stage {
        match self {
            Raster::Visibility => SplatPass::Visibility.stage(),
            Raster::Attributes | Raster::AttributesBaked => SplatPass::Attributes.stage(),
        }
    }

    /// `listed`: the visibility pass draws `splat_list`'s list (`LISTED` in the WGSL, frames
    /// of baked direct light); without, every splat, and the vertex shader has none of the
    /// list's code.
    fn build(
        self,
        gpu: &Gpu,
        format: wgpu::TextureFormat,
        paging: &Paging,
        listed: bool,
    ) -> Result<wgpu::RenderPipeline> {
        let constants = [("LISTED", f64::from(u8::from(listed)))];
        let depth = |compare, write| wgpu::DepthStencilState {
            format: DEPTH,
            depth_write_enabled: Some(write),
            depth_compare: Some(compare),
            stencil: Default::default(),
            bias: Default::default(),
        };
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let target = Some(wgpu::ColorTargetState {
            format,
            blend: Some(wgpu::BlendState {
                color: add,
                alpha: add,
            }),
            write_mask: wgpu::ColorWrites::ALL,
        });
        let test = Some(depth(wgpu::CompareFunction::GreaterEqual, false));
        match self {
            // Reversed depth: greater is nearer.
            Raster::Visibility => raster_pipeline_at(
                gpu,
                self.stage(),
                ["vs_main", "fs_main"],
                Some(depth(wgpu::CompareFunction::Greater, true)),
                &[Some(wgpu::ColorTargetState {
                    format: FRONT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
                paging,
                &constants,
            ),
            Raster::Attributes => raster_pipeline_at(
                gpu,
                self.stage(),
                ["vs_main", "fs_main"],
                test,
                &vec![target; TARGETS],
                paging,
                &constants,
            ),
            Raster::AttributesBaked => raster_pipeline_at(
                gpu,
                self.stage(),
                ["vs_baked", "fs_baked"],
                test,
                &[target.clone(), target],
                paging,
                &constants,
            ),
        }
    }
}

/// Storage buffers `splat_compute` binds: the splats, the eight of `splat_shading`, the tile
/// lists' starts and entries, `splat_shade`'s output and the surfaces' clips.
const SPLAT_COMPUTE_BUFFERS: u32 = 13;

/// Whether the device can run the compute splatter: it stores f32 targets from a compute pass
/// and binds its buffers in one stage.
fn compute_splatter_fits(gpu: &Gpu, format: wgpu::TextureFormat) -> bool {
    format == wgpu::TextureFormat::Rgba32Float
        && gpu.limits.max_storage_buffers_per_shader_stage >= SPLAT_COMPUTE_BUFFERS
        && gpu.limits.max_storage_textures_per_shader_stage >= TARGETS as u32
}

impl SplatPipelines {
    pub fn new(gpu: &Gpu) -> Result<SplatPipelines> {
        let format = accumulation_format(gpu);
        let need = TARGETS as u32 * format.target_pixel_byte_cost().unwrap_or(16);
        let have = gpu.limits.max_color_attachment_bytes_per_sample;
        if need > have {
            return Err(Error::Gpu(format!(
                "the splat passes write {need} bytes per pixel to their targets; this device \
                 allows {have}"
            )));
        }
        let pipelines = SplatPipelines {
            format,
            raster: Default::default(),
            shade: Default::default(),
            splat_compute: compute_splatter_fits(gpu, format),
            indirect: gpu
                .adapter
                .get_downlevel_capabilities()
                .flags
                .contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION),
        };
        // Compiled now, so that a device that cannot run them says so before any work.
        let unpaged = Paging::default();
        for which in [
            Raster::Visibility,
            Raster::Attributes,
            Raster::AttributesBaked,
        ] {
            pipelines.raster(gpu, which, &unpaged, false)?;
        }
        for direct in [Direct::Baked, Direct::Rays] {
            pipelines.shade_pipeline(gpu, &unpaged, direct)?;
        }
        gpu.pipeline(Stage::SplatSelect)?;
        gpu.pipeline(Stage::SplatList)?;
        gpu.pipeline(Stage::SplatShade)?;
        if pipelines.splat_compute {
            gpu.pipeline(Stage::SplatCompute)?;
        }
        gpu.check()?;
        Ok(pipelines)
    }

    /// The raster pipeline `which` for arrays paged as `paging`, drawing the list or every
    /// splat, built on first use.
    fn raster(
        &self,
        gpu: &Gpu,
        which: Raster,
        paging: &Paging,
        listed: bool,
    ) -> Result<wgpu::RenderPipeline> {
        let key = (which, paging.clone(), listed);
        if let Some(p) = self.raster.lock().ok().and_then(|m| m.get(&key).cloned()) {
            return Ok(p);
        }
        let pipeline = which.build(gpu, self.format, paging, listed)?;
        gpu.check()?;
        if let Ok(mut m) = self.raster.lock() {
            m.insert(key, pipeline.clone());
        }
        Ok(pipeline)
    }

    /// The shade pass for geometry paged as `paging`, casting shadow rays or not, built on
    /// first use.
    fn shade_pipeline(&self, gpu: &Gpu, paging: &Paging, direct: Direct) -> Result<ShadePipeline> {
        let key = (paging.clone(), direct);
        if let Some(p) = self.shade.lock().ok().and_then(|m| m.get(&key).cloned()) {
            return Ok(p);
        }
        let pipeline = ShadePipeline::new(gpu, paging, direct)?;
        if let Ok(mut m) = self.shade.lock() {
            m.insert(key, pipeline.clone());
        }
        Ok(pipeline)
    }

    pub fn targets(&self, gpu: &Gpu, width: u32, height: u32) -> Result<FrameTargets> {
        let texture = |label, format, usage| {
            gpu.texture_2d(label, (width, height), format, usage)
                .create_view(&Default::default())
        };
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let storage = match self.splat_compute {
            true => wgpu::TextureUsages::STORAGE_BINDING,
            false => wgpu::TextureUsages::empty(),
        };
        let depth = texture("splat depth", DEPTH, attachment);
        let front = texture(
            "splat front",
            FRONT,
            attachment | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let sums = (0..TARGETS)
            .map(|_| {
                texture(
                    "splat sums",
                    self.format,
                    attachment | wgpu::TextureUsages::TEXTURE_BINDING | storage,
                )
            })
            .collect();
        let pixels = width as u64 * height as u64;
        let image = |label| gpu.storage_zeroed(label, pixels * 16);
        Ok(FrameTargets {
            width,
            height,
            depth,
            front,
            sums,
            hdr: image("hdr image")?,
            surface: image("surface image")?,
            history: OnceLock::new(),
        })
    }

    /// The format of the blended targets.
    pub fn format(&self) -> wgpu::TextureFormat {
        self.format
    }

    /// Records the shade pass alone, over targets another pass filled (the reference).
    pub fn shade(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PassBuffers,
        cam: &Camera,
        params: &ShadeParams,
        out: &FrameTargets,
    ) -> Result<()> {
        let plan = FramePlan::new(cam, *params, Splatting::Raster);
        self.record(
            gpu,
            encoder,
            scene,
            &self.uniforms(gpu, &plan),
            out,
            SplatPass::Shade,
        )
    }

    /// Records one frame into `out.hdr`: visibility, attributes, shade.
    pub fn draw(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PassBuffers,
        plan: &FramePlan,
        out: &FrameTargets,
    ) -> Result<()> {
        let uniforms = self.uniforms(gpu, plan);
        for pass in SplatPass::ALL {
            self.record(gpu, encoder, scene, &uniforms, out, pass)?;
        }
        Ok(())
    }

    /// One frame with a wait after each pass: the milliseconds of each, in `SplatPass::ALL`
    /// order (benchmarks; a frame that waits between passes is slower than `draw`'s).
    pub fn draw_timed(
        &self,
        gpu: &Gpu,
        scene: &PassBuffers,
        plan: &FramePlan,
        out: &FrameTargets,
    ) -> Result<[f64; 3]> {
        let uniforms = self.uniforms(gpu, plan);
        let mut ms = [0.0; 3];
        for (pass, slot) in SplatPass::ALL.into_iter().zip(&mut ms) {
            let t = std::time::Instant::now();
            let mut encoder = gpu.encoder(pass.name());
            self.record(gpu, &mut encoder, scene, &uniforms, out, pass)?;
            gpu.submit_and_wait(encoder)?;
            *slot = crate::timing::ms_since(t);
        }
        Ok(ms)
    }

    /// The selection of a frame of baked direct light alone (`record_splat_select`: the walk
    /// down the nodes, `splat_select`, the scan and `splat_list`), waited for: its
    /// milliseconds; 0 for a frame that selects nothing (direct light by rays). Benchmarks.
    pub fn select_timed(&self, gpu: &Gpu, scene: &PassBuffers, plan: &FramePlan) -> Result<f64> {
        let uniforms = self.uniforms(gpu, plan);
        if Direct::of_code(uniforms.direct) != Direct::Baked {
            return Ok(0.0);
        }
        let t = std::time::Instant::now();
        let mut encoder = gpu.encoder("selection");
        self.record_splat_select(gpu, &mut encoder, scene, &uniforms)?;
        gpu.submit_and_wait(encoder)?;
        Ok(crate::timing::ms_since(t))
    }

    /// The frame's uniforms, from its plan: the camera its passes read (the level of detail
    /// in moving frames of the raster passes only) and its shading.
    fn uniforms(&self, gpu: &Gpu, plan: &FramePlan) -> Uniforms {
        Uniforms {
            camera: plan.cam,
            cam: gpu.uniform("camera", &plan.cam),
            params: gpu.uniform("shade params", &plan.params),
            direct: plan.params.direct,
            splatting: plan.splatting,
            tiles: Default::default(),
        }
    }

    /// Whether `splatter` draws with the compute splatter on this device. `Auto` takes the
    /// raster passes: on llvmpipe the compute splatter measured 3–4× slower (its per-pixel loop
    /// over each tile's list costs more than the rasterizer's triangle setup saves;
    /// docs/measurements.md), and no other device class has been measured yet.
    pub fn splatting(&self, splatter: Splatter) -> Result<Splatting> {
        let can = self.splat_compute;
        match splatter {
            Splatter::Raster => Ok(Splatting::Raster),
            Splatter::Compute if can => Ok(Splatting::Compute),
            Splatter::Compute => Err(Error::Gpu(format!(
                "this device cannot run the compute splatter (it needs f32 storage targets and \
                 {SPLAT_COMPUTE_BUFFERS} storage buffers in one stage); use --splatter raster"
            ))),
            Splatter::Auto => Ok(Splatting::Raster),
        }
    }

    /// Records `splat_select`, the scan of its counts and `splat_list`, before the visibility
    /// pass of a frame of baked direct light, chunk by chunk of the level of detail's tree: the
    /// radius each visited splat is drawn with, the list of those drawn in the chunks' order,
    /// the raster passes' indirect draw of it and `splat_shade`'s dispatch.
    fn record_splat_select(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PassBuffers,
        uniforms: &Uniforms,
    ) -> Result<()> {
        // The merge tree with the level of detail on, the chunks alone with it off.
        let tree = match scene.tree {
            Some(t) if t.merged == (uniforms.camera.lod > 0.0) => t,
            _ => {
                return Err(Error::Internal(
                    "a frame of baked direct light was drawn before the tree it selects by was \
                     built (FrameScene::ensure_tree)"
                        .into(),
                ));
            }
        };
        let select = [
            &uniforms.cam,
            scene.splats,
            scene.group_counts,
            &tree.lods,
            scene.drawn,
            &tree.chunks,
            &tree.order,
            scene.visits,
            &tree.spreads,
            scene.drawn_normals,
            // `LodTree::nodes` holds one level at least.
            &tree.nodes[0].visits,
        ];
        // The walk down the chunks' nodes, from the top: one invocation a node.
        for (k, level) in tree.nodes.iter().enumerate().rev() {
            let up = tree.nodes.get(k + 1).map_or(&tree.visit_all, |l| &l.visits);
            let groups = crate::sequence::groups(Stage::SplatNodes, level.count)?;
            let walk = [&uniforms.cam, &level.nodes, up, &level.visits];
            gpu.dispatch(encoder, Stage::SplatNodes, &walk, groups)?;
        }
        // One invocation a chunk, in both passes.
        let chunks = scene.splat_count.div_ceil(crate::lod::CHUNK as u32);
        let groups = crate::sequence::groups(Stage::SplatSelect, chunks)?;
        gpu.dispatch(encoder, Stage::SplatSelect, &select, groups)?;
        super::scan::exclusive_scan(gpu, encoder, scene.group_counts, chunks)?;
        let list = [
            scene.group_counts,
            scene.drawn,
            scene.selected_count,
            scene.selected,
            scene.draw_args,
            &tree.chunks,
            &tree.order,
            scene.visits,
        ];
        gpu.dispatch(encoder, Stage::SplatList, &list, groups)
    }

    /// Records `splat_shade`: the radiance towards the eye of every splat `splat_select`
    /// listed, for the attribute pass of a frame of baked direct light.
    fn record_splat_shade(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PassBuffers,
        uniforms: &Uniforms,
    ) -> Result<()> {
        let stage = Stage::SplatShade;
        let mut buffers = scene.shading(&uniforms.cam, &uniforms.params).to_vec();
        buffers.extend([
            scene.shaded,
            scene.selected_count,
            scene.selected,
            scene.drawn_normals,
        ]);
        // The sky, which an environment light's glossy part reads, where there is one.
        buffers.extend(scene.sky);
        let defines: &[&str] = if scene.sky.is_some() { &["sky"] } else { &[] };
        if self.indirect {
            // As many workgroups as the list needs (`splat_list` wrote them), not the scene.
            let args = (scene.draw_args, 16);
            return gpu.dispatch_indirect(encoder, (stage, defines), &[&buffers], args);
        }
        let groups = crate::sequence::groups(stage, scene.splat_count)?;
        let paging = gpu.paging(stage, &[&buffers])?;
        let pipeline = gpu.variant_paged(stage, defines, &[], &paging)?;
        gpu.dispatch_pipeline(encoder, stage, &pipeline, &paging, &[&buffers], groups)
    }

    /// The compute splatter in place of the raster passes: the tile binning for
    /// `SplatPass::Visibility`, the tile pass for `SplatPass::Attributes`.
    fn record_compute(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PassBuffers,
        uniforms: &Uniforms,
        out: &FrameTargets,
        pass: SplatPass,
    ) -> Result<()> {
        if pass == SplatPass::Visibility {
            let mut ex = GpuExecutor::new(gpu, encoder);
            let (cam, count) = (&uniforms.camera, scene.splat_count);
            let lists = bin_splat_tiles(&mut ex, cam, &uniforms.cam, scene.splats, count)?;
            *uniforms.tiles.borrow_mut() = Some(lists);
            return Ok(());
        }
        let (true, Some(lists)) = (self.splat_compute, &*uniforms.tiles.borrow()) else {
            return Err(Error::Internal(
                "the compute splatter's tile pass ran before its binning".into(),
            ));
        };
        let tile_params = gpu.uniform("tile params", &lists.params);
        let mut buffers = scene.shading(&uniforms.cam, &uniforms.params).to_vec();
        buffers.extend([&tile_params, &lists.start, &lists.splats, scene.shaded]);
        let paging = gpu.paging(Stage::SplatCompute, &[&buffers])?;
        let pipeline = &gpu.variant_paged(Stage::SplatCompute, &[], &[], &paging)?;
        let mut bound: Vec<_> = (0u32..)
            .zip(buffers.iter().copied())
            .filter(|(b, _)| !DIRECT_BAKE_BINDINGS.contains(b))
            .collect();
        bound.push((COMPUTE_CLIP_BINDING, scene.clips));
        let mut entries = gpu.paged_entries_at(Stage::SplatCompute, 0, &bound, &paging)?;
        entries.extend(
            out.sums
                .iter()
                .enumerate()
                .map(|(k, view)| wgpu::BindGroupEntry {
                    binding: buffers.len() as u32 + k as u32,
                    resource: wgpu::BindingResource::TextureView(view),
                }),
        );
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(Stage::SplatCompute.name()),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let tiles = lists.params.tiles_x * lists.params.tiles_y;
        let (x, y) = gpu.dispatch_dims(tiles)?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(Stage::SplatCompute.name()),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(x, y, 1);
        Ok(())
    }

    /// Records one splat pass of a frame; in frames of baked direct light the visibility pass
    /// selects the drawn splats first and the attribute pass shades them.
    fn record(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PassBuffers,
        uniforms: &Uniforms,
        out: &FrameTargets,
        pass: SplatPass,
    ) -> Result<()> {
        let baked = Direct::of_code(uniforms.direct) == Direct::Baked;
        match pass {
            SplatPass::Visibility if baked => {
                self.record_splat_select(gpu, encoder, scene, uniforms)?
            }
            SplatPass::Attributes if baked => {
                self.record_splat_shade(gpu, encoder, scene, uniforms)?
            }
            _ => {}
        }
        if uniforms.splatting == Splatting::Compute && pass != SplatPass::Shade {
            return self.record_compute(gpu, encoder, scene, uniforms, out, pass);
        }
        match pass {
            SplatPass::Visibility => self.record_visibility(gpu, encoder, scene, uniforms, out),
            SplatPass::Attributes => self.record_attributes(gpu, encoder, scene, uniforms, out),
            SplatPass::Shade => self.record_shade(gpu, encoder, scene, uniforms, out),
        }
    }

    /// A raster pass's pipeline for the paging of `list` (buffers by binding), and its bind
    /// group (the attribute passes also read the front target).
    fn bound_raster(
        &self,
        gpu: &Gpu,
        which: Raster,
        list: &[(u32, &wgpu::Buffer)],
        out: &FrameTargets,
        baked: bool,
    ) -> Result<(wgpu::RenderPipeline, wgpu::BindGroup)> {
        let stage = which.stage();
        let paging = gpu.paging_by(stage, |group, binding| {
            let found = list.iter().find(|(b, _)| *b == binding);
            found.filter(|_| group == 0).map(|(_, buffer)| *buffer)
        })?;
        let pipeline = self.raster(gpu, which, &paging, baked)?;
        let mut entries = gpu.paged_entries_at(stage, 0, list, &paging)?;
        if which != Raster::Visibility {
            entries.push(wgpu::BindGroupEntry {
                binding: FRONT_BINDING,
                resource: wgpu::BindingResource::TextureView(&out.front),
            });
        }
        let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(stage.name()),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        Ok((pipeline, group))
    }

    /// The visibility pass: the nearest disk's depth and id into the front target.
    fn record_visibility(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PassBuffers,
        uniforms: &Uniforms,
        out: &FrameTargets,
    ) -> Result<()> {
        let baked = Direct::of_code(uniforms.direct) == Direct::Baked;
        let list = [
            (0, &uniforms.cam),
            (1, scene.splats),
            (2, scene.drawn),
            (3, scene.selected_count),
            (4, scene.selected),
            (VISIBILITY_CLIP_BINDING, scene.clips),
        ];
        let (pipeline, vis_group) =
            self.bound_raster(gpu, Raster::Visibility, &list, out, baked)?;
        let front = Some(wgpu::RenderPassColorAttachment {
            view: &out.front,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        });
        let (stage, depth) = (Stage::SplatVisibility, wgpu::LoadOp::Clear(0.0));
        let bound = (&pipeline, &vis_group);
        self.draw_splats(encoder, (stage, &[front], depth), out, scene, bound, baked);
        Ok(())
    }

    /// A splat raster pass into `color` (its depth target cleared or loaded, `depth`): the
    /// listed splats, drawn indirectly, in frames of baked direct light; else every splat.
    #[allow(clippy::too_many_arguments)]
    fn draw_splats(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (stage, color, depth): (
            Stage,
            &[Option<wgpu::RenderPassColorAttachment>],
            wgpu::LoadOp<f32>,
        ),
        out: &FrameTargets,
        scene: &PassBuffers,
        (pipeline, group): (&wgpu::RenderPipeline, &wgpu::BindGroup),
        baked: bool,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(stage.name()),
            color_attachments: color,
            depth_stencil_attachment: depth_attachment(out, depth),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        match baked && self.indirect {
            true => pass.draw_indirect(scene.draw_args, 0),
            false => pass.draw(SPLAT_VERTICES, 0..instances(scene.splat_count)),
        }
    }

    /// The attribute pass: the disks within the depth tolerance blended into the sums.
    fn record_attributes(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PassBuffers,
        uniforms: &Uniforms,
        out: &FrameTargets,
    ) -> Result<()> {
        let baked = Direct::of_code(uniforms.direct) == Direct::Baked;
        let (cam_buf, params_buf) = (&uniforms.cam, &uniforms.params);
        // `fs_main` reads none of the direct bake's bindings (the lights, the bake's two
        // buffers), so its derived layout has none; `fs_baked` reads the camera, the splats
        // and what `splat_shade` wrote.
        let mut list: Vec<(u32, &wgpu::Buffer)> = match baked {
            true => vec![
                (0, cam_buf),
                (1, scene.splats),
                (SHADED_BINDING, scene.shaded),
                (DRAWN_BINDING, scene.drawn),
                (DRAWN_BINDING + 1, scene.selected_count),
                (DRAWN_BINDING + 2, scene.selected),
            ],
            false => (0u32..)
                .zip(scene.shading(cam_buf, params_buf))
                .filter(|(b, _)| !DIRECT_BAKE_BINDINGS.contains(b))
                .collect(),
        };
        list.push((ATTRIBUTES_CLIP_BINDING, scene.clips));
        let which = match baked {
            true => Raster::AttributesBaked,
            false => Raster::Attributes,
        };
        let (pipeline, attr_group) = self.bound_raster(gpu, which, &list, out, baked)?;
        let mut color = out.cleared_sums();
        if baked {
            color.truncate(2);
        }
        let (stage, depth) = (Stage::SplatAttributes, wgpu::LoadOp::Load);
        let bound = (&pipeline, &attr_group);
        self.draw_splats(encoder, (stage, &color, depth), out, scene, bound, baked);
        Ok(())
    }

    /// The shade pass: each pixel's blended surface shaded into the HDR image.
    fn record_shade(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PassBuffers,
        uniforms: &Uniforms,
        out: &FrameTargets,
    ) -> Result<()> {
        let (cam_buf, params_buf) = (&uniforms.cam, &uniforms.params);
        let mut frame_entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: cam_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: params_buf.as_entire_binding(),
            },
        ];
        frame_entries.extend(
            out.sums
                .iter()
                .enumerate()
                .map(|(i, view)| wgpu::BindGroupEntry {
                    binding: 2 + i as u32,
                    resource: wgpu::BindingResource::TextureView(view),
                }),
        );
        frame_entries.push(wgpu::BindGroupEntry {
            binding: 6,
            resource: scene.lights.as_entire_binding(),
        });
        frame_entries.push(wgpu::BindGroupEntry {
            binding: 7,
            resource: out.hdr.as_entire_binding(),
        });
        frame_entries.push(wgpu::BindGroupEntry {
            binding: 11,
            resource: out.surface.as_entire_binding(),
        });
        // The baked light at the glossy rays' hits (paged: a splat's each, like the geometry),
        // and the hit disks' materials.
        let hits = [
            (8, scene.splat_light),
            (9, scene.direct),
            (10, scene.materials),
        ];
        let paging = gpu.paging_by(Stage::Shade, |group, binding| match group {
            0 => hits.iter().find(|h| h.0 == binding).map(|h| h.1),
            _ => scene.geometry.get(binding as usize).copied(),
        })?;
        frame_entries.extend(gpu.paged_entries_at(Stage::Shade, 0, &hits, &paging)?);
        let shade = self.shade_pipeline(gpu, &paging, Direct::of_code(uniforms.direct))?;
        let geometry_entries = gpu.paged_entries(Stage::Shade, 1, &scene.geometry, &paging)?;
        let groups = [frame_entries, geometry_entries]
            .iter()
            .zip(&shade.layouts)
            .map(|(entries, layout)| {
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(Stage::Shade.name()),
                    layout,
                    entries,
                })
            })
            .collect::<Vec<_>>();
        let (x, y) = gpu.dispatch_dims(crate::sequence::groups(
            Stage::Shade,
            out.width * out.height,
        )?)?;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(Stage::Shade.name()),
            timestamp_writes: None,
        });
        pass.set_pipeline(&shade.pipeline);
        for (g, group) in groups.iter().enumerate() {
            pass.set_bind_group(g as u32, group, &[]);
        }
        pass.dispatch_workgroups(x, y, 1);
        Ok(())
    }
}

/// The depth target as a raster pass attaches it, cleared or loaded.
fn depth_attachment(
    out: &FrameTargets,
    load: wgpu::LoadOp<f32>,
) -> Option<wgpu::RenderPassDepthStencilAttachment<'_>> {
    Some(wgpu::RenderPassDepthStencilAttachment {
        view: &out.depth,
        depth_ops: Some(wgpu::Operations {
            load,
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    })
}
