//! View lists (`render --views FILE`): the cameras of an image sequence drawn from one bake. A
//! TOML file holds explicit cameras, an orbit, or both (the explicit ones first):
//!
//! ```toml
//! [[view]]                 # any [camera] key but `resolution`; the scene's camera fills the rest
//! eye = [0.5, 0.2, 3.5]
//! target = [0.0, 0.0, 0.0]
//!
//! [orbit]                  # the scene's camera turned about an axis through its target
//! frames = 36              # views, evenly over `degrees`
//! degrees = 360.0          # default 360
//! axis = [0.0, 1.0, 0.0]   # default: the camera's up
//!
//! [path]                   # keyframes, interpolated smoothly in time (`scene::path`)
//! fps = 30                 # frames a second, from the first key's time to the last's
//! [[path.key]]             # time in seconds; any [camera] key but `resolution`, as a view's
//! time = 0.0
//! eye = [0.0, 0.5, 4.0]
//! ```
//!
//! A `.json` file is a camera path as nerfstudio and splat editors write it (`scene::path`).

use std::path::Path;

use glam::{Quat, Vec3};
use serde::Deserialize;

use super::file::{CameraDesc, FovAxis};
use crate::error::{Error, Result};

/// Most views one file may make: past it a typo in `frames` is likelier than intent.
pub const MAX_VIEWS: u32 = 1_000_000;
/// The most an orbit turns, in degrees either way: 100 turns.
pub const MAX_ORBIT_DEGREES: f32 = 36_000.0;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ViewsFile {
    #[serde(default)]
    view: Vec<ViewDesc>,
    orbit: Option<Orbit>,
    path: Option<KeyPath>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyPath {
    fps: Option<f32>,
    key: Vec<KeyDesc>,
}

/// A key: its time (seconds) and a view's keys.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyDesc {
    time: f32,
    eye: Option<[f32; 3]>,
    target: Option<[f32; 3]>,
    up: Option<[f32; 3]>,
    fov: Option<f32>,
    fov_axis: Option<FovAxis>,
}

impl KeyDesc {
    fn view(&self) -> ViewDesc {
        ViewDesc {
            eye: self.eye,
            target: self.target,
            up: self.up,
            fov: self.fov,
            fov_axis: self.fov_axis,
        }
    }
}

/// The frames a second of a path that does not say.
pub const DEFAULT_FPS: f32 = 30.0;

/// A view list's cameras, and the frames a second its path or camera-path file gives.
#[derive(Clone, Debug, Default)]
pub struct ViewList {
    pub cameras: Vec<CameraDesc>,
    pub fps: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ViewDesc {
    eye: Option<[f32; 3]>,
    target: Option<[f32; 3]>,
    up: Option<[f32; 3]>,
    fov: Option<f32>,
    fov_axis: Option<FovAxis>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Orbit {
    frames: u32,
    #[serde(default = "full_turn")]
    degrees: f32,
    axis: Option<[f32; 3]>,
}

fn full_turn() -> f32 {
    360.0
}

/// The cameras `path` lists, in order, each completing `base` (the scene's camera).
pub fn load(path: &Path, base: &CameraDesc) -> Result<Vec<CameraDesc>> {
    Ok(load_list(path, base)?.cameras)
}

/// The cameras `path` lists and its frames a second: a TOML view list, or a camera-path
/// `.json` file.
pub fn load_list(path: &Path, base: &CameraDesc) -> Result<ViewList> {
    let bytes = crate::budget::Budget::current().read_file(path)?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| Error::parse(path, "text", format!("not UTF-8 text: {e}")))?;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        let (cameras, fps) = super::path::parse_camera_path(path, text, base)?;
        if cameras.is_empty() {
            return Err(Error::parse(path, "camera_path", "the path has no camera"));
        }
        return Ok(ViewList { cameras, fps });
    }
    parse_list(path, text, base)
}

pub fn parse(path: &Path, text: &str, base: &CameraDesc) -> Result<Vec<CameraDesc>> {
    Ok(parse_list(path, text, base)?.cameras)
}

impl ViewDesc {
    /// `base` with what this view gives in its place.
    fn camera(&self, base: &CameraDesc) -> CameraDesc {
        CameraDesc {
            eye: self.eye.unwrap_or(base.eye),
            target: self.target.unwrap_or(base.target),
            up: self.up.unwrap_or(base.up),
            fov: self.fov.unwrap_or(base.fov),
            fov_axis: self.fov_axis.unwrap_or(base.fov_axis),
            resolution: base.resolution,
            background: base.background,
        }
    }
}

