//! GPU timestamp profiler: every compute pass gets a pair of timestamps; durations are summed per label.
//!
//! Heavy passes are split into several dispatches (and submissions), so one label usually owns many
//! pairs. The durations are GPU execution times only: gaps between submissions are not counted.

use std::collections::BTreeMap;

use super::GpuContext;

const CAPACITY: u32 = 4096;

pub struct Profiler {
    query_set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    labels: Vec<String>,
    period_ns: f64,
    overflowed: bool,
}

impl Profiler {
    pub fn new(ctx: &GpuContext) -> Self {
        let (query_set, resolve) = if ctx.timestamps {
            let qs = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: CAPACITY,
            });
            let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: CAPACITY as u64 * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (Some(qs), Some(buf))
        } else {
            (None, None)
        };
        Profiler {
            query_set,
            resolve,
            labels: Vec::new(),
            period_ns: ctx.queue.get_timestamp_period() as f64,
            overflowed: false,
        }
    }

    /// Timestamp writes for one compute pass under `label`, or `None` when timestamps are unsupported or
    /// the query set is full (the pass then runs untimed and `overflowed()` reports it).
    pub fn pass(&mut self, label: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let qs = self.query_set.as_ref()?;
        let i = self.labels.len() as u32 * 2;
        if i + 2 > CAPACITY {
            self.overflowed = true;
            return None;
        }
        self.labels.push(label.to_string());
        Some(wgpu::ComputePassTimestampWrites {
            query_set: qs,
            beginning_of_pass_write_index: Some(i),
            end_of_pass_write_index: Some(i + 1),
        })
    }

    pub fn overflowed(&self) -> bool {
        self.overflowed
    }

    /// Reads all timestamps written since the last call and returns milliseconds per label (summed),
    /// then resets. Must be called after the timed work has been submitted.
    pub fn collect(&mut self, ctx: &GpuContext) -> anyhow::Result<BTreeMap<String, f64>> {
        let mut out = BTreeMap::new();
        let n = self.labels.len() as u32 * 2;
        if let (Some(qs), Some(buf), true) = (&self.query_set, &self.resolve, n > 0) {
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            enc.resolve_query_set(qs, 0..n, buf, 0);
            ctx.queue.submit([enc.finish()]);
            let ticks: Vec<u64> = ctx.read_buffer(buf, n as usize)?;
            for (k, label) in self.labels.iter().enumerate() {
                let (a, b) = (ticks[2 * k], ticks[2 * k + 1]);
                let ms = b.saturating_sub(a) as f64 * self.period_ns * 1e-6;
                *out.entry(label.clone()).or_insert(0.0) += ms;
            }
        }
        self.labels.clear();
        self.overflowed = false;
        Ok(out)
    }
}
