//! Scenes: the TOML file (`file`), procedural shapes (`shapes`) and models (`crate::scene::model`)
//! turned into the flat arrays the stages consume: splats, materials, lights.

pub mod file;
pub mod model;
pub mod path;
mod settings;
pub mod shapes;
pub mod sides;
pub mod sky;
pub mod views;

use std::path::{Path, PathBuf};

use glam::{Affine3A, Quat, Vec3};

use crate::budget::Budget;
use crate::error::{Error, Result};
use crate::grid::{GridConfig, SplatGrid, splat_is_sane};
use crate::shared::trace::Geometry;

use crate::types::{Light, Material, Splat, SurfaceClip, light_flags, light_kind};
pub use file::BakeDesc;
use file::{Anchor, CameraDesc, LightDesc, MaterialDesc, ObjectDesc, Scale, SceneFile, ShapeKind};
use shapes::Disk;

/// Most splats one procedural object may make (about 3 GB of splats and grid): past it a
/// typo in `spacing` is far likelier than intent.
pub const MAX_OBJECT_SPLATS: u64 = 50_000_000;

/// Splat spacing of procedural shapes when an object does not set `spacing`.
pub const DEFAULT_SPACING: f32 = 0.025;

/// A loaded scene, ready for the stages.
#[derive(Clone, Debug)]
pub struct Scene {
    pub path: PathBuf,
    pub camera: CameraDesc,
    pub bake: BakeDesc,
    pub grid: GridConfig,
    pub splats: Vec<Splat>,
    pub materials: Vec<Material>,
    pub material_names: Vec<String>,
    pub lights: Vec<Light>,
    /// One line per object: what it is and how many splats it made.
    pub objects: Vec<ObjectSummary>,
    /// The names of the scene's surfaces, which `Splat::object` indexes: one per object, but
    /// a Cornell box's five walls apart ("#1 cornell_box floor"), so that an object-ID image
    /// tells the walls apart.
    pub surfaces: Vec<String>,
    /// Where each surface's disks end, one per surface (`SurfaceClip`): a box's and a quad's
    /// at its edges; none for spheres and models. A surface past its end clips nothing.
    pub clips: Vec<SurfaceClip>,
    /// The map of its environment light, if it has one (`lights` holds the light itself).
    pub sky: sky::SkyTable,
    /// Where this scene's origin lies in the file's coordinates (`recentre`); zero for a
    /// scene near the origin.
    pub origin: Vec3,
    /// The memory budget of what the scene makes (`--max-memory`, its `max_memory`, or the
    /// machine's share): its splats at load, its photons in the bake.
    pub budget: Budget,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct ObjectSummary {
    pub shape: String,
    pub source: Option<String>,
    pub splats: usize,
    /// Model vertices left out: by a rule of the format (`dropped_by`), or because no face
    /// used them (they have no normal or extent).
    pub dropped: usize,
    /// The rules of the model's format that left points out, and how many each.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dropped_by: Vec<model::reading::RuleCount>,
    /// The model's points that could not be read or were not finite, skipped (`--strict`
    /// refuses them instead).
    pub skipped: usize,
    /// The first of them: the file, where in it and what was wrong.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_skipped: Option<String>,
    /// Of `splats`, the back sides a model's open surface was given (`sides`).
    pub back_sides: usize,
}

/// The search radius a scene takes where it sets none is its size over this.
pub const DEFAULT_RADIUS_DIVISOR: f32 = 40.0;

/// The search radii a scene accepts, as fractions of its size: past its size a photon counts
/// everywhere; below a millionth of it none lands near a splat.
pub const RADIUS_RANGE: (f32, f32) = (1e-6, 1.0);

/// A scene whose centre lies farther from the origin than this many times its size is moved
/// to the origin.
pub const FAR_FROM_ORIGIN: f32 = 4.0;

impl Scene {
    /// Moves a scene that lies far from the origin (`FAR_FROM_ORIGIN`) so that its centre is
    /// at the origin, and adds the shift to `origin`. Light transport does not depend on where
    /// the scene is, but f32 does: 1e5 from the origin one ulp is 0.008, a third of a typical
    /// splat spacing, and ray–disk tests lose their digits to the offset. Scanned scenes often
    /// sit in georeferenced coordinates that far away.
    pub fn recentre(&mut self) {
        let (lo, hi) = self.bounds();
        let centre = (lo + hi) * 0.5;
        let size = (hi - lo).max_element().max(f32::MIN_POSITIVE);
        if !centre.is_finite() || centre.length() <= FAR_FROM_ORIGIN * size {
            return;
        }
        let shift = |p: &mut [f32; 3]| *p = (Vec3::from(*p) - centre).to_array();
        self.splats.iter_mut().for_each(|s| shift(&mut s.center));
        self.lights.iter_mut().for_each(|l| shift(&mut l.position));
        shift(&mut self.camera.eye);
        shift(&mut self.camera.target);
        let moved = Affine3A::from_translation(-centre);
        self.clips.iter_mut().for_each(|c| *c = c.mapped(&moved));
        self.origin += centre;
    }

    /// What rays trace in this scene, through its splat grid `grid`.
    pub fn geometry<'a>(&'a self, grid: &'a SplatGrid) -> Geometry<'a> {
        Geometry {
            grid,
            splats: &self.splats,
            clips: &self.clips,
            sky: self.sky.entries(),
        }
    }

    /// Bounds of the splat disks.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        crate::grid::splat_bounds(&self.splats).unwrap_or((Vec3::ZERO, Vec3::ZERO))
    }

    /// True when some material has a specular part, i.e. lobes are worth fitting.
    pub fn has_glossy(&self) -> bool {
        self.materials.iter().any(Material::is_glossy)
    }

