//! GPU stage timing with timestamp queries written at the start and end of compute passes.
//! Where the device has no timestamp support every stage reads "n/a" (`ms == None`).

use super::{read_buffer, GpuContext};
use crate::{Error, Result};

/// One timed stage; `ms` is `None` where timestamps are unavailable.
#[derive(Clone, Debug, PartialEq)]
pub struct StageTime {
    pub label: String,
    pub ms: Option<f64>,
}

impl std::fmt::Display for StageTime {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.ms {
            Some(ms) => write!(f, "{}: {ms:.3} ms", self.label),
            None => write!(f, "{}: n/a", self.label),
        }
    }
}

/// Collects timestamp pairs for up to `capacity` passes of one submission.
pub struct GpuTimer {
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    labels: Vec<String>,
    capacity: u32,
}

impl GpuTimer {
    pub fn new(ctx: &GpuContext, capacity: u32) -> Self {
        let queries = ctx.timestamps.then(|| {
            let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("stage timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: capacity * 2,
            });
            let resolve = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: u64::from(capacity) * 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolve)
        });
        Self {
            queries,
            labels: Vec::new(),
            capacity,
        }
    }

    /// Timestamp writes for a new compute pass named `label` (None without timestamp support).
    pub fn pass(&mut self, label: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        assert!(
            (self.labels.len() as u32) < self.capacity,
            "GpuTimer capacity {} exceeded",
            self.capacity
        );
        let index = self.labels.len() as u32;
        self.labels.push(label.to_owned());
        self.queries
            .as_ref()
            .map(|(set, _)| wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: Some(2 * index),
                end_of_pass_write_index: Some(2 * index + 1),
            })
    }

    /// Records the resolve of all written timestamps; call before `encoder.finish()`.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some((set, buffer)) = &self.queries {
            let used = self.labels.len() as u32 * 2;
            if used > 0 {
                encoder.resolve_query_set(set, 0..used, buffer, 0);
            }
        }
    }

    /// Reads the stage times after the submission completed, and clears the timer for reuse.
    pub fn read(&mut self, ctx: &GpuContext) -> Result<Vec<StageTime>> {
        let labels = std::mem::take(&mut self.labels);
        let Some((_, buffer)) = &self.queries else {
            return Ok(labels
                .into_iter()
                .map(|label| StageTime { label, ms: None })
                .collect());
        };
        let ticks: Vec<u64> = read_buffer(ctx, buffer, labels.len() * 2)?;
        let period_ns = f64::from(ctx.queue.get_timestamp_period());
        if period_ns <= 0.0 {
            return Err(Error::Gpu("device reports a zero timestamp period".into()));
        }
        Ok(labels
            .into_iter()
            .enumerate()
            .map(|(i, label)| {
                let (start, end) = (ticks[2 * i], ticks[2 * i + 1]);
                let ms = (end >= start).then(|| (end - start) as f64 * period_ns * 1e-6);
                StageTime { label, ms }
            })
            .collect())
    }
}

/// Adds up stages with the same label (e.g. several treelet rounds), in order of first
/// appearance; a label is "n/a" if any of its passes is.
pub fn aggregate_stages(stages: Vec<StageTime>) -> Vec<StageTime> {
    let mut out: Vec<StageTime> = Vec::new();
    for stage in stages {
        match out.iter_mut().find(|s| s.label == stage.label) {
            Some(total) => total.ms = total.ms.zip(stage.ms).map(|(a, b)| a + b),
            None => out.push(stage),
        }
    }
    out
}
