//! The pinhole camera of a scene: pixel ↔ ray, and world point → pixel.

use glam::{Vec2, Vec3};

use crate::scene::file::{CameraDesc, FovAxis};

#[derive(Clone, Copy, Debug)]
pub struct View {
    pub eye: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// tan of the half field of view along x and y.
    pub tan_half: Vec2,
    pub width: u32,
    pub height: u32,
}

impl View {
    /// The view of `desc` at `width` × `height` pixels (square pixels; `fov` spans `fov_axis`).
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> View {
        let eye = Vec3::from(desc.eye);
        let forward = (Vec3::from(desc.target) - eye).normalize();
        let right = forward.cross(Vec3::from(desc.up)).normalize();
        let up = right.cross(forward);
        let t = (desc.fov.to_radians() * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let tan_half = match desc.fov_axis {
            FovAxis::X => Vec2::new(t, t / aspect),
            FovAxis::Y => Vec2::new(t * aspect, t),
        };
        View {
            eye,
            forward,
            right,
            up,
            tan_half,
            width,
            height,
        }
    }

    /// The pixel (column, row from the top) a world point projects to, if it is in front of
    /// the camera and inside the image.
    pub fn project(&self, p: Vec3) -> Option<(u32, u32)> {
        let v = p - self.eye;
        let z = v.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let ndc = Vec2::new(v.dot(self.right), v.dot(self.up)) / (z * self.tan_half);
        let x = (ndc.x * 0.5 + 0.5) * self.width as f32;
        let y = (0.5 - ndc.y * 0.5) * self.height as f32;
        let inside =
            (0.0..self.width as f32).contains(&x) && (0.0..self.height as f32).contains(&y);
        inside.then_some((x as u32, y as u32))
    }
}