    /// What frames of the scene select by: with the level of detail on (`merged`), its merge
    /// tree, with the merged normals where a material is glossy; else its chunks alone.
    pub fn lod_tree(&self, merged: bool) -> crate::lod::LodTree {
        match merged {
            true => crate::lod::LodTree::build(&self.splats, self.has_glossy()),
            false => crate::lod::LodTree::flat(&self.splats),
        }
    }

    /// Model points skipped over all objects because they could not be read or were not
    /// finite, and the first of them (`model::LeftOut`).
    pub fn skipped_points(&self) -> (usize, Option<&str>) {
        let count = self.objects.iter().map(|o| o.skipped).sum();
        let first = (self.objects.iter()).find_map(|o| o.first_skipped.as_deref());
        (count, first)
    }

    /// Refuses a search radius that makes the indirect light vanish: larger than the scene
    /// (every photon counts at every splat, its power spread over the whole scene's area), or
    /// so small against it that no photon lands within it; and one that is no positive number
    /// (`em::check_radius`). The message gives the sensible range and the default.
    pub fn check_radius(&self) -> std::result::Result<(), String> {
        let Some(r) = self.bake.radius else {
            return Ok(());
        };
        crate::em::check_radius(r)?;
        let (lo, hi) = self.bounds();
        let size = (hi - lo).max_element();
        let (least, most) = (size * RADIUS_RANGE.0, size * RADIUS_RANGE.1);
        if (least..=most).contains(&r) || size.is_nan() || size <= 0.0 {
            return Ok(());
        }
        let which = if r > most {
            "larger than"
        } else {
            "too small for"
        };
        // Four significant digits, in the notation a reader takes in at a glance.
        let short = |x: f32| match x.abs() {
            a if (1e-3..1e4).contains(&a) => {
                let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
                format!("{x:.decimals$}")
            }
            _ => format!("{x:.3e}"),
        };
        Err(format!(
            "radius {r} is {which} the scene, {} across: a radius from {} to {} suits it (the \
             default, 1/40 of its size, is {})",
            short(size),
            short(least),
            short(most),
            short(size / DEFAULT_RADIUS_DIVISOR)
        ))
    }

    /// Photon search radius: the scene's, or the largest extent of the bounds over
    /// `DEFAULT_RADIUS_DIVISOR`.
    pub fn search_radius(&self) -> f32 {
        self.bake.radius.unwrap_or_else(|| {
            let (lo, hi) = self.bounds();
            (hi - lo).max_element() / DEFAULT_RADIUS_DIVISOR
        })
    }
}

/// Reads and builds a scene file.
pub fn load(path: &Path) -> Result<Scene> {
    let bytes = Budget::current().read_file(path)?;
    let text = String::from_utf8(bytes)
        .map_err(|e| Error::parse(path, "encoding", format!("not UTF-8 text: {e}")))?;
    parse(path, &text)
}

/// A TOML file's parse error, at the line it names (scene files, view lists).
pub(crate) fn toml_error(path: &Path, text: &str, e: toml::de::Error) -> Error {
    let at = e.span().map_or_else(
        || "top".to_string(),
        |s| format!("line {}", line_of(text, s.start)),
    );
    Error::parse(path, at, e.message().trim().to_string())
}

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// Points and meshes handed over in memory, by the names scene objects give as `array`.
pub type Arrays = std::collections::HashMap<String, model::Mesh>;

/// Builds a scene from TOML text; `path` names it in errors and anchors model paths.
pub fn parse(path: &Path, text: &str) -> Result<Scene> {
    parse_with(path, text, &Arrays::new())
}

