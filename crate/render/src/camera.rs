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

    /// Fits a box to a view of this aspect (width / height), seen from the current yaw and
    /// pitch: target its centre, and the least distance at which all eight corners lie in
    /// both the vertical and the horizontal field of view (with a 6 % margin). Unlike
    /// [`OrbitCamera::frame`], a wide row of figures uses the view's width, so each figure is
    /// drawn as large as the view allows.
    pub fn fit(&mut self, lo: Vec3, hi: Vec3, aspect: f32) {
        let c = (lo + hi) * 0.5;
        self.target = c;
        let forward = (self.eye() - self.target).normalize_or(Vec3::Z);
        let right = Vec3::Y.cross(forward).normalize_or(Vec3::X);
        let up = forward.cross(right);
        let tan_v = (self.fov_y * 0.5).tan();
        let tan_h = tan_v * aspect.max(1e-3);
        let mut d: f32 = 0.0;
        for k in 0..8 {
            let corner = Vec3::new(if k & 1 == 0 { lo.x } else { hi.x }, if k & 2 == 0 { lo.y } else { hi.y }, if k & 4 == 0 { lo.z } else { hi.z });
            let v = corner - c;
            // Depth towards the eye: a corner nearer the camera needs more room.
            let z = v.dot(forward);
            d = d.max(z + v.dot(right).abs() / tan_h).max(z + v.dot(up).abs() / tan_v);
        }
        self.distance = (d * 1.06).clamp(0.5, 5_000.0);
    }

    /// Frames a box: target its centre, distance so it fits.
    pub fn frame(&mut self, lo: Vec3, hi: Vec3) {
        let c = (lo + hi) * 0.5;
        let r = ((hi - lo).length() * 0.5).max(0.3);
        self.target = c;
        self.distance = (r / (self.fov_y * 0.5).tan() * 1.15).clamp(0.5, 5_000.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ndc(cam: &OrbitCamera, aspect: f32, p: Vec3) -> Vec3 {
        let c = cam.view_proj(aspect) * p.extend(1.0);
        c.truncate() / c.w
    }

    #[test]
    fn fit_fills_the_view_in_the_tighter_direction() {
        // A row of six figures (7.8 m by 1.8 m) in a wide view, and a lone figure in a tall one.
        for (lo, hi, aspect) in [
            (Vec3::new(-3.9, 0.0, -0.3), Vec3::new(3.9, 1.8, 0.3), 1.5),
            (Vec3::new(-0.4, 0.0, -0.3), Vec3::new(0.4, 1.8, 0.3), 0.6),
            (Vec3::new(-0.4, 0.0, -0.3), Vec3::new(0.4, 1.8, 0.3), 2.0),
        ] {
            let mut cam = OrbitCamera::default();
            cam.fit(lo, hi, aspect);
            let mut most: f32 = 0.0;
            for k in 0..8 {
                let p = Vec3::new(if k & 1 == 0 { lo.x } else { hi.x }, if k & 2 == 0 { lo.y } else { hi.y }, if k & 4 == 0 { lo.z } else { hi.z });
                let q = ndc(&cam, aspect, p);
                assert!(q.x.abs() <= 1.0 && q.y.abs() <= 1.0, "corner {p} outside the view: {q}");
                most = most.max(q.x.abs()).max(q.y.abs());
            }
            // Tight: some corner reaches near the edge (the 6 % margin and perspective aside).
            assert!(most > 0.85, "box fills only {most} of the view ({lo} .. {hi}, aspect {aspect})");
            // Tighter than the old sphere framing.
            let mut old = OrbitCamera::default();
            old.frame(lo, hi);
            assert!(cam.distance < old.distance, "fit {} vs frame {}", cam.distance, old.distance);
        }
    }
}
