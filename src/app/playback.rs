//! The animation clock of the viewer and its controls: play/pause, single steps, speed, seeking,
//! and whether time follows the wall clock or advances one animation frame per displayed frame
//! (the default: on a slow device every frame of the animation is still shown, in slow motion).

use crate::anim::TimeRange;

/// Playback settings the panel edits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Playback {
    pub playing: bool,
    /// Animation frames (or seconds, in real time) per displayed frame (per second).
    pub speed: f32,
    /// Advance by the wall-clock time between frames instead of one frame step per frame.
    pub real_time: bool,
    /// Use the animation's camera (turned off when the user moves the camera).
    pub follow_camera: bool,
    /// Keep a second tree (refit when rebuilding, rebuild when refitting) and plot both trees'
    /// SAH cost on every animated frame (downloads both trees each frame).
    pub compare: bool,
}

impl Default for Playback {
    fn default() -> Self {
        Self {
            playing: true,
            speed: 1.0,
            real_time: false,
            follow_camera: true,
            compare: true,
        }
    }
}

impl Playback {
    pub const MIN_SPEED: f32 = 0.1;
    pub const MAX_SPEED: f32 = 8.0;
}

/// What the user asked of the clock this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClockRequest {
    /// Advance one frame step (and pause).
    pub step: bool,
    /// Jump to this time.
    pub seek: Option<f32>,
}

/// The current animation time, kept as a position in frames: [0, frames), looping; fractional
/// positions between the last frame and the loop's end show the last frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clock {
    pub range: TimeRange,
    position: f32,
}

impl Clock {
    pub fn new(range: TimeRange) -> Self {
        Self {
            range,
            position: 0.0,
        }
    }

    /// The animation time shown now.
    pub fn t(&self) -> f32 {
        let last = (self.range.frames - 1) as f32;
        self.range.start + self.position.min(last) * self.range.step()
    }

    /// Moves the clock for one displayed frame `dt` seconds after the previous one. Returns
    /// whether it wrapped around the end (a new loop). Pauses `playback` on a single step.
    pub fn advance(&mut self, playback: &mut Playback, request: ClockRequest, dt: f32) -> bool {
        let step = self.range.step();
        if step <= 0.0 {
            return false;
        }
        if let Some(t) = request.seek {
            let last = (self.range.frames - 1) as f32;
            self.position = ((t - self.range.start) / step).clamp(0.0, last);
            return false;
        }
        let frames = if request.step {
            playback.playing = false;
            1.0
        } else if playback.playing {
            let speed = playback
                .speed
                .clamp(Playback::MIN_SPEED, Playback::MAX_SPEED);
            if playback.real_time {
                dt.max(0.0) * speed / step
            } else {
                speed
            }
        } else {
            0.0
        };
        if frames == 0.0 {
            return false;
        }
        let period = self.range.frames as f32;
        let position = self.position + frames;
        self.position = position.rem_euclid(period);
        position >= period
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_frames_and_wraps() {
        let mut clock = Clock::new(TimeRange::new(0.0, 1.0, 5));
        let mut playback = Playback::default();
        assert!(!clock.advance(&mut playback, ClockRequest::default(), 10.0));
        assert_eq!(
            clock.t(),
            0.25,
            "frame-locked: one step per frame whatever dt"
        );
        for _ in 0..3 {
            clock.advance(&mut playback, ClockRequest::default(), 0.0);
        }
        assert_eq!(clock.t(), 1.0);
        assert!(clock.advance(&mut playback, ClockRequest::default(), 0.0));
        assert_eq!(clock.t(), 0.0, "the loop goes on with the first frame");
    }

    #[test]
    fn pause_step_seek_and_real_time() {
        let mut clock = Clock::new(TimeRange::new(0.0, 2.0, 3));
        let mut playback = Playback {
            playing: false,
            ..Playback::default()
        };
        clock.advance(&mut playback, ClockRequest::default(), 0.5);
        assert_eq!(clock.t(), 0.0);
        let step = ClockRequest {
            step: true,
            seek: None,
        };
        clock.advance(&mut playback, step, 0.5);
        assert_eq!(clock.t(), 1.0);
        let seek = ClockRequest {
            step: false,
            seek: Some(9.0),
        };
        clock.advance(&mut playback, seek, 0.5);
        assert_eq!(clock.t(), 2.0);
        playback.playing = true;
        playback.real_time = true;
        playback.speed = 2.0;
        // Position 2 + 0.25 s · 2 / (1 s per frame) = 2.5 of a 3-frame loop: the last frame shows.
        assert!(!clock.advance(&mut playback, ClockRequest::default(), 0.25));
        assert_eq!(clock.t(), 2.0);
        assert!(clock.advance(&mut playback, ClockRequest::default(), 0.5));
        assert!((clock.t() - 0.5).abs() < 1e-6, "{}", clock.t());
        playback.playing = true;
        clock.advance(&mut playback, step, 0.25);
        assert!(!playback.playing, "a single step pauses");
    }
}