/// `parse`, with the models that name an `array` taken from `arrays`.
pub fn parse_with(path: &Path, text: &str, arrays: &Arrays) -> Result<Scene> {
    let file: SceneFile = toml::from_str(text).map_err(|e| toml_error(path, text, e))?;
    let at_line = |span: std::ops::Range<usize>, msg: String| {
        Error::at_line(path, line_of(text, span.start), msg)
    };
    let invalid = |msg: String| Error::parse(path, "scene", msg);

    validate_camera(&file.camera).map_err(|m| invalid(format!("[camera]: {m}")))?;
    validate_bake(&file.bake).map_err(|m| invalid(format!("[bake]: {m}")))?;
    let max_memory = (file.max_memory.as_deref())
        .map(crate::budget::parse_size)
        .transpose()
        .map_err(|m| invalid(format!("max_memory: {m}")))?;
    let budget = Budget::for_scene(max_memory);

    // Materials: "default" first (grey diffuse unless the file defines it), then by name.
    let mut material_names = vec!["default".to_string()];
    let mut material_descs = vec![file.materials.get("default").cloned().unwrap_or_default()];
    for (name, m) in &file.materials {
        if name != "default" {
            material_names.push(name.clone());
            material_descs.push(m.clone());
        }
    }
    let mut materials = Vec::new();
    for (name, m) in material_names.iter().zip(&material_descs) {
        materials.push(material(m).map_err(|msg| invalid(format!("[materials.{name}]: {msg}")))?);
    }
    let material_index = |name: Option<&String>| -> std::result::Result<u32, String> {
        let name = name.map_or("default", |s| s.as_str());
        material_names
            .iter()
            .position(|n| n == name)
            .map(|i| i as u32)
            .ok_or_else(|| {
                format!(
                    "unknown material '{name}' (defined: {})",
                    material_names.join(", ")
                )
            })
    };

    let base_dir = path.parent().unwrap_or(Path::new("."));
    let mut splats = Vec::new();
    let mut objects = Vec::new();
    let mut surfaces = Vec::new();
    let mut clips = Vec::new();
    let mut extra_materials = Vec::new();
    let mut models = Vec::new();
    for (k, obj) in file.objects.iter().enumerate() {
        let span = obj.span();
        let obj = obj.get_ref();
        let at = |msg: String| {
            at_line(
                span.clone(),
                format!("object #{} ({}): {msg}", k + 1, obj.shape.name()),
            )
        };
        let summary = build_object(
            obj,
            base_dir,
            &material_index,
            &material_descs,
            Built {
                splats: &mut splats,
                surfaces: &mut surfaces,
                clips: &mut clips,
                name: surface_name(k, obj),
                extra_materials: &mut extra_materials,
                first_extra: material_names.len() as u32,
                budget,
                arrays,
            },
            &at,
        )?;
        // A model, and a quad (a sheet too: a ground under a sky sees the sky below it), may
        // get back sides; closed shapes keep one.
        if matches!(obj.shape, ShapeKind::Model | ShapeKind::Quad) {
            models.push(sides::ModelSplats {
                object: objects.len(),
                range: splats.len() - summary.splats..splats.len(),
                sides: obj.sides.unwrap_or_default(),
            });
        }
        objects.push(summary);
    }
    if splats.is_empty() {
        return Err(invalid(
            "the scene has no splats: add at least one [[object]]".into(),
        ));
    }
    // The materials of lights that reflect, named as objects name theirs.
    let mut light_materials = Vec::with_capacity(file.lights.len());
    for (k, desc) in file.lights.iter().enumerate() {
        let at = |m: String| at_line(desc.span(), format!("light #{}: {m}", k + 1));
        light_materials.push(match desc.get_ref() {
            LightDesc::Area {
                material: Some(name),
                spacing,
                ..
            } => Some((
                material_index(Some(name)).map_err(at)?,
                positive(spacing.unwrap_or(DEFAULT_SPACING), "spacing").map_err(at)?,
            )),
            _ => None,
        });
    }
    for (name, m) in extra_materials {
        materials.push(material(&m).map_err(|msg| invalid(format!("material {name}: {msg}")))?);
        material_names.push(name);
    }
    let bounds = crate::grid::splat_bounds(&splats).unwrap_or((Vec3::ZERO, Vec3::ZERO));

    let mut lights = Vec::new();
    let mut sky = None;
    for (k, l) in file.lights.iter().enumerate() {
        let at = |m: String| at_line(l.span(), format!("light #{}: {m}", k + 1));
        let is_sky = matches!(
            l.get_ref(),
            LightDesc::Environment { .. } | LightDesc::Sky { .. }
        );
        if is_sky && sky.is_some() {
            return Err(at("a scene has at most one environment light".into()));
        }
        let map = match l.get_ref() {
            LightDesc::Environment {
                map,
                radiance,
                scale,
                ..
            } => {
                let map = environment_map(map.as_deref(), *radiance, *scale, base_dir);
                Some((map.map_err(at)?, None))
            }
            LightDesc::Sky {
                sun_elevation,
                sun_azimuth,
                turbidity,
                ground_albedo,
                scale,
                ..
            } => {
                let scale = positive(scale.unwrap_or(1.0), "scale").map_err(at)?;
                let sun = (*sun_elevation, sun_azimuth.unwrap_or(0.0));
                let (turbidity, albedo) = (turbidity.unwrap_or(3.0), ground_albedo.unwrap_or(0.3));
                let map = sky::hosek_wilkie(sun, turbidity, albedo, scale).map_err(at)?;
                Some((map, Some(albedo)))
            }
            _ => None,
        };
        lights.push(light(l.get_ref(), bounds, map.as_ref().map(|m| &m.0)).map_err(at)?);
        if let Some((map, albedo)) = map {
            sky = Some((map, albedo, lights.len() - 1));
        }
    }
    // A sky model's ground, below its horizon, is lit by the scene's suns too.
    if let Some((map, Some(albedo), at)) = &mut sky {
        let up = Vec3::from(lights[*at].direction);
        for sun in lights.iter().filter(|l| l.kind == light_kind::SUN) {
            let cos = (-Vec3::from(sun.direction).dot(up)).max(0.0);
            let e = Vec3::from(sun.power) / sun.area * cos;
            map.light_ground((e * (*albedo / std::f32::consts::PI)).into());
        }
    }
    let sky = sky.map(|(map, ..)| map.table());
    if lights.is_empty() {
        return Err(invalid(
            "the scene has no lights: add at least one [[light]]".into(),
        ));
    }
    // Lights that reflect: each a surface of splats of its material, after the objects'.
    for (k, (light, body)) in lights.iter().zip(&light_materials).enumerate() {
        let Some((mat, spacing)) = *body else {
            continue;
        };
        let (frame, size) = light_body(light, spacing);
        let planned = shapes::quad_count(&frame, size, spacing);
        if planned > MAX_OBJECT_SPLATS as f64 {
            let span = file.lights[k].span();
            return Err(at_line(
                span,
                format!(
                    "light #{}: its surface at spacing {spacing} would make {planned:.3e} \
                     splats, more than the {MAX_OBJECT_SPLATS} one object may have: raise \
                     `spacing`",
                    k + 1,
                ),
            ));
        }
        let what = format!("the scene with light #{}'s surface", k + 1);
        let made = splats.len() as f64;
        let count_at = |s: f32| made + shapes::quad_count(&frame, size, s);
        (budget.check_splats(&what, spacing, &count_at))
            .map_err(|m| at_line(file.lights[k].span(), m))?;
        let mut disks = Vec::new();
        shapes::quad(&frame, size, spacing, &mut disks);
        let clip = shapes::quad_clip(&frame, size, spacing);
        let object = surfaces.len() as u32;
        surfaces.push(format!("light {}", k + 1));
        clips.push(clip);
        let diffuse = material_descs[mat as usize].diffuse.rgb();
        splats.extend(disks.iter().map(|d| Splat {
            center: d.center.into(),
            radius: d.radius,
            normal: d.normal.into(),
            material: mat,
            diffuse,
            object,
        }));
    }

    let mut scene = Scene {
        path: path.to_owned(),
        camera: file.camera,
        bake: file.bake,
        grid: file.grid,
        splats,
        materials,
        material_names,
        lights,
        objects,
        surfaces,
        clips,
        sky: sky.unwrap_or_default(),
        origin: Vec3::ZERO,
        budget,
    };
    scene
        .check_radius()
        .map_err(|m| invalid(format!("[bake]: {m}")))?;
    scene.recentre();
    sides::add_back_sides(&mut scene, &models).map_err(invalid)?;
    Ok(scene)
}

