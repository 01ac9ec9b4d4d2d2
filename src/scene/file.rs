//! The scene file format (TOML), as serde structs. Every table denies unknown keys, so a typo
//! is an error that names the file, line and key instead of a silently ignored setting.
//! docs/scenes.md documents the format; `scene::load` turns it into splats, lights and materials.

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::grid::GridConfig;
pub use crate::photons::StoreRange;

pub type Vec3 = [f32; 3];

/// An RGB triple, or one number for grey.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rgb {
    Grey(f32),
    Rgb(Vec3),
}

/// Read by hand, so that a wrong colour says what a colour is (an untagged enum's error names
/// no form: "data did not match any variant").
impl<'de> Deserialize<'de> for Rgb {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Rgb, D::Error> {
        struct Colour;
        impl<'de> serde::de::Visitor<'de> for Colour {
            type Value = Rgb;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a colour: one number (grey) or three, [r, g, b]")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<Rgb, E> {
                Ok(Rgb::Grey(v as f32))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<Rgb, E> {
                Ok(Rgb::Grey(v as f32))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Rgb, E> {
                Ok(Rgb::Grey(v as f32))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<Rgb, A::Error> {
                let mut c = Vec::new();
                while let Some(v) = seq.next_element::<f32>()? {
                    c.push(v);
                }
                match c[..] {
                    [r, g, b] => Ok(Rgb::Rgb([r, g, b])),
                    _ => Err(serde::de::Error::custom(format!(
                        "a colour is one number (grey) or three, [r, g, b]: got {} numbers",
                        c.len()
                    ))),
                }
            }
        }
        d.deserialize_any(Colour)
    }
}

impl Rgb {
    pub fn rgb(self) -> Vec3 {
        match self {
            Rgb::Grey(v) => [v; 3],
            Rgb::Rgb(c) => c,
        }
    }
}

/// A uniform scale factor or one per axis.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f32),
    PerAxis(Vec3),
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(default)]
    pub camera: CameraDesc,
    #[serde(default)]
    pub bake: BakeDesc,
    #[serde(default)]
    pub grid: GridConfig,
    /// Named materials; objects refer to them by name. `default` is grey diffuse unless defined.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialDesc>,
    #[serde(default, rename = "light")]
    pub lights: Vec<toml::Spanned<LightDesc>>,
    #[serde(default, rename = "object")]
    pub objects: Vec<toml::Spanned<ObjectDesc>>,
    /// The memory budget of what the scene makes (`budget::parse_size`: `"8G"`); the
    /// command line's `--max-memory` wins.
    #[serde(default)]
    pub max_memory: Option<String>,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraDesc {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Field of view in degrees, along `fov_axis`.
    pub fov: f32,
    /// "x" (horizontal, as Mitsuba's default) or "y".
    pub fov_axis: FovAxis,
    /// Image size in pixels, [width, height].
    pub resolution: [u32; 2],
    /// What the camera sees where it sees nothing: `"sky"` (the sky and the sun's disk, black
    /// without them), `"black"`, or a colour.
    pub background: Background,
}

/// What the camera sees where its ray meets nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Background {
    #[default]
    Sky,
    Colour([f32; 3]),
}

impl Background {
    /// `ShadeParams::background` and `PathParams::background`.
    pub fn uniform(self) -> [f32; 4] {
        match self {
            Background::Sky => [0.0; 4],
            Background::Colour([r, g, b]) => [r, g, b, 1.0],
        }
    }

    /// `"sky"`, `"black"`, or a colour `r,g,b` (linear, non-negative).
    pub fn parse(text: &str) -> Result<Background, String> {
        match text.trim() {
            "sky" => Ok(Background::Sky),
            "black" => Ok(Background::Colour([0.0; 3])),
            rgb => {
                let parts: Vec<f32> = (rgb.split(','))
                    .map(|p| p.trim().parse::<f32>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| {
                        format!("a background is `sky`, `black` or `r,g,b`, got {text:?}")
                    })?;
                match parts[..] {
                    [r, g, b] if parts.iter().all(|x| x.is_finite() && *x >= 0.0) => {
                        Ok(Background::Colour([r, g, b]))
                    }
                    _ => Err(format!(
                        "a background colour is three finite, non-negative numbers, got {text:?}"
                    )),
                }
            }
        }
    }
}

