//! The frames on the CPU mirrors: the direct bake, the splat passes of a frame and of a still
//! image's refinement frames, the reference and the path tracer, each the sequence the device
//! runs (`gpu::renderer::FrameRenderer`), on `CpuExecutor`s or the mirrors' functions.

use std::borrow::Cow;

use crate::bins::PhotonBins;
use crate::cpu;
use crate::direct::{DirectMap, direct_params, shadow_bias};
use crate::em::LobeMap;
use crate::error::Result;
use crate::frame::{Direct, FrameConfig, FramePlan, Splatting, Terms, path_params, shade_params};
use crate::grid::SplatGrid;
use crate::scene::Scene;
use crate::sequence::Executor;
use crate::types::{Camera, EmParams, PathParams, ShadeParams};

/// The direct bake on the CPU mirror (`sequence::bake_direct`).
pub fn cpu_direct(scene: &Scene, grid: &SplatGrid) -> Result<DirectMap> {
    let geo = scene.geometry(grid);
    let params = direct_params(scene);
    let mut ex = cpu::CpuExecutor::tracing(geo);
    let lights = ex.upload("lights", &scene.lights)?;
    let order = ex.upload("direct order", &crate::grid::splat_order(&scene.splats))?;
    let baked = crate::sequence::bake_direct(&mut ex, &lights, &order, &params)?;
    baked.read_back(&mut ex, &params)
}

/// The path-traced image of `cam` on the CPU mirror: `spp` samples per pixel, averaged, of
/// the light terms `show`.
pub fn cpu_path(
    scene: &Scene,
    grid: &SplatGrid,
    cam: &Camera,
    show: Terms,
    spp: u32,
) -> Result<Vec<[f32; 4]>> {
    let geo = scene.geometry(grid);
    let pixels = (cam.size[0] * cam.size[1]) as usize;
    let mut ex = cpu::CpuExecutor::tracing(geo);
    let cam_buf = ex.uniform("camera", cam)?;
    let materials = ex.upload("materials", &scene.materials)?;
    let lights = ex.upload("lights", &scene.lights)?;
    let hdr = ex.zeroed("path image", pixels.max(1) as u64 * 16)?;
    let first = path_params(scene, cam, show, shadow_bias(&scene.splats));
    for k in 0..spp.max(1) {
        let params = PathParams { sample: k, ..first };
        crate::sequence::path_sample(&mut ex, &params, &cam_buf, &materials, &lights, &hdr)?;
    }
    ex.read(&hdr, pixels)
}

/// The direct bake a frame reads where it is `needed`: `made` where the bake made one of the
/// scene's lights (final gathering's), else baked now.
fn direct_for<'a>(
    scene: &Scene,
    grid: &SplatGrid,
    needed: bool,
    made: Option<&'a DirectMap>,
) -> Result<Cow<'a, DirectMap>> {
    Ok(match (needed, made) {
        (false, _) => Cow::Owned(DirectMap::default()),
        (true, Some(d)) => Cow::Borrowed(d),
        (true, None) => Cow::Owned(cpu_direct(scene, grid)?),
    })
}

/// The splat passes on the CPU: visibility, attributes, shade; linear HDR pixels. Baked
/// direct light (`params.direct`) is `direct` where the bake made it (`Baked::direct`), else
/// baked first.
pub fn cpu_frame(
    scene: &Scene,
    grid: &SplatGrid,
    (lobes, direct): (&LobeMap, Option<&DirectMap>),
    cam: &Camera,
    params: &ShadeParams,
) -> Result<Vec<[f32; 4]>> {
    let plan = FramePlan::new(cam, *params, Splatting::Raster);
    let needed = plan.reads_direct_bake() || params.glossy_rays > 0;
    let direct = direct_for(scene, grid, needed, direct)?;
    Ok(cpu_draw(scene, grid, (lobes, &direct), &plan, 0))
}

/// The frame of `plan` (`spp` 0: the frame a moving camera gets), or the still image of its
/// `spp` refinement frames (`FramePlan::refinement`), with the direct bake made.
pub fn cpu_draw(
    scene: &Scene,
    grid: &SplatGrid,
    (lobes, direct): (&LobeMap, &DirectMap),
    plan: &FramePlan,
    spp: u32,
) -> Vec<[f32; 4]> {
    cpu_draw_surface(scene, grid, (lobes, direct), plan, spp).0
}

/// `cpu_draw`, and the surface each pixel of its last frame shows.
pub fn cpu_draw_surface(
    scene: &Scene,
    grid: &SplatGrid,
    (lobes, direct): (&LobeMap, &DirectMap),
    plan: &FramePlan,
    spp: u32,
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let [w, h] = plan.view.size;
    let mut hdr = vec![[0.0; 4]; (w * h) as usize];
    let mut surface = vec![[0.0; 4]; hdr.len()];
    match spp {
        0 => cpu_frame_into(scene, grid, lobes, direct, plan, (&mut hdr, &mut surface)),
        spp => {
            for k in 0..spp {
                let plan = plan.refinement(k, spp);
                cpu_frame_into(scene, grid, lobes, direct, &plan, (&mut hdr, &mut surface));
            }
        }
    }
    (hdr, surface)
}

