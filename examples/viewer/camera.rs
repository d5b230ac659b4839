//! The viewer's camera: orbit around a target or fly through the scene, either depth convention.

use fieldkit::view::View;
use glam::{Mat4, Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// Where the camera is and how it projects. Orbit: drag to turn around `target`, scroll to move
/// in and out. Fly: drag to look, W/A/S/D/Q/E to move the eye (and the target with it).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// The point the camera looks at (orbit centre).
    pub target: Vec3,
    /// Radians around +y, 0 looking along −z.
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    /// Eye to target, world units.
    pub distance: f32,
    /// Vertical field of view, radians.
    pub fov: f32,
    /// Near and far planes, world units.
    pub near: f32,
    /// Far plane.
    pub far: f32,
    /// Fly instead of orbit.
    pub fly: bool,
    /// Reversed Z (near at depth 1, far at 0).
    pub reversed_z: bool,
}

impl Camera {
    /// Orbiting `target` from `distance` away.
    pub fn orbit(target: Vec3, yaw: f32, pitch: f32, distance: f32, far: f32) -> Self {
        Self {
            target,
            yaw,
            pitch,
            distance,
            fov: 0.8,
            near: 0.05,
            far,
            fly: false,
            reversed_z: false,
        }
    }

    /// Unit vector from the target toward the eye.
    fn back(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(sy * cp, sp, cy * cp)
    }

    /// The eye position.
    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    /// Depth the targets are cleared to: the far plane.
    pub fn clear_depth(&self) -> f32 {
        if self.reversed_z { 0.0 } else { 1.0 }
    }

    /// The projection alone (depth 0..1, or 1..0 reversed).
    pub fn proj(&self, aspect: f32) -> Mat4 {
        let (n, f) = if self.reversed_z {
            (self.far, self.near)
        } else {
            (self.near, self.far)
        };
        glam::camera::rh::proj::directx::perspective(self.fov, aspect, n, f)
    }

    /// World → view.
    pub fn view_matrix(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y)
    }

    /// The fieldkit view for a `size` target.
    pub fn view(&self, size: [u32; 2]) -> View {
        let aspect = size[0] as f32 / size[1].max(1) as f32;
        View {
            view_proj: self.proj(aspect) * self.view_matrix(),
            viewport: size,
            reversed_z: self.reversed_z,
            origin: [0, 0],
        }
    }

    /// The ocean's camera (f64 world, the same projection).
    pub fn ocean(&self, size: [u32; 2]) -> fieldkit::ocean::OceanCamera {
        let aspect = size[0] as f32 / size[1].max(1) as f32;
        fieldkit::ocean::OceanCamera::look_at(
            self.eye().as_dvec3(),
            self.target.as_dvec3(),
            self.proj(aspect),
        )
    }

    /// Turn by a mouse drag of `delta` pixels.
    pub fn drag(&mut self, delta: Vec2) {
        let eye = self.eye();
        self.yaw -= delta.x * 0.008;
        self.pitch = (self.pitch + delta.y * 0.008).clamp(-1.55, 1.55);
        if self.fly {
            // Look around the eye: keep it where it is.
            self.target = eye - self.back() * self.distance;
        }
    }

    /// Scroll: orbit in or out (fly: nothing).
    pub fn zoom(&mut self, scroll: f32) {
        if !self.fly {
            self.distance = (self.distance * (-scroll * 0.002).exp()).clamp(0.01, self.far * 0.5);
        }
    }

    /// Fly: move by `local` (x right, y up, z forward) world units.
    pub fn fly_by(&mut self, local: Vec3) {
        let forward = -self.back();
        let right = forward.cross(Vec3::Y).normalize_or_zero();
        self.target += right * local.x + Vec3::Y * local.y + forward * local.z;
    }
}
