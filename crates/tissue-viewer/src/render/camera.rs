//! An orbit camera around the cube: drag to rotate, wheel to zoom.

use glam::{Mat4, Vec3};

/// Orbit camera looking at `target` from `distance` along the direction given by `yaw`/`pitch`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitCamera {
    /// Point looked at, metres.
    pub target: Vec3,
    /// Distance from the target, metres.
    pub distance: f32,
    /// Rotation about the z (up) axis, radians.
    pub yaw: f32,
    /// Elevation above the x-y plane, radians.
    pub pitch: f32,
    /// Vertical field of view, radians.
    pub fov_y: f32,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        Self { target: Vec3::splat(0.05), distance: 0.32, yaw: -0.9, pitch: 0.45, fov_y: 0.75 }
    }
}

impl OrbitCamera {
    /// Camera position, metres.
    pub fn eye(&self) -> Vec3 {
        let dir = Vec3::new(self.pitch.cos() * self.yaw.cos(), self.pitch.cos() * self.yaw.sin(), self.pitch.sin());
        self.target + self.distance * dir
    }

    /// World-to-clip matrix for an aspect ratio (width / height).
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let view = glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Z);
        // wgpu's clip space: z in [0, 1], y up (glam's "directx" convention).
        let proj = glam::camera::rh::proj::directx::perspective(self.fov_y, aspect.max(1e-3), 0.01, 10.0);
        proj * view
    }

    /// Rotates by a mouse drag (pixels).
    pub fn rotate(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.01;
        self.pitch = (self.pitch + dy * 0.01).clamp(-1.5, 1.5);
    }

    /// Zooms by wheel steps (positive: closer).
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * (1.0 - 0.1 * steps)).clamp(0.05, 3.0);
    }

    /// The ray through a point of the view, given in normalised device coordinates
    /// (`x, y` in [-1, 1], y up): origin and unit direction.
    pub fn ray(&self, ndc: [f32; 2], aspect: f32) -> (Vec3, Vec3) {
        let inv = self.view_proj(aspect).inverse();
        let near = inv.project_point3(Vec3::new(ndc[0], ndc[1], 0.0));
        let far = inv.project_point3(Vec3::new(ndc[0], ndc[1], 1.0));
        (near, (far - near).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_hits_the_target() {
        let c = OrbitCamera::default();
        let (o, d) = c.ray([0.0, 0.0], 1.5);
        let closest = o + d * (c.target - o).dot(d);
        assert!((closest - c.target).length() < 1e-4);
    }
}
