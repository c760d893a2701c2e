//! A frame's statistics read back without waiting: the timestamps of its passes (animate, build
//! stages, trace), the tracer's ray counters and the tree's node and reference counts (and the
//! wide tree's, when the update converted it) are copied into a staging buffer at the end of the
//! frame's recording and reach the panel a frame or two later, once the GPU is done. A few slots
//! rotate; when all are still in flight (the GPU is behind), a frame records without statistics.

use super::animated_scene::COMPANION_PREFIX;
use super::stats::BuildTiming;
use crate::device::Tree;
use crate::gpu::{GpuContext, GpuTimer, Readback, Recorder, StageTime, TimedPass};
use crate::trace::{RecordedTrace, TraceStats};

/// Slots in flight at most.
const SLOTS: usize = 3;
/// Passes one frame records at most (animate, the build's stages, trace, tonemap).
const MAX_PASSES: u32 = 32;
/// Staging layout: timestamps, then trace counters, then tree counts, then the wide tree's
/// counters (nodes, references, capacity overflows).
const TICKS_BYTES: u64 = MAX_PASSES as u64 * 16;
const COUNTERS_BYTES: u64 = 64 * 8;
const TREE_COUNTS_AT: u64 = TICKS_BYTES + COUNTERS_BYTES;
const WIDE_COUNTS_AT: u64 = TREE_COUNTS_AT + 8;
const WIDE_COUNTS_BYTES: u64 = 12;
const STAGING_BYTES: u64 = WIDE_COUNTS_AT + WIDE_COUNTS_BYTES;

/// What a frame recorded, to interpret its readback.
#[derive(Clone, Debug, Default)]
pub struct FrameRecord {
    /// The frame rebuilt or refitted its tree; CPU builders' time (GPU builders' stages are
    /// timestamped).
    pub built: bool,
    pub build_cpu: Option<StageTime>,
    /// The frame animated; a CPU evaluation's time (GPU kernels are timestamped).
    pub animated: bool,
    pub animate_cpu: Option<StageTime>,
    pub trace: Option<RecordedTrace>,
    /// Wall-clock time of recording the frame (the trace's fallback without timestamps).
    pub wall_ms: f64,
    /// The tree had a wide layout after the frame (its counters were copied; set by `record`).
    pub wide: bool,
}

/// What a frame's readback says.
#[derive(Clone, Debug, Default)]
pub struct FrameResult {
    pub build: Option<BuildTiming>,
    /// The rebuild-versus-refit companion's update (passes labelled `COMPANION_PREFIX`).
    pub companion: Option<BuildTiming>,
    pub animate: Option<StageTime>,
    pub trace: Option<TraceStats>,
    /// (nodes, references) of the tree after the frame.
    pub tree_counts: (u32, u32),
    /// (wide nodes, references) of its wide layout, when the frame's tree had one.
    pub wide_counts: Option<(u32, u32)>,
    /// The wide conversion ran out of nodes (a bug: its capacity bounds every binary tree).
    pub wide_overflowed: bool,
    /// Paths that overflowed the traversal stack.
    pub overflows: u64,
}

struct Slot {
    /// Lent to the frame being recorded (`begin`), returned by `submitted`.
    timer: Option<GpuTimer>,
    readback: Readback,
    /// Timed passes and the record of the frame in flight.
    pending: Option<(Vec<TimedPass>, FrameRecord)>,
}

pub struct FrameReadback {
    slots: Vec<Slot>,
    /// The slot of the frame being recorded.
    recording: Option<usize>,
}