impl<'de> Deserialize<'de> for Background {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Background, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Form {
            Word(String),
            Colour(Rgb),
        }
        match Form::deserialize(d).map_err(|_| {
            serde::de::Error::custom("a background is \"sky\", \"black\" or a colour")
        })? {
            Form::Word(w) => Background::parse(&w).map_err(serde::de::Error::custom),
            Form::Colour(c) => {
                let c = c.rgb();
                if c.iter().all(|x| x.is_finite() && *x >= 0.0) {
                    Ok(Background::Colour(c))
                } else {
                    Err(serde::de::Error::custom(format!(
                        "a background colour is finite and non-negative, got {c:?}"
                    )))
                }
            }
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FovAxis {
    #[default]
    X,
    Y,
}

impl Default for CameraDesc {
    /// The camera of Mitsuba 3's Cornell box (`scenes/diffuse.toml`, docs/scenes.md).
    fn default() -> Self {
        CameraDesc {
            eye: [0.0, 0.0, 3.9],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov: 39.3077,
            fov_axis: FovAxis::X,
            resolution: [512, 512],
            background: Background::Sky,
        }
    }
}

/// Lighting-bake settings; the command line overrides them.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BakeDesc {
    /// Photons emitted.
    pub photons: u64,
    /// Photon search radius for the lobe fit; default: 1/40 of the scene's largest extent.
    pub radius: Option<f32>,
    /// Lobes per splat (with `prune`, the most a splat keeps).
    pub lobes: u32,
    /// EM iterations.
    pub iterations: u32,
    pub seed: u32,
    /// Maximum photon path length (bounces).
    pub max_depth: u32,
    /// Which photon hits are stored: "indirect" (bounce >= 1, the thesis's choice: direct
    /// light comes from shadow rays) or "all".
    pub store: StoreRange,
    /// Lobe family: "vmf" (default) or "ward" (the thesis's).
    pub family: crate::em::LobeFamily,
    /// Sparse EM (thesis §3.5).
    pub sparse: bool,
    /// Photons count for a splat within this many splat radii of its plane.
    pub slab: f32,
    /// Drop the lobes a splat's photons do not need (a BIC test after the fit), so splats
    /// lit from few directions keep fewer lobes and shade faster.
    pub prune: bool,
    /// Most candidate photons one splat's lobe fit visits per pass (0: all): past it an even
    /// subset, reweighted, bounds the fit's time by splats, not photons; irradiance still
    /// sums every photon.
    pub fit_candidates: u32,
    /// Final gathering: glossy splats fit their lobes to `gather`² rays cast from their
    /// centres, each bringing back the baked light of the diffuse surface it meets, instead
    /// of to the photons within the search radius (0: the photons, the thesis's fit).
    pub gather: u32,
    /// Where the splats' photon irradiance comes from: "deposits" (default; time bounded by
    /// splats, with final gathering) or "photons" (every photon within the search radius).
    pub estimate: crate::em::Estimate,
    /// Shared fits: fitted splats within one cell of this many search radii, facing alike,
    /// share one lobe fit, whose rays all of them cast (0: each splat fits its own lobes).
    pub share: f32,
    /// The photons' estimate widened where the light is smooth: the widest kernel, in search
    /// radii (0: each splat keeps its own estimate).
    pub smooth: f32,
}

impl Default for BakeDesc {
    fn default() -> Self {
        BakeDesc {
            photons: 1_000_000,
            radius: None,
            lobes: 8,
            iterations: 10,
            seed: 1,
            max_depth: 8,
            store: StoreRange::Indirect,
            family: crate::em::LobeFamily::Vmf,
            sparse: false,
            slab: 2.0,
            prune: true,
            fit_candidates: crate::em::DEFAULT_FIT_CANDIDATES,
            gather: crate::em::DEFAULT_GATHER,
            estimate: crate::em::Estimate::Deposits,
            share: crate::em::DEFAULT_SHARE,
            smooth: crate::em::DEFAULT_SMOOTH,
        }
    }
}

/// Isotropic Ward material (docs/design.md §3).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialDesc {
    /// Diffuse albedo ρd (linear RGB).
    pub diffuse: Rgb,
    /// Specular albedo ρs (linear RGB).
    pub specular: Rgb,
    /// Ward roughness α (> 0).
    pub roughness: f32,
}

