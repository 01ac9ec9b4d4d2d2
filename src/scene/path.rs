//! Camera paths of a sequence: keyframes interpolated smoothly in time (a view list's `[path]`),
//! and the camera-path JSON files that nerfstudio and splat editors write (one camera a frame).

use std::path::Path;

use glam::{Mat4, Vec3};
use serde::Deserialize;

use super::file::{CameraDesc, FovAxis};
use crate::error::{Error, Result};

/// The most frames a second a path may ask for.
pub const MAX_FPS: f32 = 1000.0;

/// One keyframe: where the camera is at `time` (seconds); what it leaves out stays the
/// camera's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    pub time: f32,
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub fov: f32,
}

/// A C1 curve through `values` at `times` (increasing): cubic Hermite segments whose tangents
/// are the Catmull–Rom ones for uneven times, (v[i+1] − v[i−1]) / (t[i+1] − t[i−1]), one-sided
/// at the ends. It passes through every key, and its velocity is continuous across each: no
/// kink where a segment meets the next.
fn hermite<T>(times: &[f32], values: &[T], t: f32) -> T
where
    T: Copy
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<f32, Output = T>,
{
    let n = values.len();
    if n == 1 || t <= times[0] {
        return values[0];
    }
    if t >= times[n - 1] {
        return values[n - 1];
    }
    let i = times.partition_point(|&k| k <= t).clamp(1, n - 1) - 1;
    let tangent = |j: usize| {
        let (a, b) = (j.saturating_sub(1), (j + 1).min(n - 1));
        (values[b] - values[a]) * (1.0 / (times[b] - times[a]))
    };
    let h = times[i + 1] - times[i];
    let s = (t - times[i]) / h;
    let (s2, s3) = (s * s, s * s * s);
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    values[i] * h00 + tangent(i) * (h10 * h) + values[i + 1] * h01 + tangent(i + 1) * (h11 * h)
}

/// The camera at time `t` on the path through `keys` (sorted by time, at least one).
pub fn at(keys: &[Key], t: f32, base: &CameraDesc) -> CameraDesc {
    let times: Vec<f32> = keys.iter().map(|k| k.time).collect();
    let of = |f: fn(&Key) -> Vec3| keys.iter().map(f).collect::<Vec<Vec3>>();
    let fovs: Vec<f32> = keys.iter().map(|k| k.fov).collect();
    let up = hermite(&times, &of(|k| k.up), t);
    CameraDesc {
        eye: hermite(&times, &of(|k| k.eye), t).to_array(),
        target: hermite(&times, &of(|k| k.target), t).to_array(),
        up: up.normalize_or(Vec3::from(base.up)).to_array(),
        fov: hermite(&times, &fovs, t).clamp(1e-3, 179.0),
        ..base.clone()
    }
}

/// The frames of a path at `fps`: one at each 1/fps from its first key's time to its last's
/// (both in).
pub fn frames(keys: &[Key], fps: f32, base: &CameraDesc) -> Vec<CameraDesc> {
    let (first, last) = (keys[0].time, keys[keys.len() - 1].time);
    // A hair of slack: a last key at a whole number of frames is a frame.
    let count = ((last - first) * fps + 1e-3).floor() as usize + 1;
    (0..count)
        .map(|k| at(keys, first + k as f32 / fps, base))
        .collect()
}

/// The camera-path JSON of nerfstudio (`ns-render camera-path`) and the splat editors that
/// write it: per frame a camera-to-world matrix (OpenGL axes: the camera looks along its −z,
/// up its +y) and a vertical field of view.
#[derive(Debug, Deserialize)]
struct CameraPathFile {
    camera_path: Vec<PathCamera>,
    fps: Option<f32>,
}