/// How far behind its emitting face a reflecting light's surface lies, in its splats' spacing:
/// far above a hit's rounding (a spacing of 0.025 puts it 2.5e-5 behind, fifty float steps at
/// a distance of 4), and thin enough that the camera sees no rim of it beside the light: at
/// 0.01 a spacing, a band of a tenth of a pixel along the light's near edge showed the
/// surface's underside at 256², and GL and Vulkan split some of its pixels differently.
const LIGHT_BODY_OFFSET: f32 = 1e-3;

/// Where the surface of an area light that reflects lies, as a `quad` object's transform and
/// size: the light's rectangle a little behind its emitting face, facing the way it emits (so
/// that rays meeting the light's front hit it).
fn light_body(l: &Light, spacing: f32) -> (Affine3A, [f32; 2]) {
    let (eu, ev) = (Vec3::from(l.edge_u), Vec3::from(l.edge_v));
    let n = Vec3::from(l.direction);
    let centre = Vec3::from(l.position) + 0.5 * (eu + ev) - n * (LIGHT_BODY_OFFSET * spacing);
    let frame = Affine3A::from_cols(
        eu.normalize().into(),
        ev.normalize().into(),
        n.into(),
        centre.into(),
    );
    (frame, [eu.length(), ev.length()])
}

fn finite3(v: [f32; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// A camera that can draw (also each view of a view list, `views`).
pub(crate) fn validate_camera(c: &CameraDesc) -> std::result::Result<(), String> {
    if !(finite3(c.eye) && finite3(c.target) && finite3(c.up)) {
        return Err("eye, target and up must be finite".into());
    }
    let forward = Vec3::from(c.target) - Vec3::from(c.eye);
    if forward.length() < 1e-12 {
        return Err("eye and target coincide".into());
    }
    if forward.cross(c.up.into()).length() < 1e-6 * forward.length() * Vec3::from(c.up).length() {
        return Err("up is zero or parallel to the viewing direction".into());
    }
    if !(c.fov > 0.0 && c.fov < 180.0) {
        return Err(format!(
            "fov must be between 0 and 180 degrees, got {}",
            c.fov
        ));
    }
    let [w, h] = c.resolution;
    check_resolution(w, h)
}

/// Image sizes the renderer accepts, for the scene's camera and for command-line overrides.
pub fn check_resolution(w: u32, h: u32) -> std::result::Result<(), String> {
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!(
            "resolution must be within 1..=16384 per side, got {w}x{h}"
        ));
    }
    Ok(())
}

/// `x` when it is finite and above zero, else the error "`what` must be positive, got x".
fn positive(x: f32, what: &str) -> std::result::Result<f32, String> {
    if x > 0.0 && x.is_finite() {
        Ok(x)
    } else {
        Err(format!("{what} must be positive, got {x}"))
    }
}

/// A rectangle's [width, height], both positive.
fn positive_size(size: [f32; 2]) -> std::result::Result<[f32; 2], String> {
    if size.iter().all(|&s| positive(s, "").is_ok()) {
        Ok(size)
    } else {
        Err(format!("size must be positive, got {size:?}"))
    }
}

fn validate_bake(b: &BakeDesc) -> std::result::Result<(), String> {
    crate::photons::check_photon_count(b.photons)?;
    if let Some(r) = b.radius {
        crate::em::check_radius(r)?;
    }
    crate::em::check_lobes(b.lobes)?;
    if b.iterations == 0 || b.iterations > 1000 {
        return Err(format!(
            "iterations must be within 1..=1000, got {}",
            b.iterations
        ));
    }
    crate::em::check_slab(b.slab)?;
    crate::em::check_gather(b.gather)?;
    crate::em::check_share(b.share)?;
    crate::em::check_smooth(b.smooth)?;
    if b.max_depth == 0 || b.max_depth > 64 {
        return Err(format!(
            "max_depth must be within 1..=64, got {}",
            b.max_depth
        ));
    }
    Ok(())
}

fn material(m: &MaterialDesc) -> std::result::Result<Material, String> {
    let (d, s) = (m.diffuse.rgb(), m.specular.rgb());
    for (name, c) in [("diffuse", d), ("specular", s)] {
        if !c.iter().all(|x| (0.0..=1.0).contains(x)) {
            return Err(format!(
                "{name} albedo must be within [0, 1] per channel, got {c:?}"
            ));
        }
    }
    if (0..3).any(|i| d[i] + s[i] > 1.0 + 1e-6) {
        return Err(format!(
            "diffuse + specular exceeds 1 ({d:?} + {s:?}): the surface would create energy"
        ));
    }
    Ok(Material {
        specular: s,
        roughness: positive(m.roughness, "roughness")?,
    })
}

fn nonneg_rgb(c: [f32; 3], what: &str) -> std::result::Result<[f32; 3], String> {
    if c.iter().all(|x| x.is_finite() && *x >= 0.0) {
        Ok(c)
    } else {
        Err(format!("{what} must be finite and non-negative, got {c:?}"))
    }
}

fn unit(v: [f32; 3], what: &str) -> std::result::Result<Vec3, String> {
    let v = Vec3::from(v);
    if !v.is_finite() || v.length() < 1e-12 {
        return Err(format!(
            "{what} must be a finite non-zero vector, got {v:?}"
        ));
    }
    Ok(v.normalize())
}

