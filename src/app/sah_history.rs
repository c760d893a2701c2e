//! SAH cost over animation time for the viewer's plot: per animated frame, the cost of the tree
//! rebuilt for that frame and of the first frame's tree refitted to it. Cleared when the scene,
//! the builder or the loop changes.

use std::collections::VecDeque;

/// Samples kept (oldest dropped first).
const CAPACITY: usize = 2048;

/// Both trees' SAH cost at one animation time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SahSample {
    pub t: f32,
    pub rebuild: f32,
    pub refit: f32,
}

#[derive(Clone, Debug, Default)]
pub struct SahHistory {
    samples: VecDeque<SahSample>,
    /// Names of the two series ("rebuild (lbvh)", "refit (lbvh topology)").
    pub labels: (String, String),
}

impl SahHistory {
    /// An empty history with these series names.
    pub fn new(rebuild_label: String, refit_label: String) -> Self {
        Self {
            samples: VecDeque::new(),
            labels: (rebuild_label, refit_label),
        }
    }

    /// Adds a sample; a sample at the time of the last one replaces it.
    pub fn push(&mut self, sample: SahSample) {
        if self.samples.back().is_some_and(|s| s.t == sample.t) {
            self.samples.pop_back();
        }
        if self.samples.len() == CAPACITY {
            self.samples.pop_front();
        }
        self.samples.push_back(sample);
    }

    pub fn clear(&mut self) {
        self.samples.clear();
    }

    pub fn last(&self) -> Option<SahSample> {
        self.samples.back().copied()
    }

    /// (t, rebuild cost) and (t, refit cost) points, oldest first.
    pub fn series(&self) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
        self.samples
            .iter()
            .map(|s| {
                (
                    [f64::from(s.t), f64::from(s.rebuild)],
                    [f64::from(s.t), f64::from(s.refit)],
                )
            })
            .unzip()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_one_sample_per_time_in_order() {
        let mut h = SahHistory::new("a".into(), "b".into());
        for (t, c) in [(0.0, 1.0), (0.5, 2.0), (0.5, 3.0)] {
            h.push(SahSample {
                t,
                rebuild: c,
                refit: 2.0 * c,
            });
        }
        let (rebuild, refit) = h.series();
        assert_eq!(rebuild, vec![[0.0, 1.0], [0.5, 3.0]]);
        assert_eq!(refit[1], [0.5, 6.0]);
        h.clear();
        assert!(h.last().is_none());
    }
}
