//! What the side panel reports about the running viewer: frame times (smoothed, with a short
//! history for the plot), the last trace's ray throughput, the last build's stage times and the
//! current tree's size and SAH cost.

use std::collections::VecDeque;
use std::time::Instant;

use crate::gpu::{aggregate_stages, StageTime};
use crate::trace::TraceStats;

/// One build's timings: per-stage GPU times (aggregated by label) and the total.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildTiming {
    pub stages: Vec<StageTime>,
    /// Sum of the stage times; wall-clock time where the device has no timestamps.
    pub total_ms: f64,
    /// Whether `total_ms` comes from GPU timestamps (false: wall clock or CPU time).
    pub timestamped: bool,
}

impl BuildTiming {
    /// The timing of GPU `stages` that took `wall_ms` on the wall clock.
    pub fn from_stages(stages: Vec<StageTime>, wall_ms: f64) -> Self {
        let gpu_ms: Option<f64> = stages.iter().map(|s| s.ms).sum();
        Self {
            stages: aggregate_stages(stages),
            total_ms: gpu_ms.unwrap_or(wall_ms),
            timestamped: gpu_ms.is_some(),
        }
    }
}

/// Frames kept for the frame-time plot.
pub const HISTORY: usize = 240;
/// Weight of the newest frame in the smoothed frame time.
const SMOOTHING: f64 = 0.1;

/// The current tree's SAH cost and when it was measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeSah {
    pub cost: f32,
    pub leaves: usize,
    pub measured: Instant,
}

#[derive(Default)]
pub struct FrameStats {
    last_frame: Option<Instant>,
    /// Smoothed frame time in ms.
    pub frame_ms: Option<f64>,
    /// Recent frame times in ms, oldest first.
    pub history: VecDeque<f64>,
    pub frames: u64,
    /// The last trace's statistics (one frame's samples).
    pub trace: Option<TraceStats>,
    /// The last build's timings, and whether it was a per-frame rebuild.
    pub build: Option<BuildTiming>,
    pub tree_sah: Option<TreeSah>,
}

impl FrameStats {
    /// Marks the start of a new frame and records the time since the previous one.
    pub fn tick(&mut self, now: Instant) {
        if let Some(last) = self.last_frame {
            let ms = now.duration_since(last).as_secs_f64() * 1e3;
            self.frame_ms = Some(match self.frame_ms {
                Some(avg) => avg + SMOOTHING * (ms - avg),
                None => ms,
            });
            if self.history.len() == HISTORY {
                self.history.pop_front();
            }
            self.history.push_back(ms);
        }
        self.last_frame = Some(now);
        self.frames += 1;
    }

    pub fn fps(&self) -> Option<f64> {
        self.frame_ms.filter(|&ms| ms > 0.0).map(|ms| 1e3 / ms)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn frame_times_are_smoothed_and_bounded() {
        let mut stats = FrameStats::default();
        let t0 = Instant::now();
        stats.tick(t0);
        assert_eq!(stats.frame_ms, None);
        for i in 1..=(HISTORY as u32 + 10) {
            stats.tick(t0 + Duration::from_millis(20 * u64::from(i)));
        }
        assert_eq!(stats.history.len(), HISTORY);
        assert!((stats.frame_ms.unwrap() - 20.0).abs() < 1e-6);
        assert!((stats.fps().unwrap() - 50.0).abs() < 1e-6);
    }
}