fn one_of(
    a: Option<file::Rgb>,
    b: Option<file::Rgb>,
    names: &str,
) -> std::result::Result<(bool, [f32; 3]), String> {
    match (a, b) {
        (Some(a), None) => Ok((true, a.rgb())),
        (None, Some(b)) => Ok((false, b.rgb())),
        _ => Err(format!("give exactly one of {names}")),
    }
}

/// The sun's angular diameter (degrees) where a `sun` light gives none.
const SUN_ANGLE: f32 = 0.53;

/// An environment light's map: the image at `map` (relative to `base_dir`) or the constant
/// `radiance`, times `scale`.
fn environment_map(
    map: Option<&str>,
    radiance: Option<file::Rgb>,
    scale: Option<f32>,
    base_dir: &Path,
) -> std::result::Result<sky::Sky, String> {
    let scale = positive(scale.unwrap_or(1.0), "scale")?;
    let sky = match (map, radiance) {
        (Some(m), None) => sky::Sky::load(&base_dir.join(m), scale)?,
        (None, Some(c)) => {
            let c = nonneg_rgb(c.rgb(), "radiance")?.map(|x| x * scale);
            let sky = sky::Sky::constant(c);
            sky.check()?;
            sky
        }
        _ => return Err("give exactly one of `map` (an EXR or .hdr image) or `radiance`".into()),
    };
    Ok(sky)
}

/// The disk a light far away (directional, the sun, a sky) sends its photons from: across the
/// bounding sphere of the splats within `(lo, hi)`, its centre, radius and area.
fn covering_disk((lo, hi): (Vec3, Vec3)) -> (Vec3, f32, f32) {
    let r = (0.5 * (hi - lo).length()).max(1e-6);
    (0.5 * (lo + hi), r, std::f32::consts::PI * r * r)
}

/// The scene's light of description `l`, its scene's splats within `(lo, hi)`; `sky` is an
/// environment light's map.
fn light(
    l: &LightDesc,
    (lo, hi): (Vec3, Vec3),
    sky: Option<&sky::Sky>,
) -> std::result::Result<Light, String> {
    let four_pi = 4.0 * std::f32::consts::PI;
    let mut out = Light::default();
    match l {
        LightDesc::Point {
            position,
            power,
            intensity,
        } => {
            let (is_power, c) = one_of(*power, *intensity, "`power` (W) or `intensity` (W/sr)")?;
            let c = nonneg_rgb(c, "power")?;
            out.kind = light_kind::POINT;
            out.position = finite_point(*position)?;
            out.power = if is_power { c } else { c.map(|x| x * four_pi) };
        }
        LightDesc::Spot {
            position,
            direction,
            target,
            power,
            angle,
            inner_angle,
        } => {
            let dir = match (direction, target) {
                (Some(d), None) => unit(*d, "direction")?,
                (None, Some(t)) => unit(
                    (Vec3::from(*t) - Vec3::from(*position)).into(),
                    "target - position",
                )?,
                _ => return Err("give exactly one of `direction` or `target`".into()),
            };
            let inner = inner_angle.unwrap_or(*angle);
            if !(*angle > 0.0 && *angle < 180.0 && inner > 0.0 && inner <= *angle) {
                return Err(format!(
                    "need 0 < inner_angle <= angle < 180 degrees, got {inner} and {angle}"
                ));
            }
            out.kind = light_kind::SPOT;
            out.position = finite_point(*position)?;
            out.direction = dir.into();
            out.power = nonneg_rgb(power.rgb(), "power")?;
            out.cos_outer = angle.to_radians().cos();
            out.cos_inner = inner.to_radians().cos();
        }
        LightDesc::Area {
            center,
            size,
            normal,
            u_axis,
            radiance,
            power,
            material,
            spacing: _,
        } => {
            let n = unit(*normal, "normal")?;
            positive_size(*size)?;
            let u_hint = match u_axis {
                Some(u) => unit(*u, "u_axis")?,
                None => least_aligned_axis(n),
            };
            let u = (u_hint - n * n.dot(u_hint)).normalize_or_zero();
            if u == Vec3::ZERO {
                return Err("u_axis is parallel to normal".into());
            }
            let v = n.cross(u);
            let (eu, ev) = (u * size[0], v * size[1]);
            let area = size[0] * size[1];
            let (is_radiance, c) =
                one_of(*radiance, *power, "`radiance` (W/m²/sr) or `power` (W)")?;
            let c = nonneg_rgb(c, "emission")?;
            out.kind = light_kind::AREA;
            if material.is_some() {
                out.flags |= light_flags::REFLECTS;
            }
            out.position = (Vec3::from(finite_point(*center)?) - 0.5 * (eu + ev)).into();
            out.direction = n.into();
            out.edge_u = eu.into();
            out.edge_v = ev.into();
            out.area = area;
            // A one-sided Lambertian emitter of radiance L emits π·L·A watts.
            out.power = if is_radiance {
                c.map(|x| x * std::f32::consts::PI * area)
            } else {
                c
            };
        }
        LightDesc::Directional {
            direction,
            irradiance,
        } => {
            let d = unit(*direction, "direction")?;
            // Emit from a disk that covers the scene's bounding sphere, outside it.
            let (center, r, area) = covering_disk((lo, hi));
            out.kind = light_kind::DIRECTIONAL;
            out.position = (center - d * (2.0 * r)).into();
            out.direction = d.into();
            out.area = area;
            out.power = nonneg_rgb(irradiance.rgb(), "irradiance")?.map(|x| x * area);
        }
        LightDesc::Sun {
            direction,
            irradiance,
            angle,
        } => {
            let d = unit(*direction, "direction")?;
            let angle = angle.unwrap_or(SUN_ANGLE);
            if !(angle > 0.0 && angle < 90.0) {
                return Err(format!("angle must be in (0, 90) degrees, got {angle}"));
            }
            let (center, r, area) = covering_disk((lo, hi));
            let half = f64::from(angle).to_radians() / 2.0;
            out.kind = light_kind::SUN;
            out.position = (center - d * (2.0 * r)).into();
            out.direction = d.into();
            out.area = area;
            out.cos_outer = half.cos() as f32;
            // 1 − cos, from the half-angle's sine: exact where the cosine rounds to 1.
            out.cos_inner = (2.0 * (half / 2.0).sin().powi(2)) as f32;
            out.power = nonneg_rgb(irradiance.rgb(), "irradiance")?.map(|x| x * area);
        }
        LightDesc::Environment { rotation, up, .. } | LightDesc::Sky { rotation, up, .. } => {
            let sky = sky.ok_or("an environment light needs its map")?;
            let rotation = rotation.unwrap_or(0.0);
            if !rotation.is_finite() {
                return Err(format!("rotation must be finite, got {rotation}"));
            }
            let up = match up.unwrap_or_default() {
                file::UpAxis::Y => Vec3::Y,
                file::UpAxis::Z => Vec3::Z,
            };
            let [x, y, z] = sky::frame(up, rotation);
            // Photons start on a disk across the scene's bounding sphere, as a directional
            // light's do, from every direction.
            let (center, _, area) = covering_disk((lo, hi));
            out.kind = light_kind::ENVIRONMENT;
            out.position = center.into();
            out.edge_u = x.into();
            out.direction = y.into();
            out.edge_v = z.into();
            out.area = area;
            out.power = sky.integral().map(|x| x * area);
        }
    }
    // Each value finite, its power (times 4π, an area or the scene's cross-section) may not be.
    if !out.power.iter().all(|x| x.is_finite()) {
        return Err(format!(
            "its power comes to {:?} W, past what f32 holds (3.4e38): give a smaller power, \
             intensity, radiance or irradiance",
            out.power
        ));
    }
    Ok(out)
}

