//! E57 terrestrial-scanner files (the `e57` crate): every point cloud of the file, each moved by
//! its pose into the file's common frame, with colours where the cloud has them (normalised by
//! the file's colour limits). Spherical scans are converted to Cartesian points; points with
//! no valid position (a return that did not come back) are left out and counted, points whose
//! position is not finite or past f32's range skipped and counted (`Reading`). Scans carry
//! no normals: the splats' normals come from their neighbours (`normals::pca_normals`).

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;

use super::Mesh;
use super::reading::{LeftOut, Reading, point_f32};
use crate::error::{Error, Result};

/// The rule that leaves out a point with no position.
const NO_RETURN: &str = "points with no valid position (returns that did not come back)";

/// Parses an E57 file's `bytes` (the reader keeps them: no copy of a large file).
/// A panic of the E57 crate on a damaged file is an error (`reading::guarded`).
pub fn parse(path: &Path, bytes: Vec<u8>, reading: &Reading) -> Result<Mesh> {
    super::reading::guarded(path, || parse_unguarded(path, bytes, reading))
}

fn parse_unguarded(path: &Path, bytes: Vec<u8>, reading: &Reading) -> Result<Mesh> {
    let bad = |at: String, e: e57::Error| Error::parse(path, at, e.to_string());
    let mut reader =
        e57::E57Reader::new(Cursor::new(bytes)).map_err(|e| bad("header".into(), e))?;
    let clouds = reader.pointclouds();
    let announced = clouds.iter().map(|pc| pc.records).sum::<u64>();
    reading.check_points(path, "point clouds", announced)?;
    let mut mesh = Mesh::default();
    let mut left_out = LeftOut::default();
    let mut colors = Vec::new();
    let with_colors = !clouds.is_empty() && clouds.iter().all(|pc| pc.has_color());
    for (c, pc) in clouds.iter().enumerate() {
        let at = |k: usize| format!("point cloud #{} point #{}", c + 1, k + 1);
        let mut points = reader
            .pointcloud_simple(pc)
            .map_err(|e| bad(format!("point cloud #{}", c + 1), e))?;
        points.spherical_to_cartesian(true);
        points.apply_pose(true);
        points.normalize_color(true);
        for (k, point) in points.enumerate() {
            let p = point.map_err(|e| bad(at(k), e))?;
            let e57::CartesianCoordinate::Valid { x, y, z } = p.cartesian else {
                left_out.drop_by(NO_RETURN);
                continue;
            };
            let v: Vec3 = match point_f32("position", [x, y, z]) {
                Ok(v) => v,
                Err(m) => {
                    left_out.skip(reading, Error::parse(path, at(k), m))?;
                    continue;
                }
            };
            mesh.positions.push(v);
            if with_colors {
                let rgb = p.color.map_or([0.0; 3], |c| [c.red, c.green, c.blue]);
                colors.push(rgb.map(|x| {
                    if x.is_finite() {
                        x.clamp(0.0, 1.0)
                    } else {
                        0.0
                    }
                }));
            }
        }
    }
    mesh.left_out = left_out;
    if with_colors {
        mesh.colors = Some(colors);
    }
    Ok(mesh)
}
