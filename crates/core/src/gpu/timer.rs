//! Per-pass GPU timings from timestamp queries, summed per stage name.

use crate::error::Result;
use crate::gpu::GpuContext;

/// Timestamp queries of one submission; `collect` adds their durations to the stage totals.
pub struct Timer {
    set: Option<wgpu::QuerySet>,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    capacity: u32,
    labels: Vec<&'static str>,
    /// (stage, seconds) in order of first appearance.
    pub totals: Vec<(String, f64)>,
}

impl Timer {
    /// Room for `passes` timed passes per submission (wgpu allows 4096 queries a set).
    pub fn new(ctx: &GpuContext, passes: u32) -> Self {
        let capacity = (passes * 2).clamp(2, wgpu::QUERY_SET_MAX_QUERIES);
        let set = ctx.timestamps.then(|| {
            ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: capacity,
            })
        });
        let size = capacity as u64 * 8;
        let buffer = |label, usage| {
            crate::gpu::create_buffer(
                &ctx.device,
                &wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                },
            )
        };
        Timer {
            set,
            resolve: buffer(
                "timestamp resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            readback: buffer(
                "timestamp readback",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
            capacity,
            labels: Vec::new(),
            totals: Vec::new(),
        }
    }

    /// Timestamp writes for the next pass of stage `label`; `None` without timestamp support
    /// or when this submission's queries are used up (that pass goes untimed).
    pub fn pass(&mut self, label: &'static str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let first = self.labels.len() as u32 * 2;
        if self.set.is_none() || first + 2 > self.capacity {
            return None;
        }
        self.labels.push(label);
        Some(wgpu::RenderPassTimestampWrites {
            query_set: self.set.as_ref()?,
            beginning_of_pass_write_index: Some(first),
            end_of_pass_write_index: Some(first + 1),
        })
    }

    /// Timestamp writes for the next compute pass of stage `label` (see [`Timer::pass`]).
    pub fn compute_pass(
        &mut self,
        label: &'static str,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let first = self.labels.len() as u32 * 2;
        if self.set.is_none() || first + 2 > self.capacity {
            return None;
        }
        self.labels.push(label);
        Some(wgpu::ComputePassTimestampWrites {
            query_set: self.set.as_ref()?,
            beginning_of_pass_write_index: Some(first),
            end_of_pass_write_index: Some(first + 1),
        })
    }

    /// Records the copy of this submission's timestamps to the readback buffer.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let (Some(set), n) = (&self.set, self.labels.len() as u32 * 2) else {
            return;
        };
        if n == 0 {
            return;
        }
        encoder.resolve_query_set(set, 0..n, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, n as u64 * 8);
    }

    /// After the submission: adds its pass durations to the totals and frees the queries.
    pub fn collect(&mut self, ctx: &GpuContext) -> Result<()> {
        if self.labels.is_empty() {
            return Ok(());
        }
        let bytes = ctx.read_buffer(&self.readback)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        let period = ctx.queue.get_timestamp_period() as f64 * 1e-9;
        for (i, label) in self.labels.drain(..).enumerate() {
            let seconds = ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period;
            match self.totals.iter_mut().find(|(l, _)| l == label) {
                Some((_, t)) => *t += seconds,
                None => self.totals.push((label.to_string(), seconds)),
            }
        }
        Ok(())
    }
}

impl Timer {
    /// Forgets the totals and any unresolved queries, for the next frame.
    pub fn reset(&mut self) {
        self.labels.clear();
        self.totals.clear();
    }
}