/// The frame of `plan` with the direct bake made, into `hdr` (a refinement frame adds to it),
/// and the surface each pixel shows into `surface` (the temporal pass reprojects by it).
pub fn cpu_frame_into(
    scene: &Scene,
    grid: &SplatGrid,
    lobes: &LobeMap,
    direct: &DirectMap,
    plan: &FramePlan,
    (hdr, surface): (&mut [[f32; 4]], &mut [[f32; 4]]),
) {
    let (cam, params) = (&plan.cam, &plan.params);
    let selection = match plan.reads_direct_bake() {
        true => {
            let tree = scene.lod_tree(cam.lod > 0.0);
            Some(cpu::splat_select::selection(cam, &scene.splats, &tree))
        }
        false => None,
    };
    let drawn = match (&selection, cam.lod > 0.0) {
        (Some(sel), true) => {
            std::borrow::Cow::Owned(cpu::splat_select::drawn_splats(&scene.splats, &sel.drawn))
        }
        _ => std::borrow::Cow::Borrowed(&scene.splats[..]),
    };
    let tiles = cpu::splat_visibility::bin_tiles(cam, &drawn);
    // Disks end where their surfaces end (wgsl/shared/drawn_clip.wgsl).
    let clips = &scene.clips[..];
    let visible = cpu::splat_visibility::splat_visibility(cam, &drawn, clips, &tiles);
    let shading = cpu::splat_shading::Shading {
        params,
        splat_light: &lobes.light,
        lobes: &lobes.lobes,
        lobe_norms: crate::lobe_norms::lobe_norms(),
        baked: cpu::splat_shading::BakedDirect {
            lights: &scene.lights,
            direct: &direct.direct,
            visibility: &direct.visibility,
            sky: scene.sky.entries(),
        },
    };
    let shaded = match &selection {
        Some(sel) => {
            let (splats, materials) = (&scene.splats, &scene.materials);
            let listed = (&sel.selected[..], &sel.normals[..]);
            cpu::splat_shade::splat_shade(cam, splats, materials, &shading, listed)
        }
        None => Vec::new(),
    };
    let sums = cpu::splat_attributes::splat_attributes(
        cam,
        &drawn,
        clips,
        &scene.materials,
        &shading,
        &shaded,
        &visible,
        &tiles,
    );
    let geo = scene.geometry(grid);
    let hit_light = cpu::shade::HitLight {
        splat_light: &lobes.light,
        direct_light: &direct.direct,
        materials: &scene.materials,
    };
    let lights = &scene.lights;
    cpu::shade::shade(cam, params, &sums, lights, &hit_light, &geo, hdr, surface);
}

/// The still image of `cam` on the CPU: `spp` refinement frames, each jittered and with its
/// share of shadow rays, averaged. Glossy rays read the direct bake at their hits: `direct`
/// where the bake made it, else baked first.
pub fn cpu_refined(
    scene: &Scene,
    grid: &SplatGrid,
    (lobes, direct): (&LobeMap, Option<&DirectMap>),
    cam: &Camera,
    params: &ShadeParams,
    spp: u32,
) -> Result<Vec<[f32; 4]>> {
    let direct = direct_for(scene, grid, params.glossy_rays > 0, direct)?;
    let plan = FramePlan::new(cam, *params, Splatting::Raster);
    Ok(cpu_draw(scene, grid, (lobes, &direct), &plan, spp.max(1)))
}

/// The reference on the CPU: the gather pass in place of visibility and attributes, then the
/// same shade pass (which reads no lobes: an empty map gives it its other settings) with
/// shadow rays.
pub fn cpu_reference(
    scene: &Scene,
    grid: &SplatGrid,
    bins: &PhotonBins,
    em: &EmParams,
    cam: &Camera,
    cfg: &FrameConfig,
) -> Vec<[f32; 4]> {
    // The photons give the glossy light too, with the exact BRDF: no glossy rays.
    let cfg = FrameConfig {
        direct: Direct::Rays,
        glossy_rays: 0,
        ..cfg.clone()
    };
    let params = shade_params(scene, &LobeMap::default(), &cfg);
    let geo = scene.geometry(grid);
    let sums = cpu::reference_gather::reference_gather(cam, em, &scene.materials, bins, &geo);
    let mut hdr = vec![[0.0; 4]; (cam.size[0] * cam.size[1]) as usize];
    let no_hits = cpu::shade::HitLight {
        splat_light: &[],
        direct_light: &[],
        materials: &scene.materials,
    };
    let mut surface = vec![[0.0; 4]; hdr.len()];
    let lights = &scene.lights;
    cpu::shade::shade(
        cam,
        &params,
        &sums,
        lights,
        &no_hits,
        &geo,
        &mut hdr,
        &mut surface,
    );
    hdr
}
