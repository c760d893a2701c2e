//! The frame-time model of Karras & Aila 2013, Figure 1: a frame that traces R rays through a tree
//! rebuilt every frame takes `build + R / throughput`, so its *effective* ray throughput is
//! `R / (build + R / throughput)`. Cheap builders win for few rays per frame, high-quality trees
//! for many; the best configuration for a given R is the lower envelope of these lines, and its
//! changes (crossovers) are where `build_a + R/T_a = build_b + R/T_b`, i.e.
//! `R = (build_b − build_a) / (1/T_a − 1/T_b)`. Everything here is pure arithmetic on measurements.

use serde::Serialize;

/// Rays per frame covered by the study: from a small preview frame to a long offline render.
pub const RAYS_RANGE: (f64, f64) = (1e6, 1e12);
/// Log-spaced samples of the effective-throughput curves over `RAYS_RANGE` (10 per decade).
pub const CURVE_POINTS: usize = 61;

/// One builder configuration measured on one scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measurement {
    /// "trbvh n=7 r=3" style label (unique per configuration).
    pub label: String,
    /// Builder name ("lbvh", "trbvh", "sweep", …).
    pub builder: String,
    pub treelet_size: Option<u32>,
    pub rounds: Option<u32>,
    /// Whether the builder runs on the GPU (its build time is GPU time) or the CPU.
    pub gpu: bool,
    /// Build time in milliseconds.
    pub build_ms: f64,
    /// SAH cost of the tree (Ci = 1.2, Ct = 1).
    pub sah: f64,
    /// Ray throughput of the tree (diffuse paths), in millions of rays per second.
    pub mrays_per_s: f64,
    /// Whether the tree passed the validator.
    pub valid: bool,
}

impl Measurement {
    /// Whether the model applies: a finite, non-negative build time and a positive throughput.
    pub fn is_usable(&self) -> bool {
        self.build_ms.is_finite()
            && self.build_ms >= 0.0
            && self.mrays_per_s.is_finite()
            && self.mrays_per_s > 0.0
    }

    /// Time of a frame that builds the tree once and traces `rays` rays through it, in seconds.
    pub fn frame_s(&self, rays: f64) -> f64 {
        self.build_ms * 1e-3 + rays * self.seconds_per_ray()
    }

    fn seconds_per_ray(&self) -> f64 {
        1.0 / (self.mrays_per_s * 1e6)
    }
}

/// Effective throughput in Mrays/s of a frame with `rays` rays: `rays / (build + rays / T)`.
pub fn effective_mrays(m: &Measurement, rays: f64) -> f64 {
    let seconds = m.frame_s(rays);
    if seconds > 0.0 {
        rays / seconds * 1e-6
    } else {
        m.mrays_per_s
    }
}

/// `n` points from `min` to `max` (both included), evenly spaced on a log scale.
pub fn log_space(min: f64, max: f64, n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![min],
        _ => {
            let (lo, hi) = (min.log10(), max.log10());
            (0..n)
                .map(|i| 10f64.powf(lo + (hi - lo) * i as f64 / (n - 1) as f64))
                .collect()
        }
    }
}

/// A range of rays per frame in which one configuration gives the shortest frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BestRange {
    pub label: String,
    pub from_rays: f64,
    pub to_rays: f64,
}

/// Relative tolerance under which two frame times or two crossover points count as equal, so
/// that rounding never makes a configuration best over a sliver of rays per frame.
const TIE: f64 = 1e-9;

/// The configurations that give the shortest frame time (highest effective throughput) somewhere
/// in `[min_rays, max_rays]`, in order of increasing rays per frame, with the exact crossover
/// points as range ends. Ranges tile the interval without gaps. Ties: where two configurations
/// are equal over the whole interval the one listed first wins; where several are equal at one
/// point (the start of the interval, or a crossover of three or more) the flattest wins, the one
/// that stays best after it, so no range is empty. Unusable measurements (see
/// [`Measurement::is_usable`]) never win. Empty when none is usable or the interval is empty.
pub fn best_ranges(measurements: &[Measurement], min_rays: f64, max_rays: f64) -> Vec<BestRange> {
    let usable: Vec<&Measurement> = measurements.iter().filter(|m| m.is_usable()).collect();
    if usable.is_empty() || !(min_rays.is_finite() && max_rays.is_finite() && min_rays < max_rays) {
        return Vec::new();
    }
    // Lines f(R) = build + R · seconds_per_ray: the fastest at `min_rays`.
    let Some(mut current) = flattest_near_min(&usable, |m| m.frame_s(min_rays)) else {
        return Vec::new();
    };
    let mut from = min_rays;
    let mut ranges = Vec::new();
    loop {
        // Only flatter lines can overtake the current one; the first to do so wins.
        let flatter: Vec<&Measurement> = usable
            .iter()
            .copied()
            .filter(|m| m.seconds_per_ray() < current.seconds_per_ray())
            .collect();
        let next = flattest_near_min(&flatter, |m| crossover(current, m).max(from));
        match next {
            Some(m) if crossover(current, m).max(from) < max_rays => {
                let at = crossover(current, m).max(from);
                if at > from * (1.0 + TIE) {
                    ranges.push(range(current, from, at));
                    from = at;
                }
                current = m;
            }
            _ => {
                ranges.push(range(current, from, max_rays));
                return ranges;
            }
        }
    }
}

/// Of the measurements whose `key` is within `TIE` of the smallest, the flattest line (the first
/// listed among equally flat ones).
fn flattest_near_min<'a>(
    candidates: &[&'a Measurement],
    key: impl Fn(&Measurement) -> f64,
) -> Option<&'a Measurement> {
    let min = candidates.iter().map(|m| key(m)).min_by(f64::total_cmp)?;
    let limit = min + min.abs() * TIE;
    candidates
        .iter()
        .copied()
        .filter(|m| key(m) <= limit)
        .min_by(|a, b| a.seconds_per_ray().total_cmp(&b.seconds_per_ray()))
}

/// Rays per frame at which `a` and `b` take the same time (`a` steeper than `b`).
fn crossover(a: &Measurement, b: &Measurement) -> f64 {
    let build_gap_s = (b.build_ms - a.build_ms) * 1e-3;
    build_gap_s / (a.seconds_per_ray() - b.seconds_per_ray())
}

fn range(m: &Measurement, from_rays: f64, to_rays: f64) -> BestRange {
    BestRange {
        label: m.label.clone(),
        from_rays,
        to_rays,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_space_hits_both_ends() {
        let xs = log_space(1e6, 1e12, 61);
        assert_eq!(xs.len(), 61);
        assert!((xs[0] - 1e6).abs() < 1e-3);
        assert!((xs[10] / 1e7 - 1.0).abs() < 1e-12);
        assert!((xs[60] / 1e12 - 1.0).abs() < 1e-12);
    }
}
