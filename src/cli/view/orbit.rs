//! The viewer's camera: an orbit about a target (yaw, pitch, distance) that the mouse turns,
//! pans and zooms, and WASD flies (moving target and eye together).

use glam::Vec3;

use crate::scene::file::CameraDesc;

#[derive(Clone, Debug)]
pub struct Orbit {
    pub target: Vec3,
    /// Radians about the up axis, and above the horizontal plane.
    pub yaw: f32,
    pub pitch: f32,
    pub distance: f32,
    /// The scene's camera for everything the orbit does not change (up, field of view).
    pub base: CameraDesc,
}

/// Radians per pixel of mouse drag.
const TURN: f32 = 0.005;
/// Zoom factor per wheel line.
const ZOOM: f32 = 0.9;
/// Pitch stays short of the poles, where yaw has no meaning.
const PITCH_LIMIT: f32 = 1.55;

impl Orbit {
    pub fn new(base: &CameraDesc) -> Orbit {
        let up = Vec3::from(base.up).normalize_or(Vec3::Y);
        let back = Vec3::from(base.eye) - Vec3::from(base.target);
        let distance = back.length().max(1e-6);
        let d = back / distance;
        let (right, fwd) = frame(up);
        Orbit {
            target: Vec3::from(base.target),
            yaw: d.dot(right).atan2(d.dot(fwd)),
            pitch: d.dot(up).clamp(-1.0, 1.0).asin(),
            distance,
            base: base.clone(),
        }
    }

    fn up(&self) -> Vec3 {
        Vec3::from(self.base.up).normalize_or(Vec3::Y)
    }

    /// Unit vector from the target to the eye.
    fn back(&self) -> Vec3 {
        let (right, fwd) = frame(self.up());
        let horizontal = self.yaw.sin() * right + self.yaw.cos() * fwd;
        self.pitch.cos() * horizontal + self.pitch.sin() * self.up()
    }

    pub fn camera(&self) -> CameraDesc {
        CameraDesc {
            eye: (self.target + self.distance * self.back()).to_array(),
            target: self.target.to_array(),
            ..self.base.clone()
        }
    }

    /// A drag of (dx, dy) pixels turns the eye about the target.
    pub fn turn(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * TURN;
        self.pitch = (self.pitch + dy * TURN).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Turns the eye about the up axis through the target by `degrees` (a scripted orbit;
    /// `scene::views::turned`'s turn of the scene's camera).
    pub fn spin(&mut self, degrees: f32) {
        self.yaw += degrees.to_radians();
    }

    /// A drag of (dx, dy) pixels slides the target across the view.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let back = self.back();
        let right = self.up().cross(back).normalize_or(Vec3::X);
        let up = back.cross(right);
        let scale = self.distance * TURN * 0.2;
        self.target += scale * (-dx * right + dy * up);
    }

    /// `lines` of the wheel: positive zooms in.
    pub fn zoom(&mut self, lines: f32) {
        self.distance = (self.distance * ZOOM.powf(lines)).max(1e-4);
    }

    /// Flies by (forward, right, up) in units of the orbit distance.
    pub fn fly(&mut self, forward: f32, right: f32, up: f32) {
        let back = self.back();
        let r = self.up().cross(back).normalize_or(Vec3::X);
        self.target += self.distance * (-forward * back + right * r + up * self.up());
    }
}

/// Two horizontal axes about `up`: (right, forward), a fixed frame yaw is measured in.
fn frame(up: Vec3) -> (Vec3, Vec3) {
    let fwd = if up.z.abs() < 0.9 { Vec3::Z } else { Vec3::X };
    let fwd = (fwd - up * fwd.dot(up)).normalize();
    (up.cross(fwd), fwd)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_orbit_reproduces_the_scene_camera() {
        let base = CameraDesc {
            eye: [0.3, 0.4, 3.9],
            target: [0.0, -0.1, 0.0],
            ..CameraDesc::default()
        };
        let cam = Orbit::new(&base).camera();
        let d = Vec3::from(cam.eye) - Vec3::from(base.eye);
        assert!(d.length() < 1e-5, "{:?}", cam.eye);
        assert_eq!(cam.target, base.target);
    }

    #[test]
    fn turning_keeps_the_distance_and_zoom_shortens_it() {
        let mut o = Orbit::new(&CameraDesc::default());
        let d = o.distance;
        o.turn(120.0, -40.0);
        let cam = o.camera();
        let r = (Vec3::from(cam.eye) - Vec3::from(cam.target)).length();
        assert!((r - d).abs() < 1e-4);
        o.zoom(2.0);
        assert!((o.distance - d * 0.81).abs() < 1e-4);
    }
}
