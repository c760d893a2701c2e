//! Kochanek–Bartels (tension–continuity–bias) interpolation of BART key-frame tracks, and the
//! evaluation of a named animation (`k name { … }`: translation, rotation, scale and visibility
//! tracks) into a transform at a given time.
//!
//! Each track is a cubic Hermite spline per segment between consecutive keys, with the
//! tangents of Kochanek & Bartels (SIGGRAPH 1984) in the form of BART's `kbsplpos.c` (Dave
//! Eberly's code). For the segment from key 1 to key 2 (neighbours key 0 and key 3), with
//! tension T, continuity C and bias B of the key the tangent belongs to:
//!
//! * outgoing tangent at key 1 = adj0·[(1−T)(1+C)(1+B)/2·(P1−P0) + (1−T)(1−C)(1−B)/2·(P2−P1)];
//! * incoming tangent at key 2 = adj1·[(1−T)(1−C)(1+B)/2·(P2−P1) + (1−T)(1+C)(1−B)/2·(P3−P2)];
//! * adj0 = 2(t2−t1)/(t2−t0) and adj1 = 2(t2−t1)/(t3−t1) (Kochanek–Bartels' correction for
//!   unevenly spaced keys), and the segment is evaluated at u = (t−t1)/(t2−t1) ∈ [0, 1].
//!
//! The curve runs through ALL keys and clamps to the first key before it and to the last key
//! after it (the convention of the reference frames; BART's code instead uses the first and the
//! last key only for tangents, see the `bart` module documentation). At the ends the missing
//! neighbour is the end key itself (P0 = P1 and t0 = t1 in the first segment, P3 = P2 and
//! t3 = t2 in the last), so the end tangents are the end segment's chord times (1−T)(1−C)(1−B)
//! at the first key and (1−T)(1−C)(1+B) at the last: keys in uniform straight motion stay
//! uniform. A track with a single key is constant.
//!
//! Rotation tracks are splined per component on (axis x, axis y, axis z, angle in degrees); the
//! axis is normalised after interpolation (see the module documentation of `bart` for why this
//! differs from BART's quaternion spline).

use glam::{DAffine3, DQuat, DVec3};

/// One key of an N-component track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Key<const N: usize> {
    pub time: f64,
    pub value: [f64; N],
    pub tension: f64,
    pub continuity: f64,
    pub bias: f64,
}

/// A Kochanek–Bartels spline through N-component keys (see the file header for the formulas).
#[derive(Clone, Debug)]
pub(super) struct Spline<const N: usize> {
    segments: Vec<Segment<N>>,
}

/// One cubic piece: component k is c[k][0] + u·(c[k][1] + u·(c[k][2] + u·c[k][3])), u ∈ [0, 1].
#[derive(Clone, Copy, Debug)]
struct Segment<const N: usize> {
    start: f64,
    end: f64,
    coeffs: [[f64; 4]; N],
}

impl<const N: usize> Spline<N> {
    /// Builds the spline through `keys` (at least one).
    ///
    /// Key times should not decrease, but, as in BART's code, they are not required to (a gun
    /// rotation track of the robots scene jumps back in time): `eval` then uses the first
    /// segment whose end time lies beyond `t`.
    pub fn new(keys: &[Key<N>]) -> Result<Self, String> {
        let Some(last) = keys.last() else {
            return Err("a key-frame track needs at least one key".into());
        };
        let segments = if keys.len() == 1 {
            // A constant: one empty segment whose value is the key at both ends.
            vec![Segment::new(last, last, last, last)]
        } else {
            (0..keys.len() - 1)
                .map(|i| {
                    let k0 = &keys[i.saturating_sub(1)];
                    let k3 = keys.get(i + 2).unwrap_or(last);
                    Segment::new(k0, &keys[i], &keys[i + 1], k3)
                })
                .collect()
        };
        Ok(Self { segments })
    }

    /// The value at time `t`, clamped to the first/last key outside their range.
    pub fn eval(&self, t: f64) -> [f64; N] {
        let first = &self.segments[0];
        let last = &self.segments[self.segments.len() - 1];
        let (segment, u) = if t <= first.start {
            (first, 0.0)
        } else if t >= last.end {
            (last, 1.0)
        } else {
            // The first segment whose end lies beyond t, as BART's linear search (`t < tmax`);
            // one exists because t < last.end.
            let s = self.segments.iter().find(|s| t < s.end).unwrap_or(last);
            (s, (t - s.start) / (s.end - s.start))
        };
        let c = &segment.coeffs;
        std::array::from_fn(|k| c[k][0] + u * (c[k][1] + u * (c[k][2] + u * c[k][3])))
    }
}

