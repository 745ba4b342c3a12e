//! Step 3: primary rays through pixel centres (or a sub-pixel offset of them, `with_jitter`) →
//! shading points (`shaders-wgsl/primary.wgsl`).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::dispatch::Kernel;
use super::dispatch::{Gpu, Run};
use super::pass::Pass;
use super::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gpu::GpuContext;
use crate::scene::Camera;

/// Bytes per shading point (`ShadingPoint` in `common/gbuffer.wgsl`).
pub const SP_BYTES: u64 = 64;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct CameraParams {
    pub eye: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub forward: [f32; 4],
    /// width, height, and the sub-pixel jitter of the rays (x, y as f32 bits; 0: pixel centres).
    pub size: [u32; 4],
}

impl CameraParams {
    pub fn new(cam: &Camera, width: u32, height: u32) -> Self {
        let t = (0.5 * cam.yfov).tan();
        let aspect = width as f32 / height as f32;
        let f = cam.forward();
        let up0 = cam.up();
        let right = f.cross(up0).normalize();
        let up = right.cross(f);
        CameraParams {
            eye: cam.eye().extend(0.0).into(),
            right: (right * t * aspect).extend(0.0).into(),
            up: (up * t).extend(0.0).into(),
            forward: f.extend(0.0).into(),
            size: [width, height, 0, 0],
        }
    }

    fn axis(a: [f32; 4]) -> Vec3 {
        Vec3::new(a[0], a[1], a[2])
    }

    /// The same view with every primary ray through (x + 0.5 + jx, y + 0.5 + jy) instead of the
    /// pixel centre, `jitter` in (-0.5, 0.5)² (anti-aliasing at rest).
    pub fn with_jitter(mut self, jitter: [f32; 2]) -> Self {
        self.size[2] = jitter[0].to_bits();
        self.size[3] = jitter[1].to_bits();
        self
    }

    /// The sub-pixel offset of the primary rays (`with_jitter`).
    pub fn jitter(&self) -> [f32; 2] {
        [f32::from_bits(self.size[2]), f32::from_bits(self.size[3])]
    }

    pub fn eye_point(&self) -> Vec3 {
        Self::axis(self.eye)
    }

    /// The (unnormalised) direction of the ray through image point (x, y), in pixels with pixel
    /// centres at + 0.5, as `primary.wgsl` makes it.
    pub fn ray(&self, x: f32, y: f32) -> Vec3 {
        let sx = 2.0 * x / self.size[0] as f32 - 1.0;
        let sy = 1.0 - 2.0 * y / self.size[1] as f32;
        Self::axis(self.forward) + sx * Self::axis(self.right) + sy * Self::axis(self.up)
    }

    /// `ray`'s inverse: where direction `d` from the eye lands in the image (pixels) and its depth
    /// along the view axis; `None` unless that depth is above `near` × |d| (behind the eye).
    pub fn project(&self, d: Vec3, near: f32) -> Option<(f32, f32, f32)> {
        let (r, u) = (Self::axis(self.right), Self::axis(self.up));
        let z = d.dot(Self::axis(self.forward));
        if z.is_nan() || z <= near * d.length() {
            return None;
        }
        let sx = d.dot(r) / (z * r.dot(r));
        let sy = d.dot(u) / (z * u.dot(u));
        Some((
            (sx + 1.0) * 0.5 * self.size[0] as f32,
            (1.0 - sy) * 0.5 * self.size[1] as f32,
            z,
        ))
    }
}

pub struct Primary {
    kernel: Kernel,
    camera: crate::gpu::persistent::Uniform<CameraParams>,
}

impl Primary {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let entries = [uniform_layout(1), storage_layout(2, false)];
        Primary {
            camera: crate::gpu::persistent::Uniform::new("camera"),
            kernel: Kernel::new(ctx, scene, "primary", &entries, &[]),
        }
    }

    /// Fills `gbuffer` (width × height shading points) for `camera`.
    pub fn record(&self, g: &mut Gpu, camera: &CameraParams, gbuffer: &wgpu::Buffer) {
        let ctx = g.ctx;
        let cam = self.camera.set(ctx, camera);
        let bg = self.kernel.bind_group(ctx, &[(1, cam), (2, gbuffer)]);
        let n = camera.size[0] * camera.size[1];
        let run = Run {
            label: Pass::Primary.name(),
            group: &bg,
            seed: 0,
        };
        self.kernel.run(g, run, n, 1 << 17, &mut |_, _| {});
    }
}

/// A shading point as `common/gbuffer.wgsl` lays it out (w components: valid flag, material).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    pub valid: bool,
    pub pos: Vec3,
    pub normal: Vec3,
    pub material: u32,
    pub albedo: Vec3,
    pub emission: Vec3,
}

impl ShadingPoint {
    /// Decodes one G-buffer record (4 × vec4).
    pub fn from_gpu(r: &[[f32; 4]]) -> Self {
        ShadingPoint {
            valid: r[0][3] > 0.0,
            pos: Vec3::new(r[0][0], r[0][1], r[0][2]),
            normal: Vec3::new(r[1][0], r[1][1], r[1][2]),
            material: r[1][3].to_bits(),
            albedo: Vec3::new(r[2][0], r[2][1], r[2][2]),
            emission: Vec3::new(r[3][0], r[3][1], r[3][2]),
        }
    }
}