/// A path's frames: its keys checked and sorted in time, sampled at its rate.
fn path_frames(path: &Path, p: &KeyPath, base: &CameraDesc) -> Result<Vec<CameraDesc>> {
    let bad = |m: String| Error::parse(path, "path", m);
    let fps = p.fps.unwrap_or(DEFAULT_FPS);
    super::path::check_fps(fps).map_err(bad)?;
    if p.key.is_empty() {
        return Err(bad("a path needs at least one [[path.key]]".into()));
    }
    let mut keys = Vec::with_capacity(p.key.len());
    // What no key interpolates (the field of view's axis) is the first key's.
    let first = p.key[0].view().camera(base);
    for (k, d) in p.key.iter().enumerate() {
        let cam = d.view().camera(base);
        super::validate_camera(&cam).map_err(|m| bad(format!("key #{}: {m}", k + 1)))?;
        if !d.time.is_finite() {
            return Err(bad(format!("key #{}: time must be finite", k + 1)));
        }
        keys.push(super::path::Key {
            time: d.time,
            eye: cam.eye.into(),
            target: cam.target.into(),
            up: cam.up.into(),
            fov: cam.fov,
        });
    }
    if let Some(k) = keys.windows(2).position(|w| w[1].time <= w[0].time) {
        return Err(bad(format!(
            "key #{}: times must increase, got {} after {}",
            k + 2,
            keys[k + 1].time,
            keys[k].time
        )));
    }
    let span = keys[keys.len() - 1].time - keys[0].time;
    if span * fps >= MAX_VIEWS as f32 {
        return Err(bad(format!(
            "{span} s at {fps} frames a second is more than {MAX_VIEWS} frames"
        )));
    }
    let frames = super::path::frames(&keys, fps, &first);
    for (k, cam) in frames.iter().enumerate() {
        super::validate_camera(cam).map_err(|m| bad(format!("frame {k}: {m}")))?;
    }
    Ok(frames)
}

/// A TOML view list's cameras: its views, then its orbit's, then its path's.
pub fn parse_list(path: &Path, text: &str, base: &CameraDesc) -> Result<ViewList> {
    let file: ViewsFile = toml::from_str(text).map_err(|e| super::toml_error(path, text, e))?;
    let mut views = Vec::new();
    for (k, v) in file.view.iter().enumerate() {
        let cam = v.camera(base);
        super::validate_camera(&cam)
            .map_err(|m| Error::parse(path, format!("view #{}", k + 1), m))?;
        views.push(cam);
    }
    if let Some(o) = &file.orbit {
        let bad = |m: String| Error::parse(path, "orbit", m);
        if !(1..=MAX_VIEWS).contains(&o.frames) {
            return Err(bad(format!(
                "frames must be within 1..={MAX_VIEWS}, got {}",
                o.frames
            )));
        }
        let axis = Vec3::from(o.axis.unwrap_or(base.up));
        // NaN too: it is within no range.
        if !(-MAX_ORBIT_DEGREES..=MAX_ORBIT_DEGREES).contains(&o.degrees) {
            return Err(bad(format!(
                "degrees = {} is out of range: an orbit turns at most ±{MAX_ORBIT_DEGREES} \
                 degrees (100 turns; 360 is one)",
                o.degrees
            )));
        }
        if !(axis.is_finite() && axis.length() > 1e-6) {
            return Err(bad(format!(
                "axis = {axis} must be a nonzero vector of finite numbers"
            )));
        }
        for k in 0..o.frames {
            let cam = turned(base, axis, o.degrees * k as f32 / o.frames as f32);
            super::validate_camera(&cam).map_err(|m| bad(format!("frame {k}: {m}")))?;
            views.push(cam);
        }
    }
    let mut fps = None;
    if let Some(p) = &file.path {
        views.extend(path_frames(path, p, base)?);
        fps = Some(p.fps.unwrap_or(DEFAULT_FPS));
    }
    if views.is_empty() {
        return Err(Error::parse(
            path,
            "views",
            "the file lists no view: add a [[view]], an [orbit] or a [path]",
        ));
    }
    Ok(ViewList {
        cameras: views,
        fps,
    })
}

/// `base` turned by `degrees` about `axis` (a nonzero vector) through its target.
pub fn turned(base: &CameraDesc, axis: Vec3, degrees: f32) -> CameraDesc {
    let (eye, target) = (Vec3::from(base.eye), Vec3::from(base.target));
    let q = Quat::from_axis_angle(axis.normalize(), degrees.to_radians());
    CameraDesc {
        eye: (target + q * (eye - target)).to_array(),
        up: (q * Vec3::from(base.up)).to_array(),
        ..base.clone()
    }
}

/// The file of view `k` of `count` in the sequence named by `output`: a run of `#` in its name
/// becomes `k` zero-padded to that width (`frame_####.png`), else `_k` (padded to the count's
/// digits) goes before the extension.
pub fn numbered(output: &Path, k: usize, count: usize) -> std::path::PathBuf {
    let name = output
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let digits = count.saturating_sub(1).max(1).to_string().len().max(4);
    let named = match name.find('#') {
        Some(start) => {
            let run = name[start..].chars().take_while(|&c| c == '#').count();
            format!("{}{k:0run$}{}", &name[..start], &name[start + run..])
        }
        None => {
            let stem = output
                .file_stem()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            match output.extension() {
                Some(ext) => format!("{stem}_{k:0digits$}.{}", ext.to_string_lossy()),
                None => format!("{stem}_{k:0digits$}"),
            }
        }
    };
    output.with_file_name(named)
}