/// `2·num/den`, or 0 where the keys coincide in time (the tangent then does not matter: the
/// segment has zero length and is only ever evaluated at its ends).
fn adjust(num: f64, den: f64) -> f64 {
    if den != 0.0 {
        2.0 * num / den
    } else {
        0.0
    }
}

impl<const N: usize> Segment<N> {
    /// The piece from `k1` to `k2`, with neighbours `k0` (before `k1`) and `k3` (after `k2`).
    fn new(k0: &Key<N>, k1: &Key<N>, k2: &Key<N>, k3: &Key<N>) -> Self {
        let adj0 = adjust(k2.time - k1.time, k2.time - k0.time);
        let out_prev = 0.5 * adj0 * (1.0 - k1.tension) * (1.0 + k1.continuity) * (1.0 + k1.bias);
        let out_next = 0.5 * adj0 * (1.0 - k1.tension) * (1.0 - k1.continuity) * (1.0 - k1.bias);
        let adj1 = adjust(k2.time - k1.time, k3.time - k1.time);
        let in_prev = 0.5 * adj1 * (1.0 - k2.tension) * (1.0 - k2.continuity) * (1.0 + k2.bias);
        let in_next = 0.5 * adj1 * (1.0 - k2.tension) * (1.0 + k2.continuity) * (1.0 - k2.bias);
        // Hermite form with the tangents folded in (as `kbsplpos.c`).
        let coeffs = std::array::from_fn(|k| {
            let d = k2.value[k] - k1.value[k];
            let t_out = out_next * d + out_prev * (k1.value[k] - k0.value[k]);
            let t_in = in_next * (k3.value[k] - k2.value[k]) + in_prev * d;
            [
                k1.value[k],
                t_out,
                3.0 * d - 2.0 * t_out - t_in,
                -2.0 * d + t_out + t_in,
            ]
        });
        Self {
            start: k1.time,
            end: k2.time,
            coeffs,
        }
    }
}

/// A named animation (`k name { … }`): optional translation, rotation and scale splines and
/// visibility switches. Its transform is T·R·S (scale first, then rotation, then translation).
#[derive(Clone, Debug, Default)]
pub(super) struct Animation {
    pub translation: Option<Spline<3>>,
    /// Components: axis x, axis y, axis z, angle in degrees.
    pub rotation: Option<Spline<4>>,
    pub scale: Option<Spline<3>>,
    /// (time, visible) switches in file order; visible before the first one.
    pub visibility: Vec<(f64, bool)>,
}

impl Animation {
    pub fn translation_at(&self, t: f64) -> DVec3 {
        self.translation
            .as_ref()
            .map_or(DVec3::ZERO, |s| DVec3::from_array(s.eval(t)))
    }

    /// The rotation at `t`: the splined axis, normalised, and the splined angle (degrees). A
    /// zero axis gives no rotation.
    pub fn rotation_at(&self, t: f64) -> DQuat {
        self.rotation.as_ref().map_or(DQuat::IDENTITY, |s| {
            let [x, y, z, degrees] = s.eval(t);
            axis_angle(DVec3::new(x, y, z), degrees)
        })
    }

    pub fn scale_at(&self, t: f64) -> DVec3 {
        self.scale
            .as_ref()
            .map_or(DVec3::ONE, |s| DVec3::from_array(s.eval(t)))
    }

    /// T·R·S at time `t`.
    pub fn transform_at(&self, t: f64) -> DAffine3 {
        DAffine3::from_scale_rotation_translation(
            self.scale_at(t),
            self.rotation_at(t),
            self.translation_at(t),
        )
    }

    /// BART's rule: visible until the first switch; from each switch's time on, its flag holds.
    pub fn visible_at(&self, t: f64) -> bool {
        self.visibility
            .iter()
            .take_while(|&&(time, _)| time <= t)
            .last()
            .is_none_or(|&(_, visible)| visible)
    }
}

/// Rotation by `degrees` about `axis` (normalised here); the identity for a zero axis.
pub(super) fn axis_angle(axis: DVec3, degrees: f64) -> DQuat {
    match axis.try_normalize() {
        Some(axis) => DQuat::from_axis_angle(axis, degrees.to_radians()),
        None => DQuat::IDENTITY,
    }
}
