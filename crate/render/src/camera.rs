//! Orbit camera (paper 002's free viewpoint): yaw and pitch around a target, wheel zoom.

use glam::{Mat4, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    pub target: Vec3,
    /// Radians about +Y; 0 looks at the figure's front (from +Z).
    pub yaw: f32,
    /// Radians above the ground plane, clamped to (-1.5, 1.5).
    pub pitch: f32,
    /// Metres from the target.
    pub distance: f32,
    /// Vertical field of view, radians.
    pub fov_y: f32,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        OrbitCamera { target: Vec3::new(0.0, 0.9, 0.0), yaw: 0.5, pitch: 0.25, distance: 4.2, fov_y: 0.8 }
    }
}

impl OrbitCamera {
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + Vec3::new(sy * cp, sp, cy * cp) * self.distance
    }

    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let view = glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y);
        // wgpu: NDC depth in [0, 1], Y up (the "directx" convention).
        // Near and far follow the distance, so a 3-m dancer and a 300-unit fox both fit.
        let near = (self.distance * 0.01).max(0.01);
        let proj = glam::camera::rh::proj::directx::perspective(self.fov_y, aspect.max(1e-3), near, near * 20_000.0);
        proj * view
    }

    /// Drag by a fraction of the view (dx, dy in view widths/heights).
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * std::f32::consts::PI;
        self.pitch = (self.pitch + dy * 2.0).clamp(-1.4, 1.45);
    }

    /// Wheel: positive zooms out.
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * (1.0 + 0.1 * steps)).clamp(0.2, 5_000.0);
    }

    /// Frames a box: target its centre, distance so it fits.
    pub fn frame(&mut self, lo: Vec3, hi: Vec3) {
        let c = (lo + hi) * 0.5;
        let r = ((hi - lo).length() * 0.5).max(0.3);
        self.target = c;
        self.distance = (r / (self.fov_y * 0.5).tan() * 1.15).clamp(0.5, 5_000.0);
    }
}
