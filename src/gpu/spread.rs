//! The spread of repeated measurements (min / median / max), as benchmarks report them, and the
//! warm-up plan that precedes every timed series: a GPU idles at low clocks and needs some
//! hundred milliseconds of work before its timings mean anything.

use serde::Serialize;

/// Min, median and max of a series of measurements.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub max: f64,
}

impl Spread {
    /// The spread of `values` (NaNs sort last); `None` when empty.
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Some(Self {
            min: *sorted.first()?,
            median: sorted[sorted.len() / 2],
            max: *sorted.last()?,
        })
    }
}

/// How a series is measured: untimed warm-up runs (at least `warmup_runs`, and until they took
/// `warmup_ms` of wall-clock time in all), then `repeats` timed runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    pub warmup_ms: f64,
    pub warmup_runs: u32,
    pub repeats: u32,
}

impl Timing {
    /// One untimed run (pipeline compilation) and `repeats` timed ones: for renders and tools
    /// that need a tree, not a benchmark.
    pub fn quick(repeats: u32) -> Self {
        Self {
            warmup_ms: 0.0,
            warmup_runs: 1,
            repeats,
        }
    }

    /// Runs `run` until the warm-up is done; returns what it took.
    pub fn warm_up<E>(&self, mut run: impl FnMut() -> Result<(), E>) -> Result<Warmup, E> {
        let start = std::time::Instant::now();
        let mut runs = 0;
        while runs < self.warmup_runs || start.elapsed().as_secs_f64() * 1e3 < self.warmup_ms {
            run()?;
            runs += 1;
        }
        Ok(Warmup {
            runs,
            ms: start.elapsed().as_secs_f64() * 1e3,
        })
    }
}

/// The warm-up a series had: untimed runs and their wall-clock time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Warmup {
    pub runs: u32,
    pub ms: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_of_values() {
        assert_eq!(Spread::of(&[]), None);
        let s = Spread::of(&[3.0, 1.0, 2.0, 9.0, 4.0]).unwrap();
        assert_eq!((s.min, s.median, s.max), (1.0, 3.0, 9.0));
        assert_eq!(Spread::of(&[5.0]).unwrap().median, 5.0);
    }

    #[test]
    fn warm_up_runs_at_least_the_count_and_the_time() {
        let mut n = 0;
        let timing = Timing {
            warmup_ms: 0.0,
            warmup_runs: 3,
            repeats: 1,
        };
        let w = timing
            .warm_up(|| {
                n += 1;
                Ok::<_, ()>(())
            })
            .unwrap();
        assert_eq!((w.runs, n), (3, 3));
        let timing = Timing {
            warmup_ms: 20.0,
            warmup_runs: 0,
            repeats: 1,
        };
        let w = timing
            .warm_up(|| {
                std::thread::sleep(std::time::Duration::from_millis(2));
                Ok::<_, ()>(())
            })
            .unwrap();
        assert!(w.ms >= 20.0 && w.runs >= 5, "{w:?}");
    }
}
