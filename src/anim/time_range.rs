//! The time axis of an animation: start and end time and the number of frames it is sampled at
//! (frame f at start + (end − start)·f/(frames − 1)). Frames past the last one wrap around to the
//! first (animations loop).

/// Start and end time of an animation and its nominal frame count (at least 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeRange {
    pub start: f32,
    pub end: f32,
    pub frames: u32,
}

impl TimeRange {
    /// A range of `frames` frames (at least 1) from `start` to `end` (at least `start`).
    pub fn new(start: f32, end: f32, frames: u32) -> Self {
        let frames = frames.max(1);
        let end = if end.is_finite() && end > start {
            end
        } else {
            start
        };
        Self { start, end, frames }
    }

    /// Seconds (scene time units) from `start` to `end`.
    pub fn duration(&self) -> f32 {
        self.end - self.start
    }

    /// Time between two consecutive frames (0 for a one-frame animation).
    pub fn step(&self) -> f32 {
        if self.frames <= 1 {
            0.0
        } else {
            self.duration() / (self.frames - 1) as f32
        }
    }

    /// Time of `frame`; frames past the last one wrap around to the first.
    pub fn frame_time(&self, frame: u32) -> f32 {
        if self.frames <= 1 {
            return self.start;
        }
        let f = frame % self.frames;
        self.start + self.duration() * f as f32 / (self.frames - 1) as f32
    }

    /// The frame nearest to `t`.
    pub fn frame_at(&self, t: f32) -> u32 {
        let step = self.step();
        if step <= 0.0 {
            return 0;
        }
        (((t - self.start) / step).round().max(0.0) as u32).min(self.frames - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_evenly_spaced_and_wrap() {
        let r = TimeRange::new(1.0, 3.0, 5);
        assert_eq!(r.step(), 0.5);
        assert_eq!(r.frame_time(0), 1.0);
        assert_eq!(r.frame_time(4), 3.0);
        assert_eq!(r.frame_time(5), 1.0);
        assert_eq!(r.frame_at(2.6), 3);
        assert_eq!(r.frame_at(9.0), 4);
    }

    #[test]
    fn degenerate_ranges_stay_at_the_start() {
        let r = TimeRange::new(2.0, 1.0, 0);
        assert_eq!((r.end, r.frames), (2.0, 1));
        assert_eq!(r.frame_time(7), 2.0);
        assert_eq!(r.frame_at(9.0), 0);
        assert_eq!(r.step(), 0.0);
    }
}