fn finite_point(p: [f32; 3]) -> std::result::Result<[f32; 3], String> {
    if finite3(p) {
        Ok(p)
    } else {
        Err(format!("position must be finite, got {p:?}"))
    }
}

/// The world axis most perpendicular to `n`, a default tangent.
fn least_aligned_axis(n: Vec3) -> Vec3 {
    let a = n.abs();
    if a.x <= a.y && a.x <= a.z {
        Vec3::X
    } else if a.y <= a.z {
        Vec3::Y
    } else {
        Vec3::Z
    }
}

fn transform(o: &ObjectDesc) -> std::result::Result<Affine3A, String> {
    let scale = match o.scale {
        None => Vec3::ONE,
        Some(Scale::Uniform(s)) => Vec3::splat(s),
        Some(Scale::PerAxis(s)) => Vec3::from(s),
    };
    if !scale.is_finite() || scale.abs().min_element() < 1e-12 {
        return Err(format!("scale must be finite and non-zero, got {scale:?}"));
    }
    let r = Vec3::from(o.rotate.unwrap_or([0.0; 3]));
    let t = Vec3::from(o.translate.unwrap_or([0.0; 3]));
    if !r.is_finite() || !t.is_finite() {
        return Err("rotate and translate must be finite".into());
    }
    let rot = Quat::from_rotation_z(r.z.to_radians())
        * Quat::from_rotation_y(r.y.to_radians())
        * Quat::from_rotation_x(r.x.to_radians());
    Ok(Affine3A::from_scale_rotation_translation(scale, rot, t))
}

/// Keys each shape accepts besides shape, material and the transform.
fn allowed_keys(shape: ShapeKind) -> &'static [&'static str] {
    match shape {
        ShapeKind::CornellBox => &["left_material", "right_material", "spacing"],
        ShapeKind::Box => &["spacing"],
        ShapeKind::Sphere => &["radius", "spacing"],
        ShapeKind::Quad => &["size", "spacing"],
        ShapeKind::Model => &[
            "path",
            "array",
            "fit",
            "anchor",
            "vertex_colors",
            "sides",
            "spacing",
        ],
    }
}

fn set_keys(o: &ObjectDesc) -> Vec<&'static str> {
    let mut keys = Vec::new();
    let mut add = |present: bool, name| {
        if present {
            keys.push(name);
        }
    };
    add(o.left_material.is_some(), "left_material");
    add(o.right_material.is_some(), "right_material");
    add(o.spacing.is_some(), "spacing");
    add(o.radius.is_some(), "radius");
    add(o.size.is_some(), "size");
    add(o.path.is_some(), "path");
    add(o.array.is_some(), "array");
    add(o.fit.is_some(), "fit");
    add(o.anchor.is_some(), "anchor");
    add(o.vertex_colors.is_some(), "vertex_colors");
    add(o.sides.is_some(), "sides");
    keys
}

/// Where an object's splats go: the scene's splats and surface names, and the object's name.
struct Built<'a> {
    splats: &'a mut Vec<Splat>,
    surfaces: &'a mut Vec<String>,
    clips: &'a mut Vec<SurfaceClip>,
    name: String,
    /// Materials the object's model file defines (MTL), appended after the scene's own
    /// `first_extra` materials.
    extra_materials: &'a mut Vec<(String, MaterialDesc)>,
    first_extra: u32,
    /// What the scene's splats may take, this object's with those before it.
    budget: Budget,
    /// Models handed over in memory.
    arrays: &'a Arrays,
}

/// An object's name in object-ID images: its place in the file and its shape, and its
/// material where it has one (a Cornell box's walls name themselves instead).
fn surface_name(k: usize, o: &ObjectDesc) -> String {
    let name = format!("#{} {}", k + 1, o.shape.name());
    match &o.material {
        Some(m) if o.shape != ShapeKind::CornellBox => format!("{name} ({m})"),
        _ => name,
    }
}

