//! What the benchmarks measure of a renderer besides its images: each pass of a frame waited
//! for, the selection alone, and the present pass onto an offscreen texture of a window's
//! format. The device times its passes apart; the mirror runs them in one call, so it reports
//! none (the caller times the whole).

use super::{On, Renderer};
use crate::camera::View;
use crate::error::{Error, Result};
use crate::frame::{FrameConfig, Splatting};
use crate::gpu::present::PresentPipeline;

/// An offscreen stand-in for a window's surface texture, and the present pass that draws the
/// tone-mapped image onto it (upsampled where the image is smaller).
pub struct PresentTarget {
    pipeline: PresentPipeline,
    view: wgpu::TextureView,
    size: (u32, u32),
}

/// The usual window surface format (Vulkan's first choice on most platforms).
const WINDOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Bgra8Unorm;

impl Renderer {
    /// Draws the moving frame of `view` (`draw_moving`) with a wait after each splat pass and
    /// after the temporal pass: on a device the milliseconds of each (visibility, attributes,
    /// shade, temporal; 0 without it), slower than `draw_moving`, which waits once; on the
    /// mirror, none.
    pub fn draw_timed(&mut self, view: &View, cfg: &FrameConfig) -> Result<Option<[f64; 4]>> {
        let scene = &self.scene;
        match &mut self.on {
            On::Device(d) => {
                let (gpu, frames, _) = d.parts(scene, &self.lobes)?;
                Ok(Some(frames.draw_timed(gpu, scene, view, cfg)?))
            }
            On::Mirror(_) => {
                self.draw_moving(view, cfg)?;
                Ok(None)
            }
        }
    }

    /// The selection alone of the moving frame of `view` (the walk of the level of detail's
    /// nodes, `splat_select`, the scan, `splat_list`), waited for: its milliseconds on a
    /// device; none on the mirror, whose rasterizer selects as it draws.
    pub fn select_timed(&mut self, view: &View, cfg: &FrameConfig) -> Result<Option<f64>> {
        let scene = &self.scene;
        match &mut self.on {
            On::Device(d) => {
                let (gpu, frames, _) = d.parts(scene, &self.lobes)?;
                Ok(Some(frames.select_timed(gpu, scene, view, cfg)?))
            }
            On::Mirror(_) => Ok(None),
        }
    }

    /// How frames splat with `cfg`: the raster pipeline, or the compute splatter where the
    /// device runs it and `cfg` asks for it (an error where it asks and the device cannot).
    pub fn splatting(&mut self, cfg: &FrameConfig) -> Result<Splatting> {
        let scene = &self.scene;
        match &mut self.on {
            On::Device(d) => {
                let (_, frames, _) = d.parts(scene, &self.lobes)?;
                frames.pipelines.splatting(cfg.splatter)
            }
            On::Mirror(_) => Ok(Splatting::Raster),
        }
    }

    /// An offscreen target of `size` pixels in a window's format, where the engine presents
    /// (a device; none on the mirror, which shows nothing in a window).
    pub fn offscreen_target(&self, size: (u32, u32)) -> Result<Option<PresentTarget>> {
        let On::Device(d) = &self.on else {
            return Ok(None);
        };
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let texture = d
            .gpu
            .texture_2d("window stand-in", size, WINDOW_FORMAT, usage);
        Ok(Some(PresentTarget {
            pipeline: PresentPipeline::new(&d.gpu, WINDOW_FORMAT)?,
            view: texture.create_view(&Default::default()),
            size,
        }))
    }

    /// Draws the last tone-mapped image (`tone`) onto `target` and waits.
    pub fn present(&self, target: &PresentTarget) -> Result<()> {
        let On::Device(d) = &self.on else {
            return Err(Error::internal("the mirror has nothing to present onto"));
        };
        let (toned, image) = d
            .toned
            .as_ref()
            .ok_or_else(|| Error::internal("an image was presented before it was tone-mapped"))?;
        let image = *image;
        d.gpu.record_and_wait("present", |encoder| {
            let (view, rgba) = (&target.view, &toned.rgba);
            target
                .pipeline
                .record(&d.gpu, encoder, view, rgba, image, target.size);
            Ok(())
        })
    }
}
