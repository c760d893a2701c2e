//! The Pareto front of tree quality against build time: the configurations that no other one
//! beats on both SAH cost and build time.

use super::Measurement;

/// Indices of the measurements on the Pareto front (lower SAH and lower build time are better),
/// ordered by build time. A measurement is dominated when another one is no worse on both and
/// strictly better on one; of exact duplicates the first is kept. Measurements with a non-finite
/// build time or SAH are left out.
pub fn pareto_front(measurements: &[Measurement]) -> Vec<usize> {
    let finite = |m: &Measurement| m.build_ms.is_finite() && m.sah.is_finite();
    let mut order: Vec<usize> = (0..measurements.len())
        .filter(|&i| finite(&measurements[i]))
        .collect();
    // By build time, then SAH, then position: a sweep keeps each strict SAH improvement.
    order.sort_by(|&a, &b| {
        let (ma, mb) = (&measurements[a], &measurements[b]);
        ma.build_ms
            .total_cmp(&mb.build_ms)
            .then(ma.sah.total_cmp(&mb.sah))
            .then(a.cmp(&b))
    });
    let mut front = Vec::new();
    let mut best_sah = f64::INFINITY;
    for i in order {
        if measurements[i].sah < best_sah {
            best_sah = measurements[i].sah;
            front.push(i);
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    fn m(build_ms: f64, sah: f64) -> Measurement {
        Measurement {
            label: format!("{build_ms}/{sah}"),
            builder: "x".into(),
            treelet_size: None,
            rounds: None,
            gpu: true,
            build_ms,
            sah,
            mrays_per_s: 1.0,
            valid: true,
        }
    }

    #[test]
    fn dominated_points_are_left_out() {
        let ms = [
            m(10.0, 50.0), // fastest
            m(20.0, 40.0), // on the front
            m(25.0, 45.0), // dominated by (20, 40)
            m(40.0, 30.0), // best SAH
            m(40.0, 35.0), // same time, worse SAH
            m(50.0, 30.0), // same SAH, slower
            m(f64::NAN, 1.0),
        ];
        assert_eq!(pareto_front(&ms), vec![0, 1, 3]);
    }

    #[test]
    fn duplicates_keep_the_first() {
        let ms = [m(5.0, 5.0), m(5.0, 5.0)];
        assert_eq!(pareto_front(&ms), vec![0]);
    }
}