/// Splats a model's surface is sampled at, in model units, where it is sampled: at the object's
/// `spacing` (world units, through `fit` and the transform's largest stretch), or, for a mesh
/// whose mean edge is over twice it, at the default of 1/80 of its extent (a coarse mesh: a
/// splat a vertex would be as large as a wall). Dense meshes and clouds keep a splat a vertex.
fn model_spacing(
    mesh: &model::Mesh,
    o: &ObjectDesc,
    fit: Option<f32>,
    m: &Affine3A,
) -> Option<f32> {
    if mesh.faces.is_empty() {
        return None;
    }
    let extent = model::surface::extent(mesh);
    let world_per_model =
        fit.map_or(1.0, |f| f / extent.max(f32::MIN_POSITIVE)) * shapes::max_scale(m);
    match o.spacing {
        Some(s) if s > 0.0 && s.is_finite() && world_per_model > 0.0 => Some(s / world_per_model),
        _ => {
            let default = extent / MODEL_SPACING_DIVISIONS;
            (default > 0.0 && model::surface::mean_edge(mesh) > 2.0 * default).then_some(default)
        }
    }
}

/// A coarse model's default splat spacing: its extent over this many.
pub const MODEL_SPACING_DIVISIONS: f32 = 80.0;

/// The Ward material of an MTL material: ρd = Kd, ρs = Ks, α = √(2 / (Ns + 2)) (the Beckmann
/// width of a Phong exponent), within [0.01, 1]; where ρd + ρs exceeds 1 in a channel both are
/// scaled down so that the material stays energy-bounded.
fn mtl_material(m: &model::MeshMaterial) -> MaterialDesc {
    let clamp = |c: [f32; 3]| c.map(|v| v.clamp(0.0, 1.0));
    let (kd, ks) = (clamp(m.kd), clamp(m.ks));
    let over = (0..3).map(|i| kd[i] + ks[i]).fold(1.0f32, f32::max);
    MaterialDesc {
        diffuse: file::Rgb::Rgb(kd.map(|v| v / over)),
        specular: file::Rgb::Rgb(ks.map(|v| v / over)),
        roughness: (2.0 / (m.ns.max(0.0) + 2.0)).sqrt().clamp(0.01, 1.0),
    }
}

/// Names of a Cornell box's walls, in `shapes::cornell_walls`' order.
const CORNELL_WALLS: [&str; 5] = ["floor", "ceiling", "back", "left", "right"];