#[derive(Debug, Deserialize)]
struct PathCamera {
    camera_to_world: Matrix,
    fov: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Matrix {
    Flat(Vec<f32>),
    Rows(Vec<Vec<f32>>),
}

impl Matrix {
    /// The matrix's 16 numbers, row by row.
    fn rows(&self) -> Option<[f32; 16]> {
        let flat: Vec<f32> = match self {
            Matrix::Flat(v) => v.clone(),
            Matrix::Rows(r) => r.iter().flatten().copied().collect(),
        };
        match flat.len() {
            16 => flat.try_into().ok(),
            // Three rows: the last, (0, 0, 0, 1), left out.
            12 => {
                let mut m = [0.0; 16];
                m[..12].copy_from_slice(&flat);
                m[15] = 1.0;
                Some(m)
            }
            _ => None,
        }
    }
}

/// The cameras of a camera-path JSON file, and its frames a second.
pub fn parse_camera_path(
    path: &Path,
    text: &str,
    base: &CameraDesc,
) -> Result<(Vec<CameraDesc>, Option<f32>)> {
    let file: CameraPathFile = serde_json::from_str(text)
        .map_err(|e| Error::at_line(path, e.line(), format!("not a camera path: {e}")))?;
    let mut cameras = Vec::with_capacity(file.camera_path.len());
    for (k, c) in file.camera_path.iter().enumerate() {
        let bad = |m: String| Error::parse(path, format!("camera_path[{k}]"), m);
        let m = c
            .camera_to_world
            .rows()
            .ok_or_else(|| bad("camera_to_world must be a 4 × 4 (or 3 × 4) matrix".into()))?;
        let world = Mat4::from_cols_array(&m).transpose();
        let eye = world.w_axis.truncate();
        let forward = -world.z_axis.truncate();
        let up = world.y_axis.truncate();
        let cam = CameraDesc {
            eye: eye.to_array(),
            target: (eye + forward.normalize_or_zero()).to_array(),
            up: up.to_array(),
            fov: c.fov.unwrap_or(base.fov),
            fov_axis: if c.fov.is_some() {
                FovAxis::Y
            } else {
                base.fov_axis
            },
            ..base.clone()
        };
        super::validate_camera(&cam).map_err(bad)?;
        cameras.push(cam);
    }
    if let Some(fps) = file.fps {
        check_fps(fps).map_err(|m| Error::parse(path, "fps", m))?;
    }
    Ok((cameras, file.fps))
}

/// A frame rate a sequence may have.
pub fn check_fps(fps: f32) -> std::result::Result<(), String> {
    if fps > 0.0 && fps <= MAX_FPS {
        Ok(())
    } else {
        Err(format!("fps must be in (0, {MAX_FPS}], got {fps}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(time: f32, eye: [f32; 3]) -> Key {
        Key {
            time,
            eye: Vec3::from(eye),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov: 40.0,
        }
    }

    #[test]
    fn the_curve_passes_through_every_key_without_a_kink() {
        let keys = [
            key(0.0, [0.0, 0.0, 4.0]),
            key(1.0, [4.0, 1.0, 0.0]),
            key(3.0, [0.0, 0.0, -4.0]),
            key(3.5, [-4.0, 2.0, 0.0]),
        ];
        let base = CameraDesc::default();
        for k in &keys {
            let eye = Vec3::from(at(&keys, k.time, &base).eye);
            assert!((eye - k.eye).length() < 1e-5, "{eye} at key {}", k.time);
        }
        // The velocity just before and just after each inner key agrees.
        let eye = |t: f32| Vec3::from(at(&keys, t, &base).eye);
        let d = 1e-3;
        for k in &keys[1..3] {
            let before = (eye(k.time) - eye(k.time - d)) / d;
            let after = (eye(k.time + d) - eye(k.time)) / d;
            assert!(
                (before - after).length() < 0.02 * before.length().max(1.0),
                "{before} {after}"
            );
        }
    }

    #[test]
    fn frames_cover_the_path_at_the_rate() {
        let keys = [key(0.0, [0.0, 0.0, 4.0]), key(2.0, [4.0, 0.0, 0.0])];
        let frames = frames(&keys, 24.0, &CameraDesc::default());
        assert_eq!(frames.len(), 49);
        assert_eq!(frames[48].eye, [4.0, 0.0, 0.0]);
    }

    #[test]
    fn a_nerfstudio_camera_looks_along_its_minus_z() {
        // A camera at (1, 2, 3) turned 90° about y: its −z is the world's −x.
        let text = r#"{"fps": 24, "camera_path": [{"camera_to_world":
            [0, 0, 1, 1,  0, 1, 0, 2,  -1, 0, 0, 3,  0, 0, 0, 1], "fov": 50, "aspect": 1.5}]}"#;
        let base = CameraDesc::default();
        let (cams, fps) = parse_camera_path(Path::new("p.json"), text, &base).unwrap();
        assert_eq!(fps, Some(24.0));
        assert_eq!(cams[0].eye, [1.0, 2.0, 3.0]);
        assert_eq!(cams[0].target, [0.0, 2.0, 3.0]);
        assert_eq!(cams[0].up, [0.0, 1.0, 0.0]);
        assert_eq!((cams[0].fov, cams[0].fov_axis), (50.0, FovAxis::Y));
    }
}
