//! E57 terrestrial-scanner files (the `e57` crate): every point cloud of the file, each moved by
//! its pose into the file's common frame, with colours where the cloud has them (normalised by
//! the file's colour limits). Spherical scans are converted to Cartesian points; points with
//! no valid position (a return that did not come back) are left out and counted. Scans carry
//! no normals: the splats' normals come from their neighbours (`normals::pca_normals`).

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;

use super::Mesh;
use crate::error::{Error, Result};

/// Parses an E57 file's `bytes` (the reader keeps them: no copy of a large file).
pub fn parse(path: &Path, bytes: Vec<u8>) -> Result<Mesh> {
    let bad = |at: String, e: e57::Error| Error::parse(path, at, e.to_string());
    let mut reader =
        e57::E57Reader::new(Cursor::new(bytes)).map_err(|e| bad("header".into(), e))?;
    let clouds = reader.pointclouds();
    let mut mesh = Mesh::default();
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
                mesh.dropped += 1;
                continue;
            };
            let v = Vec3::new(x as f32, y as f32, z as f32);
            if !v.is_finite() {
                return Err(Error::parse(
                    path,
                    at(k),
                    format!("position {v} is not finite"),
                ));
            }
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
    if mesh.positions.is_empty() {
        return Err(Error::parse(
            path,
            "points",
            "the file holds no valid point",
        ));
    }
    if with_colors {
        mesh.colors = Some(colors);
    }
    Ok(mesh)
}
