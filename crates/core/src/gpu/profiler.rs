//! GPU timestamps by `wgpu-profiler`: every compute pass is a timer query under its label;
//! durations are summed per label.
//!
//! Heavy passes are split into several dispatches (and submissions), so one label usually owns many
//! queries. Every encoder with timed passes goes through `Profiler::submit` (which resolves its
//! queries); `collect` ends the profiler's frame, waits for the results and sums them. The durations
//! are GPU execution times only: gaps between submissions are not counted. With `keep_trace` the raw
//! queries are also kept for a Chrome trace (`write_trace`, `render --trace`).

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;
use wgpu_profiler::{GpuProfiler, GpuProfilerSettings, GpuTimerQueryResult};

use super::GpuContext;

pub struct Profiler {
    inner: GpuProfiler,
    period: f32,
    /// Keep every query for `write_trace`.
    pub keep_trace: bool,
    trace: Vec<GpuTimerQueryResult>,
}

impl Profiler {
    pub fn new(ctx: &GpuContext) -> Self {
        let settings = GpuProfilerSettings {
            // Without TIMESTAMP_QUERY the passes run untimed and every label reads 0.
            enable_timer_queries: ctx.timestamps,
            enable_debug_groups: false,
            max_num_pending_frames: 2,
        };
        Profiler {
            inner: GpuProfiler::new(&ctx.device, settings).expect("valid profiler settings"),
            period: ctx.queue.get_timestamp_period(),
            keep_trace: false,
            trace: Vec::new(),
        }
    }

    /// Records `f` in one compute pass timed under `label`.
    pub fn compute_pass<R>(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        label: &str,
        f: impl FnOnce(&mut wgpu::ComputePass<'_>) -> R,
    ) -> R {
        let query = self.inner.begin_pass_query(label, enc);
        let r = {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: query.compute_pass_timestamp_writes(),
            });
            f(&mut pass)
        };
        self.inner.end_query(enc, query);
        r
    }

    /// Resolves the timer queries of `enc` and submits it.
    pub fn submit(&mut self, ctx: &GpuContext, mut enc: wgpu::CommandEncoder) {
        self.inner.resolve_queries(&mut enc);
        ctx.queue.submit([enc.finish()]);
    }

    /// Milliseconds per label of every pass submitted since the last call (summed), then resets.
    /// Must be called after the timed work has been submitted.
    pub fn collect(&mut self, ctx: &GpuContext) -> Result<BTreeMap<String, f64>> {
        self.inner
            .end_frame()
            .map_err(|e| anyhow::anyhow!("GPU profiler: {e}"))?;
        let results = loop {
            ctx.wait()?;
            if let Some(r) = self.inner.process_finished_frame(self.period) {
                break r;
            }
        };
        // Two 8-byte timestamps a query.
        super::traffic::timestamps(results.len() as u64 * 16);
        let mut out = BTreeMap::new();
        for q in &results {
            if let Some(t) = &q.time {
                *out.entry(q.label.clone()).or_insert(0.0) += (t.end - t.start) * 1e3;
            }
        }
        if self.keep_trace {
            self.trace.extend(results);
        }
        Ok(out)
    }

    /// Writes the queries kept since `keep_trace` was set as a Chrome trace (chrome://tracing,
    /// Perfetto) to `path`.
    pub fn write_trace(&self, path: &Path) -> Result<()> {
        // Written beside the target, then renamed: never a half-written file.
        crate::export::write_atomic_by_path(path, |tmp| {
            wgpu_profiler::chrometrace::write_chrometrace(tmp, &self.trace)
        })
    }
}
