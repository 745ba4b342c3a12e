//! Step 3: primary rays through pixel centres → shading points (`shaders-wgsl/primary.wgsl`).

use bytemuck::{Pod, Zeroable};

use super::dispatch::Kernel;
use super::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gpu::{GpuContext, profiler::Profiler};
use crate::scene::Camera;

/// Bytes per shading point (`ShadingPoint` in `common/gbuffer.wgsl`).
pub const SP_BYTES: u64 = 64;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct CameraParams {
    pub eye: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub forward: [f32; 4],
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
}

pub struct Primary {
    kernel: Kernel,
}

impl Primary {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let entries = [uniform_layout(1), storage_layout(2, false)];
        Primary {
            kernel: Kernel::new(ctx, scene, "primary", &entries, &[]),
        }
    }

    /// Fills `gbuffer` (width × height shading points) for `camera`.
    pub fn record(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        camera: &CameraParams,
        gbuffer: &wgpu::Buffer,
    ) {
        let cam = ctx.uniform("camera", camera);
        let bg = self.kernel.bind_group(ctx, &[(1, &cam), (2, gbuffer)]);
        let n = camera.size[0] * camera.size[1];
        self.kernel.run(
            ctx,
            profiler,
            "primary",
            scene,
            &bg,
            n,
            1 << 17,
            0,
            &mut |_, _| {},
        );
    }
}
