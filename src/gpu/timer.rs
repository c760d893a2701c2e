//! GPU stage timing with timestamp queries written at the start and end of compute passes, and
//! the number of dispatches each timed pass recorded (what a real GPU's fixed per-dispatch cost
//! multiplies). Where the device has no timestamp support every stage reads "n/a" (`ms == None`).
//! On a context that profiles dispatches (`GpuOptions::profile_dispatches`), every dispatch gets a
//! timed pass of its own, labelled with its stage and kernel (`Pass` opens them).

use super::{read_buffer, GpuContext};
use crate::{Error, Result};

/// One timed stage; `ms` is `None` where timestamps are unavailable. `dispatches`: compute
/// dispatches the stage recorded (0 for work on the CPU). `kernel`: the kernel of a dispatch timed
/// on its own (profiling dispatches), else None.
#[derive(Clone, Debug, PartialEq)]
pub struct StageTime {
    pub label: String,
    pub ms: Option<f64>,
    pub dispatches: u32,
    pub kernel: Option<&'static str>,
}

impl StageTime {
    /// A stage that ran on the CPU for `ms`.
    pub fn cpu(label: impl Into<String>, ms: f64) -> Self {
        Self {
            label: label.into(),
            ms: Some(ms),
            dispatches: 0,
            kernel: None,
        }
    }
}

/// A timed pass of a recording: its label, how many dispatches it holds, and the kernel of a
/// dispatch timed on its own.
#[derive(Clone, Debug, PartialEq)]
pub struct TimedPass {
    pub label: String,
    pub dispatches: u32,
    pub kernel: Option<&'static str>,
}

impl std::fmt::Display for StageTime {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.ms {
            Some(ms) => write!(f, "{}: {ms:.3} ms", self.label),
            None => write!(f, "{}: n/a", self.label),
        }
    }
}

/// Timed passes a timer that profiles dispatches holds (two queries each, as many as a query set
/// holds): more dispatches than any timed recording records.
const PROFILE_CAPACITY: u32 = wgpu::QUERY_SET_MAX_QUERIES / 2;

/// Collects timestamp pairs for up to `capacity` passes of one submission.
pub struct GpuTimer {
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    passes: Vec<TimedPass>,
    capacity: u32,
    /// Every dispatch gets a timed pass of its own (`ctx.profile_dispatches`).
    per_dispatch: bool,
}