impl FrameReadback {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            slots: (0..SLOTS)
                .map(|_| Slot {
                    timer: Some(GpuTimer::new(ctx, MAX_PASSES)),
                    readback: Readback::new(ctx, STAGING_BYTES),
                    pending: None,
                })
                .collect(),
            recording: None,
        }
    }

    /// The timer of a free slot for the next frame's recording (None: all in flight); give it
    /// back with `submitted`.
    pub fn begin(&mut self) -> Option<GpuTimer> {
        let free = self
            .slots
            .iter()
            .position(|s| s.pending.is_none() && s.readback.is_free() && s.timer.is_some())?;
        self.recording = Some(free);
        self.slots[free].timer.take()
    }

    /// At the end of the frame's recording: resolves its timer and copies the statistics (the
    /// counts of `tree` and of its wide layout, if it has one).
    pub fn record(
        &mut self,
        rec: &mut Recorder<'_>,
        counters: Option<&wgpu::Buffer>,
        tree: &Tree,
        mut record: FrameRecord,
    ) {
        let Some(index) = self.recording else {
            return;
        };
        rec.resolve_timer();
        let slot = &mut self.slots[index];
        let (passes, ticks) = match rec.timer_mut() {
            Some(timer) => (timer.take_passes(), timer.resolved_buffer().cloned()),
            None => (Vec::new(), None),
        };
        let encoder = rec.encoder();
        if let Some(ticks) = ticks.filter(|_| !passes.is_empty()) {
            slot.readback
                .copy(encoder, &ticks, 0, passes.len() as u64 * 16);
        }
        if let (Some(counters), Some(trace)) = (counters, record.trace) {
            slot.readback.copy(
                encoder,
                counters,
                TICKS_BYTES,
                u64::from(trace.dispatches) * 8,
            );
        }
        slot.readback.copy(encoder, &tree.counts, TREE_COUNTS_AT, 8);
        if let Some(wide) = &tree.wide {
            slot.readback
                .copy(encoder, &wide.counters, WIDE_COUNTS_AT, WIDE_COUNTS_BYTES);
        }
        record.wide = tree.wide.is_some();
        slot.pending = Some((passes, record));
    }

    /// After the frame was submitted: takes its timer back and starts reading its statistics.
    pub fn submitted(&mut self, timer: Option<GpuTimer>) {
        if let Some(index) = self.recording.take() {
            let slot = &mut self.slots[index];
            slot.timer = timer;
            slot.readback.start();
        }
    }

    /// The statistics of frames the GPU has finished (the device must have been polled).
    pub fn poll(&mut self, ctx: &GpuContext) -> Vec<FrameResult> {
        let mut results = Vec::new();
        for slot in &mut self.slots {
            if slot.pending.is_none() {
                continue;
            }
            let Some(bytes) = slot.readback.try_take() else {
                continue;
            };
            let (passes, record) = slot.pending.take().expect("checked above");
            let Ok(bytes) = bytes else {
                continue;
            };
            results.push(decode(ctx, passes, record, &bytes));
        }
        results
    }
}

fn decode(
    ctx: &GpuContext,
    passes: Vec<TimedPass>,
    record: FrameRecord,
    bytes: &[u8],
) -> FrameResult {
    let words = |at: u64, count: usize| -> Vec<u32> {
        bytemuck::pod_collect_to_vec(&bytes[at as usize..at as usize + 4 * count])
    };
    let ticks: Vec<u64> = if ctx.timestamps {
        bytemuck::pod_collect_to_vec(&bytes[..passes.len() * 16])
    } else {
        Vec::new()
    };
    let stages = GpuTimer::stage_times(ctx, passes, &ticks);
    let stage = |name: &str| stages.iter().find(|s| s.label == name).cloned();
    let animate = if record.animated {
        record.animate_cpu.clone().or_else(|| stage("animate"))
    } else {
        None
    };
    let build = record.built.then(|| {
        let mut build_stages: Vec<StageTime> = stages
            .iter()
            .filter(|s| {
                !matches!(s.label.as_str(), "animate" | "trace" | "tonemap")
                    && !s.label.starts_with(COMPANION_PREFIX)
            })
            .cloned()
            .collect();
        build_stages.extend(record.build_cpu.clone());
        BuildTiming::from_stages(build_stages, record.wall_ms)
    });
    let companion_stages: Vec<StageTime> = stages
        .iter()
        .filter_map(|s| {
            let label = s.label.strip_prefix(COMPANION_PREFIX)?;
            Some(StageTime {
                label: label.into(),
                ..s.clone()
            })
        })
        .collect();
    let companion = (!companion_stages.is_empty())
        .then(|| BuildTiming::from_stages(companion_stages, record.wall_ms));
    let (trace, overflows) = match record.trace {
        Some(recorded) => {
            let counters = words(TICKS_BYTES, 2 * recorded.dispatches as usize);
            let (rays, overflows) = recorded.totals(&counters);
            let stats = TraceStats {
                rays,
                trace_ms: stage("trace").and_then(|s| s.ms),
                wall_ms: record.wall_ms,
                samples: recorded.samples,
                steps: None,
            };
            (Some(stats), overflows)
        }
        None => (None, 0),
    };
    let counts = words(TREE_COUNTS_AT, 2);
    let wide = record
        .wide
        .then(|| words(WIDE_COUNTS_AT, (WIDE_COUNTS_BYTES / 4) as usize));
    FrameResult {
        build,
        companion,
        animate,
        trace,
        tree_counts: (counts[0], counts[1]),
        wide_counts: wide.as_ref().map(|w| (w[0], w[1])),
        wide_overflowed: wide.is_some_and(|w| w[2] != 0),
        overflows,
    }
}