impl Default for MaterialDesc {
    fn default() -> Self {
        MaterialDesc {
            diffuse: Rgb::Grey(0.5),
            specular: Rgb::Grey(0.0),
            roughness: 0.1,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub enum LightDesc {
    /// Isotropic point light: total power (W) or radiant intensity (W/sr).
    Point {
        position: Vec3,
        power: Option<Rgb>,
        intensity: Option<Rgb>,
    },
    /// Spot light: power (W) spread over the cone, smooth falloff between the angles.
    Spot {
        position: Vec3,
        /// The direction the spot points in; or give `target`.
        direction: Option<Vec3>,
        target: Option<Vec3>,
        power: Rgb,
        /// Half-angle of the cone in degrees.
        angle: f32,
        /// Half-angle in degrees inside which intensity is full; default = `angle`.
        inner_angle: Option<f32>,
    },
    /// One-sided rectangle emitting uniform radiance on the side of `normal`.
    Area {
        center: Vec3,
        /// Width along `u_axis` and height along normal × u_axis.
        size: [f32; 2],
        normal: Vec3,
        /// Direction of the first side; default: the world axis most perpendicular to `normal`.
        u_axis: Option<Vec3>,
        radiance: Option<Rgb>,
        power: Option<Rgb>,
        /// The material its front reflects with, as a surface of splats just behind its face
        /// (Mitsuba's lights reflect so); none: it reflects nothing.
        material: Option<String>,
        /// The spacing of that surface's splats (default: `DEFAULT_SPACING`).
        spacing: Option<f32>,
    },
    /// Parallel light travelling along `direction`, irradiance in W/m² across the beam.
    Directional { direction: Vec3, irradiance: Rgb },
    /// The sun: a directional light from a disk of the sky `angle` degrees across (0.53, the
    /// sun's), whose shadows are as soft as the sun's; `irradiance` (W/m²) on a surface facing
    /// it.
    Sun {
        direction: Vec3,
        irradiance: Rgb,
        angle: Option<f32>,
    },
    /// A clear sky by the Hosek–Wilkie model for a sun at `sun_elevation` and `sun_azimuth`
    /// (degrees; the azimuth in the map's frame, 0 along −z and 90 along +x for `up = "y"`),
    /// `turbidity` (3; 1–10) and `ground_albedo` (0.3), times `scale`: an environment light
    /// whose map is made at load. The sun's disk is a `sun` light of its own.
    Sky {
        sun_elevation: f32,
        sun_azimuth: Option<f32>,
        turbidity: Option<f32>,
        ground_albedo: Option<f32>,
        scale: Option<f32>,
        rotation: Option<f32>,
        up: Option<UpAxis>,
    },
    /// Light from every direction, a sky: a latitude-longitude HDR image (`map`: OpenEXR, or
    /// Radiance `.hdr`, relative to the scene file) or one `radiance` (W/m²/sr), times
    /// `scale`. One a scene.
    Environment {
        map: Option<String>,
        radiance: Option<Rgb>,
        /// Multiplies the map's or the radiance's values (default 1).
        scale: Option<f32>,
        /// Degrees the map turns about the up axis (default 0).
        rotation: Option<f32>,
        /// The scene's up axis, which the map's top looks along: "y" (default) or "z".
        up: Option<UpAxis>,
    },
}

/// A scene's up axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    #[default]
    Y,
    Z,
}

/// What an object is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// The five walls of [-1, 1]³, open towards +z, normals inwards.
    CornellBox,
    /// The cube [-1, 1]³, normals outwards.
    Box,
    /// A sphere of `radius` around the origin.
    Sphere,
    /// A `size` rectangle in the xy plane centred at the origin, normal +z.
    Quad,
    /// A PLY or OBJ file: a mesh (splats at its vertices) or a point cloud.
    Model,
}

impl ShapeKind {
    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ShapeKind::CornellBox => "cornell_box",
            ShapeKind::Box => "box",
            ShapeKind::Sphere => "sphere",
            ShapeKind::Quad => "quad",
            ShapeKind::Model => "model",
        }
    }
}

/// Where a fitted model's bounding box sits before the transform.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Anchor {
    #[default]
    Center,
    /// The box's bottom face centred at the origin (so `translate` puts it on a floor).
    Bottom,
}

/// Which of a model's disks get a back side (`scene::sides`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sides {
    /// Every disk, where the model's backs face the scene (an open sheet); none on a closed
    /// model, whose backs face its inside.
    #[default]
    Auto,
    /// None: one-sided disks, light passes a disk from behind.
    One,
    /// Every disk.
    Two,
}

/// One object. The keys that apply depend on `shape`; the loader rejects the others.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    pub shape: ShapeKind,
    /// Material name (default: "default").
    pub material: Option<String>,
    /// cornell_box: materials of the left (x = -1) and right (x = +1) walls.
    pub left_material: Option<String>,
    pub right_material: Option<String>,
    /// Procedural shapes: distance between neighbouring splats (world units).
    pub spacing: Option<f32>,
    /// sphere: radius (default 1).
    pub radius: Option<f32>,
    /// quad: [width, height] (default [1, 1]).
    pub size: Option<[f32; 2]>,
    /// model: file path, relative to the scene file.
    pub path: Option<String>,
    /// model: points or a mesh handed over in memory by name (`scene::Arrays`: the Python
    /// package's arrays), instead of `path`.
    pub array: Option<String>,
    /// model: uniformly rescale so the largest bounding-box side is this long.
    pub fit: Option<f32>,
    /// model: where the fitted bounding box sits (with `fit`).
    pub anchor: Option<Anchor>,
    /// model: use per-vertex colours as diffuse albedo when the file has them (default true).
    pub vertex_colors: Option<bool>,
    /// model: which disks get a back side (default "auto").
    pub sides: Option<Sides>,
    /// Applied as scale, then rotation (degrees about x, then y, then z), then translation.
    pub scale: Option<Scale>,
    pub rotate: Option<Vec3>,
    pub translate: Option<Vec3>,
}