impl GpuTimer {
    /// A timer for up to `capacity` passes (for `PROFILE_CAPACITY` dispatches when the context
    /// profiles dispatches).
    pub fn new(ctx: &GpuContext, capacity: u32) -> Self {
        let per_dispatch = ctx.profile_dispatches && ctx.timestamps;
        let capacity = if per_dispatch {
            capacity.max(PROFILE_CAPACITY)
        } else {
            capacity
        };
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
            passes: Vec::new(),
            capacity,
            per_dispatch,
        }
    }

    /// Whether every dispatch gets a timed pass of its own.
    pub(crate) fn per_dispatch(&self) -> bool {
        self.per_dispatch
    }

    /// Timestamp writes for a new compute pass named `label`, holding one dispatch of `kernel`
    /// when the timer profiles dispatches (None without timestamp support).
    pub fn pass(
        &mut self,
        label: &str,
        kernel: Option<&'static str>,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        assert!(
            (self.passes.len() as u32) < self.capacity,
            "GpuTimer capacity {} exceeded",
            self.capacity
        );
        let index = self.passes.len() as u32;
        self.passes.push(TimedPass {
            label: label.to_owned(),
            dispatches: 0,
            kernel,
        });
        self.queries
            .as_ref()
            .map(|(set, _)| wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: Some(2 * index),
                end_of_pass_write_index: Some(2 * index + 1),
            })
    }

    /// The dispatch count of the pass opened last (`Pass` counts into it).
    pub(crate) fn last_dispatches(&mut self) -> Option<&mut u32> {
        self.passes.last_mut().map(|p| &mut p.dispatches)
    }

    /// Records the resolve of all written timestamps; call before `encoder.finish()`.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some((set, buffer)) = &self.queries {
            let used = self.passes.len() as u32 * 2;
            if used > 0 {
                encoder.resolve_query_set(set, 0..used, buffer, 0);
            }
        }
    }

    /// The buffer of the resolved timestamps (two u64 ticks per pass, after `resolve`), for a
    /// read that does not wait; None without timestamp support.
    pub fn resolved_buffer(&self) -> Option<&wgpu::Buffer> {
        self.queries.as_ref().map(|(_, buffer)| buffer)
    }

    /// The passes recorded so far, in order; clears the timer for reuse.
    pub fn take_passes(&mut self) -> Vec<TimedPass> {
        std::mem::take(&mut self.passes)
    }

    /// The stage times of `passes` from their resolved `ticks` (None-valued without
    /// timestamps: pass an empty `ticks`).
    pub fn stage_times(ctx: &GpuContext, passes: Vec<TimedPass>, ticks: &[u64]) -> Vec<StageTime> {
        let period_ns = f64::from(ctx.queue.get_timestamp_period());
        passes
            .into_iter()
            .enumerate()
            .map(
                |(
                    i,
                    TimedPass {
                        label,
                        dispatches,
                        kernel,
                    },
                )| {
                    let ms = match ticks.get(2 * i..2 * i + 2) {
                        Some(&[start, end]) if end >= start && period_ns > 0.0 => {
                            Some((end - start) as f64 * period_ns * 1e-6)
                        }
                        _ => None,
                    };
                    StageTime {
                        label,
                        ms,
                        dispatches,
                        kernel,
                    }
                },
            )
            .collect()
    }

    /// Reads the stage times after the submission completed (blocks), and clears the timer for
    /// reuse.
    pub fn read(&mut self, ctx: &GpuContext) -> Result<Vec<StageTime>> {
        let passes = self.take_passes();
        let ticks: Vec<u64> = match &self.queries {
            Some((_, buffer)) => read_buffer(ctx, buffer, passes.len() * 2)?,
            None => Vec::new(),
        };
        if self.queries.is_some() && ctx.queue.get_timestamp_period() <= 0.0 {
            return Err(Error::Gpu("device reports a zero timestamp period".into()));
        }
        Ok(Self::stage_times(ctx, passes, &ticks))
    }
}

/// Adds up stages with the same label (e.g. several treelet rounds, or the dispatches of a stage
/// timed one by one), times and dispatches, in order of first appearance; a label is "n/a" if any
/// of its passes is. The sums name no kernel.
pub fn aggregate_stages(stages: Vec<StageTime>) -> Vec<StageTime> {
    let mut out: Vec<StageTime> = Vec::new();
    for stage in stages {
        match out.iter_mut().find(|s| s.label == stage.label) {
            Some(total) => {
                total.ms = total.ms.zip(stage.ms).map(|(a, b)| a + b);
                total.dispatches += stage.dispatches;
            }
            None => out.push(StageTime {
                kernel: None,
                ..stage
            }),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{aggregate_stages, StageTime};

    fn stage(label: &str, ms: Option<f64>, dispatches: u32) -> StageTime {
        StageTime {
            label: label.into(),
            ms,
            dispatches,
            kernel: None,
        }
    }

    #[test]
    fn stages_with_one_label_add_up_in_first_seen_order() {
        let stages = vec![
            stage("bounds", Some(1.0), 2),
            stage("sort", Some(2.0), 36),
            stage("refit", None, 1),
            stage("sort", Some(3.0), 36),
            stage("refit", Some(1.0), 1),
        ];
        assert_eq!(
            aggregate_stages(stages),
            vec![
                stage("bounds", Some(1.0), 2),
                stage("sort", Some(5.0), 72),
                stage("refit", None, 2)
            ]
        );
    }
}
