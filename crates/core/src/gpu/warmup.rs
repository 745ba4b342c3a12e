//! GPU warm-up before timing (`shaders-wgsl/warmup.wgsl`). A GPU that has idled, even for the CPU
//! work between two frames, runs the next work at a low clock: on an H100 the same direct pass
//! measured 1.0 ms or 5.7 ms depending on it, and `--camera-path` frames read 37–49 ms cold against
//! 19.6–23.9 ms warm. Every timer (`render`, `bench`, `bench --camera-path`, `--target-ms`) first
//! keeps the GPU busy with this kernel for `--warmup-ms` of GPU work (default 200), in submissions
//! of a few milliseconds each. It reads and writes no renderer state, so the images do not change
//! and a temporal frame's past stays its predecessor's.

use std::cell::Cell;
use std::time::{Duration, Instant};

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use super::GpuContext;

/// Trips of the kernel's loop per invocation: far below lavapipe's 65,535 loop limit.
const ITERATIONS: u32 = 2048;
/// A submission is grown until it takes this long (and no longer than the device limit allows).
const SUBMISSION: Duration = Duration::from_millis(4);
const WORKGROUP: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct WarmupParams {
    iterations: u32,
    _pad: [u32; 3],
}

/// The warm-up kernel, built once per device.
pub struct Warmup {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    #[cfg_attr(
        not(test),
        allow(dead_code, reason = "read back by the test; the bind group holds it")
    )]
    sink: wgpu::Buffer,
    /// Workgroups per submission, grown until one submission takes `SUBMISSION`.
    workgroups: Cell<u32>,
}

impl Warmup {
    pub fn new(ctx: &GpuContext) -> Self {
        let module = super::shader::module(&ctx.device, "warmup");
        let pipeline = ctx
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("warmup"),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            });
        let params = ctx.uniform(
            "warmup params",
            &WarmupParams {
                iterations: ITERATIONS,
                _pad: [0; 3],
            },
        );
        let sink = ctx.storage("warmup sink", WORKGROUP as u64 * 4);
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("warmup"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: sink.as_entire_binding(),
                },
            ],
        });
        Warmup {
            pipeline,
            group,
            sink,
            workgroups: Cell::new(16),
        }
    }

    /// One submission of `self.workgroups` workgroups, waited for; its wall time.
    fn submit(&self, ctx: &GpuContext) -> Result<Duration> {
        let t0 = Instant::now();
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("warmup"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.group, &[]);
            pass.dispatch_workgroups(self.workgroups.get(), 1, 1);
        }
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        Ok(t0.elapsed())
    }

    /// Keeps the GPU busy for at least `ms` milliseconds (0: nothing); returns the milliseconds
    /// spent. Each submission is waited for, so the time is the GPU's (plus a submission's overhead,
    /// small once a submission takes `SUBMISSION`).
    pub fn run(&self, ctx: &GpuContext, ms: f64) -> Result<f64> {
        if ms <= 0.0 {
            return Ok(0.0);
        }
        let max_groups = ctx.device.limits().max_compute_workgroups_per_dimension;
        let budget = Duration::from_secs_f64(ms / 1000.0);
        let t0 = Instant::now();
        while t0.elapsed() < budget {
            let took = self.submit(ctx)?;
            self.workgroups
                .set(grown(self.workgroups.get(), took, max_groups));
        }
        Ok(t0.elapsed().as_secs_f64() * 1000.0)
    }
}

/// The next submission's workgroups after `n` took `took`: doubled while a submission is shorter
/// than `SUBMISSION`, at most `max`.
fn grown(n: u32, took: Duration, max: u32) -> u32 {
    if took < SUBMISSION && n < max {
        n.saturating_mul(2).min(max)
    } else {
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The warm-up spends what it is asked (and not much more) and leaves the device usable.
    #[test]
    fn warm_up_takes_its_time_and_nothing_else() {
        let Ok(ctx) = GpuContext::new_headless() else {
            panic!("no adapter: install mesa-vulkan-drivers");
        };
        assert_eq!(ctx.warm_up(0.0).unwrap(), 0.0);
        let spent = ctx.warm_up(120.0).unwrap();
        let w = ctx.warmup.get().unwrap();
        assert!(spent >= 120.0, "spent {spent} ms");
        // One submission past the budget at most: grown to ~4 ms, a loaded 2-core VM may stretch
        // it several times.
        assert!(spent < 120.0 + 400.0, "spent {spent} ms");
        // The kernel ran: every lane of a workgroup stored its (positive, finite) sum.
        let sink: Vec<f32> = ctx.read_buffer(&w.sink, WORKGROUP as usize).unwrap();
        assert!(sink.iter().all(|&v| v.is_finite() && v > 0.0), "{sink:?}");
    }

    /// The growth rule by hand, without the clock (whether a loaded machine's submissions grow
    /// depends on the load: asserting it in the test above failed beside a cargo-mutants run).
    #[test]
    fn submissions_double_while_short_up_to_the_limit() {
        let short = SUBMISSION / 2;
        assert_eq!(grown(16, short, 65535), 32);
        assert_eq!(grown(16, SUBMISSION, 65535), 16);
        assert_eq!(grown(16, SUBMISSION * 3, 65535), 16);
        assert_eq!(grown(40000, short, 65535), 65535);
        assert_eq!(grown(65535, short, 65535), 65535);
        assert_eq!(grown(u32::MAX / 2 + 1, short, u32::MAX), u32::MAX);
    }
}