fn build_object(
    o: &ObjectDesc,
    base_dir: &Path,
    material_index: &dyn Fn(Option<&String>) -> std::result::Result<u32, String>,
    material_descs: &[MaterialDesc],
    out: Built,
    at: &dyn Fn(String) -> Error,
) -> Result<ObjectSummary> {
    let Built {
        splats,
        surfaces,
        clips,
        name,
        extra_materials,
        first_extra,
        budget,
        arrays,
    } = out;
    // Splats this object and the ones before it make, against the memory budget.
    let made = splats.len() as f64;
    let within = |spacing: f32, count_at: &dyn Fn(f32) -> f64| {
        let what = "the scene up to this object";
        budget.check_splats(what, spacing, &|s| made + count_at(s))
    };
    for key in set_keys(o) {
        if !allowed_keys(o.shape).contains(&key) {
            return Err(at(format!("key `{key}` does not apply to this shape")));
        }
    }
    let m = transform(o).map_err(at)?;
    let spacing = positive(o.spacing.unwrap_or(DEFAULT_SPACING), "spacing").map_err(at)?;
    let material = material_index(o.material.as_ref()).map_err(at)?;
    let diffuse_of = |mat: u32| material_descs[mat as usize].diffuse.rgb();
    let before = splats.len();
    // Each call is one surface, named `name` plus `part` where an object has several.
    let mut push =
        |disks: &[Disk], mat: u32, diffuse: Option<&[[f32; 3]]>, part: &str, clip: SurfaceClip| {
            let object = surfaces.len() as u32;
            clips.push(clip);
            surfaces.push(match part {
                "" => name.clone(),
                part => format!("{name} {part}"),
            });
            for (k, d) in disks.iter().enumerate() {
                splats.push(Splat {
                    center: d.center.into(),
                    radius: d.radius,
                    normal: d.normal.into(),
                    material: mat,
                    diffuse: diffuse.map_or_else(|| diffuse_of(mat), |c| c[k]),
                    object,
                });
            }
        };
    let planned_at = |spacing: f32| match o.shape {
        ShapeKind::CornellBox => shapes::cornell_count(&m, spacing),
        ShapeKind::Box => shapes::cube_count(&m, spacing),
        ShapeKind::Sphere => shapes::sphere_count(&m, o.radius.unwrap_or(1.0), spacing),
        ShapeKind::Quad => shapes::quad_count(&m, o.size.unwrap_or([1.0, 1.0]), spacing),
        ShapeKind::Model => 0.0,
    };
    let planned = planned_at(spacing);
    // A NaN count (a transform that is not finite) is refused too.
    if planned.is_nan() || planned > MAX_OBJECT_SPLATS as f64 {
        return Err(at(format!(
            "this shape at spacing {spacing} would make {planned:.3e} splats, more than the \
             {MAX_OBJECT_SPLATS} one object may have: raise `spacing` or lower `scale`"
        )));
    }
    within(spacing, &planned_at).map_err(at)?;
    let mut disks = Vec::new();
    let mut source = None;
    let mut dropped = 0;
    let mut left_out = model::LeftOut::default();
    match o.shape {
        ShapeKind::CornellBox => {
            let counts = shapes::cornell_walls(&m, spacing, &mut disks);
            let left =
                material_index(o.left_material.as_ref().or(o.material.as_ref())).map_err(at)?;
            let right =
                material_index(o.right_material.as_ref().or(o.material.as_ref())).map_err(at)?;
            let mut start = 0;
            for (wall, n) in counts.into_iter().enumerate() {
                let mat = match wall {
                    3 => left,
                    4 => right,
                    _ => material,
                };
                // Each wall ends where the box does.
                let clip = shapes::cube_clip(&m, spacing);
                push(
                    &disks[start..start + n],
                    mat,
                    None,
                    CORNELL_WALLS[wall],
                    clip,
                );
                start += n;
            }
        }
        ShapeKind::Box => {
            shapes::cube(&m, spacing, &mut disks);
            push(&disks, material, None, "", shapes::cube_clip(&m, spacing));
        }
        ShapeKind::Sphere => {
            let r = positive(o.radius.unwrap_or(1.0), "radius").map_err(at)?;
            shapes::sphere(&m, r, spacing, &mut disks);
            push(&disks, material, None, "", SurfaceClip::default());
        }
        ShapeKind::Quad => {
            let size = positive_size(o.size.unwrap_or([1.0, 1.0])).map_err(at)?;
            shapes::quad(&m, size, spacing, &mut disks);
            push(
                &disks,
                material,
                None,
                "",
                shapes::quad_clip(&m, size, spacing),
            );
        }
        ShapeKind::Model => {
            let (file, loaded);
            let mesh = match (&o.path, &o.array) {
                (Some(rel), None) => {
                    file = base_dir.join(rel);
                    loaded = model::load_with(&file, &model::Reading::within(budget))?;
                    &loaded
                }
                (None, Some(name)) => {
                    file = PathBuf::from(format!("array '{name}'"));
                    let mesh = arrays.get(name).ok_or_else(|| {
                        at(format!(
                            "no array named '{name}' was handed over (a scene file names its \
                             model by `path`)"
                        ))
                    })?;
                    model::check_array(&file, mesh)?;
                    mesh
                }
                (Some(_), Some(_)) => {
                    return Err(at("a model takes `path` or `array`, not both".into()));
                }
                (None, None) => return Err(at("a model needs `path`".into())),
            };
            let fit = o.fit.map(|f| positive(f, "fit")).transpose().map_err(at)?;
            let splat_set = match model_spacing(mesh, o, fit, &m) {
                Some(step) => {
                    // The sampled surface's splats, counted before any is made.
                    // In the file's units: `spacing` over the scene's scale of them.
                    let per = step / spacing;
                    let count_at = |s: f32| model::surface::planned(mesh, s * per);
                    within(spacing, &count_at).map_err(at)?;
                    model::surface::sample_surface(mesh, step)
                }
                None => {
                    let points = made + mesh.positions.len() as f64;
                    let what = "the scene up to this object";
                    budget.check_points(what, points).map_err(at)?;
                    model::to_splats(mesh, &file)?
                }
            };
            dropped = splat_set.dropped;
            left_out = mesh.left_out.clone();
            let placed = model::place(
                &splat_set.disks,
                fit,
                o.anchor.unwrap_or(Anchor::Center),
                &m,
            );
            let colors = splat_set
                .colors
                .as_deref()
                .filter(|_| o.vertex_colors.unwrap_or(true));
            match splat_set
                .materials
                .as_ref()
                .filter(|_| o.material.is_none())
            {
                // The file's materials (MTL), one surface each, unless the scene names one.
                Some(of_disk) => {
                    // The disks of each material in one pass (last: faces with none).
                    let none = mesh.materials.len();
                    let mut groups = vec![Vec::new(); none + 1];
                    for (i, &k) in of_disk.iter().enumerate() {
                        groups[(k as usize).min(none)].push(i);
                    }
                    for (mm, pick) in mesh.materials.iter().zip(&groups) {
                        if !mm.defined {
                            return Err(at(format!(
                                "its material `{}` is not defined by the file's material \
                                 libraries ({}): name a `material` for the object",
                                mm.name,
                                mesh.material_libraries.join(", ")
                            )));
                        }
                        let index = first_extra + extra_materials.len() as u32;
                        let desc = mtl_material(mm);
                        let albedo = desc.diffuse.rgb();
                        extra_materials.push((format!("{name}/{}", mm.name), desc));
                        let disks: Vec<Disk> = pick.iter().map(|&i| placed[i]).collect();
                        // The scene's material list gets these after all objects: the splats
                        // carry their albedo here (the vertex colours', where there are any).
                        let albedos: Vec<[f32; 3]> = match colors {
                            Some(c) => pick.iter().map(|&i| c[i]).collect(),
                            None => vec![albedo; pick.len()],
                        };
                        if !disks.is_empty() {
                            let none = SurfaceClip::default();
                            push(&disks, index, Some(&albedos), &mm.name, none);
                        }
                    }
                    // Faces with no material keep their vertex colours, as in a model with none.
                    let rest: Vec<Disk> = groups[none].iter().map(|&i| placed[i]).collect();
                    let rest_colors: Option<Vec<[f32; 3]>> =
                        colors.map(|c| groups[none].iter().map(|&i| c[i]).collect());
                    if !rest.is_empty() {
                        let none = SurfaceClip::default();
                        push(&rest, material, rest_colors.as_deref(), "", none);
                    }
                }
                None => push(&placed, material, colors, "", SurfaceClip::default()),
            }
            source = Some(o.path.clone().unwrap_or_else(|| file.display().to_string()));
        }
    }
    // Sizes near the limits of f32 make disks of radius 0 or infinite ones: refused here, so
    // that no stage meets a degenerate splat.
    if let Some(bad) = splats[before..].iter().find(|s| !splat_is_sane(s)) {
        return Err(at(format!(
            "this object makes a degenerate splat (radius {}, centre {:?}, normal {:?}): its \
             size, scale, fit or spacing is out of range",
            bad.radius, bad.center, bad.normal
        )));
    }
    Ok(ObjectSummary {
        shape: o.shape.name().to_string(),
        source,
        splats: splats.len() - before,
        dropped,
        dropped_by: left_out.by_rule,
        skipped: left_out.skipped,
        first_skipped: left_out.first_skipped,
        back_sides: 0,
    })
}
