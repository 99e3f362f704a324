//! The truth trajectory of the `fusion` experiment (spec A, "Truth trajectory";
//! Lee & Yoon 2011 §4.1): a natural cubic spline through 25 knots evenly spaced over
//! 0..1000 s — leave the surface at (0,0,0), dive to 100 m, a lawnmower ("ㄷ",
//! back-and-forth) search at constant 100 m depth with 10 course changes at 1..6 kt,
//! then surface — with small random horizontal knot offsets drawn from a trajectory
//! RNG. Also the course-change detector used to check it.
//!
//! # Nominal knot pattern
//!
//! With `n` course changes the pattern uses `2n + 5` knots (25 for `n = 10`), knot
//! spacing `h = duration / (n_knots - 1)` and segment `j = [t_j, t_{j+1}]`:
//!
//! - segments 0, 1: leg 0 (heading north) while diving, horizontal lengths
//!   `0.5 v_0 h` and `v_0 h`;
//! - segments `2, 4, ..., 2n`: the `n` turns, each a U-turn inside one segment: the
//!   knot moves `turn_width` east, north unchanged (the two 90° corners of a "ㄷ"
//!   merge into one 180° course change, centred mid-segment);
//! - segments `3, 5, ..., 2n+1`: legs `1..n`, leg `i` heading north for even `i`,
//!   south for odd `i`, length `v_i h`;
//! - segments `2n+2, 2n+3`: leg `n` continued while surfacing, lengths `v_n h`,
//!   `0.5 v_n h`.
//!
//! Depth knots are `0, 5D/6, D, ..., D, 5D/6, 0`. With this choice the natural
//! spline's knot second derivatives of depth are `M_1 = M_{n_knots-2} = -D/h^2` and
//! zero everywhere else (the equations at knots 1 and 2 read `4 M_1 = -4D/h^2` and
//! `M_1 = -D/h^2`), so the depth is **exactly** `D` during the search, with zero
//! vertical speed at its start and end, and never above the surface while diving. The search
//! phase is `[2h, (n_knots - 3) h]`.
//!
//! The default leg speeds (kt) `3, 4, 2.5, 4.5, 2.5, 4, 2, 4.5, 2, 4, 3` and turn width
//! 40 m give spline speeds of about 1.9..5.2 kt along the search, and centre the
//! fifth course change at about 438.5 s (inside the paper's zoom window 440 ± 7 s).
//!
//! # Perturbation
//!
//! Knots 1..n_knots-1 get horizontal offsets `N(0, sigma^2)` per axis, drawn in the
//! order `x_1, y_1, x_2, y_2, ...` (standard-normal draws times sigma, so the draws
//! consumed do not depend on sigma). Knot 0 stays at the origin (the mothership) and
//! depths are not perturbed, so the search depth stays exactly `D`. With the default
//! `sigma = 1 m` the checks hold with margin for every seed tried (1000 seeds: speed
//! 1.7..5.5 kt, 10 course changes, fifth change within 4 s of 440 s).
//!
//! The generator verifies its own output (speed band, depth band, number of course
//! changes during the search) and returns an error instead of a mission that breaks
//! them (possible with a large sigma; draw again with another seed or lower sigma).

use fathom_core::{
    Time,
    error::{ensure_non_negative, ensure_positive},
    time::uniform_grid,
    units::{deg_to_rad, knots_to_mps, wrap_pi},
};
use nalgebra::Vector3;
use rand::Rng;
use rand_distr::StandardNormal;

use crate::{CubicSpline3, SplineTrajectory, TrajError, Trajectory};

/// Parameters of the `fusion` mission (all SI: s, m, m/s, rad). Validate with
/// [`FusionMissionParams::check`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FusionMissionParams {
    /// Mission duration, s (paper: 1000).
    pub duration: f64,
    /// Number of spline knots, evenly spaced over `[0, duration]` (paper: 25); must
    /// equal `2 * n_course_changes + 5`.
    pub n_knots: usize,
    /// Number of course changes during the search (paper: 10).
    pub n_course_changes: usize,
    /// Search depth, m (paper: 100).
    pub search_depth: f64,
    /// Allowed depth deviation during the search, m (spec: 1).
    pub depth_tolerance: f64,
    /// Lowest allowed speed during the search, m/s (paper: 1 kt).
    pub min_speed: f64,
    /// Highest allowed speed during the search, m/s (paper: 6 kt).
    pub max_speed: f64,
    /// Nominal speed of each leg, m/s: `n_course_changes + 1` values, each within
    /// `[min_speed, max_speed]` (leg 0 is flown while diving, the last while surfacing).
    pub leg_speeds: Vec<f64>,
    /// Eastward offset of each U-turn, m.
    pub turn_width: f64,
    /// Standard deviation of the horizontal knot offsets, m.
    pub perturbation_sigma: f64,
    /// Smallest heading change that counts as a course change, rad (spec: 45 deg).
    pub min_course_change: f64,
    /// Sampling step of the self-checks and course-change detection, s (spec: 1).
    pub check_dt: f64,
}

impl Default for FusionMissionParams {
    /// The paper's mission: 1000 s, 25 knots, 10 course changes at 100 m, 1..6 kt;
    /// leg speeds (kt) `3, 4, 2.5, 4.5, 2.5, 4, 2, 4.5, 2, 4, 3`, turn width 40 m,
    /// perturbation sigma 1 m, course change > 45 deg, checks every 1 s.
    fn default() -> Self {
        Self {
            duration: 1000.0,
            n_knots: 25,
            n_course_changes: 10,
            search_depth: 100.0,
            depth_tolerance: 1.0,
            min_speed: knots_to_mps(1.0),
            max_speed: knots_to_mps(6.0),
            leg_speeds: [3.0, 4.0, 2.5, 4.5, 2.5, 4.0, 2.0, 4.5, 2.0, 4.0, 3.0]
                .iter()
                .map(|&kt| knots_to_mps(kt))
                .collect(),
            turn_width: 40.0,
            perturbation_sigma: 1.0,
            min_course_change: deg_to_rad(45.0),
            check_dt: 1.0,
        }
    }
}

/// [`FusionMissionParams`] that passed [`FusionMissionParams::check`].
#[derive(Debug, Clone, PartialEq)]
pub struct CheckedFusionMissionParams(FusionMissionParams);

impl CheckedFusionMissionParams {
    /// The validated parameters.
    pub fn params(&self) -> &FusionMissionParams {
        &self.0
    }

    /// Knot spacing `h = duration / (n_knots - 1)`, s.
    pub fn knot_spacing(&self) -> f64 {
        self.0.duration / (self.0.n_knots - 1) as f64
    }

    /// The search phase `[2h, (n_knots - 3) h]`, s.
    pub fn search_interval(&self) -> (Time, Time) {
        let h = self.knot_spacing();
        (2.0 * h, (self.0.n_knots - 3) as f64 * h)
    }
}

fn invalid(field: &str, reason: impl Into<String>) -> TrajError {
    TrajError::InvalidParameter {
        field: field.to_owned(),
        reason: reason.into(),
    }
}

impl FusionMissionParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`TrajError::Core`] for a non-finite or non-positive duration, depth, depth
    /// tolerance, speed bound, turn width or check step, or a negative sigma;
    /// [`TrajError::InvalidParameter`] when `n_course_changes` is 0, `n_knots !=
    /// 2 n_course_changes + 5`, `min_speed >= max_speed`, `leg_speeds` has the wrong
    /// length or a value outside `[min_speed, max_speed]`, or `min_course_change` is
    /// not in `(0, pi)`.
    pub fn check(&self) -> Result<CheckedFusionMissionParams, TrajError> {
        ensure_positive("duration", self.duration)?;
        ensure_positive("search_depth", self.search_depth)?;
        ensure_positive("depth_tolerance", self.depth_tolerance)?;
        ensure_positive("min_speed", self.min_speed)?;
        ensure_positive("max_speed", self.max_speed)?;
        ensure_positive("turn_width", self.turn_width)?;
        ensure_positive("check_dt", self.check_dt)?;
        ensure_non_negative("perturbation_sigma", self.perturbation_sigma)?;
        if self.n_course_changes == 0 {
            return Err(invalid("n_course_changes", "must be at least 1"));
        }
        let Some(knots_needed) = self
            .n_course_changes
            .checked_mul(2)
            .and_then(|n| n.checked_add(5))
        else {
            return Err(invalid(
                "n_course_changes",
                format!("{} is too large", self.n_course_changes),
            ));
        };
        if self.n_knots != knots_needed {
            return Err(invalid(
                "n_knots",
                format!(
                    "the pattern with {} course changes needs {knots_needed} knots, got {}",
                    self.n_course_changes, self.n_knots
                ),
            ));
        }
        if self.min_speed >= self.max_speed {
            return Err(invalid(
                "min_speed",
                format!(
                    "{} m/s is not below max_speed {} m/s",
                    self.min_speed, self.max_speed
                ),
            ));
        }
        if self.leg_speeds.len() != self.n_course_changes + 1 {
            return Err(invalid(
                "leg_speeds",
                format!(
                    "needs n_course_changes + 1 = {} values, got {}",
                    self.n_course_changes + 1,
                    self.leg_speeds.len()
                ),
            ));
        }
        for (i, &v) in self.leg_speeds.iter().enumerate() {
            if !(v >= self.min_speed && v <= self.max_speed) {
                return Err(invalid(
                    "leg_speeds",
                    format!(
                        "leg {i}: {v} m/s is outside [{}, {}] m/s",
                        self.min_speed, self.max_speed
                    ),
                ));
            }
        }
        if !(self.min_course_change > 0.0 && self.min_course_change < std::f64::consts::PI) {
            return Err(invalid(
                "min_course_change",
                format!("{} rad is not in (0, pi)", self.min_course_change),
            ));
        }
        Ok(CheckedFusionMissionParams(self.clone()))
    }
}

/// A generated `fusion` mission: knots, the spline trajectory through them and the
/// search phase.
#[derive(Debug, Clone, PartialEq)]
pub struct FusionMission {
    knot_times: Vec<Time>,
    nominal_knots: Vec<Vector3<f64>>,
    knots: Vec<Vector3<f64>>,
    trajectory: SplineTrajectory,
    search_interval: (Time, Time),
    course_changes: Vec<Time>,
}

impl FusionMission {
    /// Knot times `k h`, s.
    pub fn knot_times(&self) -> &[Time] {
        &self.knot_times
    }

    /// The unperturbed knot pattern (NED, m).
    pub fn nominal_knots(&self) -> &[Vector3<f64>] {
        &self.nominal_knots
    }

    /// The perturbed knots the trajectory passes through (NED, m).
    pub fn knots(&self) -> &[Vector3<f64>] {
        &self.knots
    }

    /// The true trajectory.
    pub fn trajectory(&self) -> &SplineTrajectory {
        &self.trajectory
    }

    /// The search phase `[start, end]`, s (depth held at the search depth).
    pub fn search_interval(&self) -> (Time, Time) {
        self.search_interval
    }

    /// Course changes detected during the search by the generator's self-check
    /// ([`detect_course_changes`] with the parameters' `check_dt` and
    /// `min_course_change`), s.
    pub fn course_changes(&self) -> &[Time] {
        &self.course_changes
    }

    /// Consumes the mission, returning its trajectory.
    pub fn into_trajectory(self) -> SplineTrajectory {
        self.trajectory
    }
}

/// The unperturbed knot pattern (see the module docs) and its knot times.
pub fn nominal_knots(params: &CheckedFusionMissionParams) -> (Vec<Time>, Vec<Vector3<f64>>) {
    let p = params.params();
    let h = params.knot_spacing();
    let n = p.n_course_changes;
    let n_knots = p.n_knots;
    let times: Vec<Time> = (0..n_knots).map(|k| k as f64 * h).collect();
    let depth_at = |k: usize| -> f64 {
        if k == 0 || k == n_knots - 1 {
            0.0
        } else if k == 1 || k == n_knots - 2 {
            p.search_depth * 5.0 / 6.0
        } else {
            p.search_depth
        }
    };
    let heading_sign = |leg: usize| if leg.is_multiple_of(2) { 1.0 } else { -1.0 };
    let mut knots = Vec::with_capacity(n_knots);
    let (mut x, mut y) = (0.0, 0.0);
    knots.push(Vector3::new(x, y, depth_at(0)));
    for seg in 0..n_knots - 1 {
        // (north step, east step) of this segment.
        let (dx, dy) = if seg < 2 {
            let len = if seg == 0 { 0.5 } else { 1.0 } * p.leg_speeds[0] * h;
            (len, 0.0)
        } else if seg >= 2 * n + 2 {
            let len = if seg == 2 * n + 2 { 1.0 } else { 0.5 } * p.leg_speeds[n] * h;
            (heading_sign(n) * len, 0.0)
        } else if (seg - 2) % 2 == 0 {
            (0.0, p.turn_width)
        } else {
            let leg = (seg - 1) / 2;
            (heading_sign(leg) * p.leg_speeds[leg] * h, 0.0)
        };
        x += dx;
        y += dy;
        knots.push(Vector3::new(x, y, depth_at(seg + 1)));
    }
    (times, knots)
}

/// Generates the `fusion` mission: the nominal pattern, perturbed horizontally with
/// `N(0, perturbation_sigma^2)` offsets drawn from `rng` (see the module docs for the
/// draw order), then checked.
///
/// # Errors
/// [`TrajError::SpeedOutOfBounds`], [`TrajError::DepthOutOfTolerance`] or
/// [`TrajError::CourseChangeCount`] when the perturbed mission fails its checks on
/// the search phase (sampled every `check_dt`); spline errors cannot occur for
/// checked parameters but are passed on.
pub fn generate_fusion_mission(
    params: &CheckedFusionMissionParams,
    rng: &mut impl Rng,
) -> Result<FusionMission, TrajError> {
    let p = params.params();
    let (knot_times, nominal) = nominal_knots(params);
    let mut knots = nominal.clone();
    for knot in knots.iter_mut().skip(1) {
        let dx: f64 = rng.sample(StandardNormal);
        let dy: f64 = rng.sample(StandardNormal);
        knot.x += p.perturbation_sigma * dx;
        knot.y += p.perturbation_sigma * dy;
    }
    let trajectory = SplineTrajectory::new(CubicSpline3::new(&knot_times, &knots)?);
    let search_interval = params.search_interval();
    let (s0, s1) = search_interval;
    for t in uniform_grid(s0, s1, p.check_dt) {
        let state = trajectory.state_at(t.min(s1))?;
        let speed = state.vel_in_nav.norm();
        if !(speed >= p.min_speed && speed <= p.max_speed) {
            return Err(TrajError::SpeedOutOfBounds {
                t,
                speed,
                min: p.min_speed,
                max: p.max_speed,
            });
        }
        let depth = state.pos_in_nav.z;
        let depth_ok = (depth - p.search_depth).abs() <= p.depth_tolerance;
        if !depth_ok {
            return Err(TrajError::DepthOutOfTolerance {
                t,
                depth,
                nominal: p.search_depth,
                tolerance: p.depth_tolerance,
            });
        }
    }
    let course_changes =
        detect_course_changes(&trajectory, s0, s1, p.check_dt, p.min_course_change)?;
    if course_changes.len() != p.n_course_changes {
        return Err(TrajError::CourseChangeCount {
            expected: p.n_course_changes,
            detected: course_changes.len(),
        });
    }
    Ok(FusionMission {
        knot_times,
        nominal_knots: nominal,
        knots,
        trajectory,
        search_interval,
        course_changes,
    })
}

/// Times of the course changes of `traj` in `[t0, t1]`.
///
/// Method: the heading (yaw) is sampled at `t0, t0 + dt, ...` (up to `t1`), and the
/// increments `d_k = wrap(psi_{k+1} - psi_k)` are split into maximal runs of the same
/// sign (a zero increment continues the current run). Each run is one turn; its
/// heading change is the sum of its increments. A turn whose `|change|` exceeds
/// `threshold_rad` is a course change, reported at the instant (linearly
/// interpolated between samples) at which half of its heading change is done — the
/// turn's centre, robust to turns with several yaw-rate peaks. Two turns in the
/// same direction with no counter-turn between them merge into one; a turn cut by
/// the window counts only its part inside the window.
///
/// # Errors
/// [`TrajError::InvalidParameter`] for a non-positive or non-finite `dt` or
/// `threshold_rad`, or `t1 < t0`; [`TrajError::OutOfRange`] when the window leaves
/// the trajectory.
pub fn detect_course_changes(
    traj: &impl Trajectory,
    t0: Time,
    t1: Time,
    dt: Time,
    threshold_rad: f64,
) -> Result<Vec<Time>, TrajError> {
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(invalid(
            "dt",
            format!("{dt} s is not a positive finite step"),
        ));
    }
    if !(threshold_rad > 0.0 && threshold_rad.is_finite()) {
        return Err(invalid(
            "threshold_rad",
            format!("{threshold_rad} rad is not positive and finite"),
        ));
    }
    if !(t0.is_finite() && t1.is_finite() && t1 >= t0) {
        return Err(invalid(
            "t1",
            format!("window [{t0}, {t1}] s is empty or not finite"),
        ));
    }
    // The grid may end half a step beyond t1; clamp so rounding never leaves the range.
    let grid: Vec<Time> = uniform_grid(t0, t1, dt)
        .into_iter()
        .map(|t| t.min(t1))
        .collect();
    let mut yaw = Vec::with_capacity(grid.len());
    for &t in &grid {
        yaw.push(traj.state_at(t)?.attitude.yaw);
    }
    let d: Vec<f64> = yaw.windows(2).map(|w| wrap_pi(w[1] - w[0])).collect();
    let mut out = Vec::new();
    let mut start = 0;
    while start < d.len() {
        let sign_of = |x: f64| if x == 0.0 { 0.0 } else { x.signum() };
        let mut sign = sign_of(d[start]);
        let mut end = start + 1;
        while end < d.len() {
            let s = sign_of(d[end]);
            if sign == 0.0 {
                sign = s;
            } else if s != 0.0 && s != sign {
                break;
            }
            end += 1;
        }
        let total: f64 = d[start..end].iter().sum();
        if total.abs() > threshold_rad {
            let half = 0.5 * total.abs();
            let mut done = 0.0;
            for k in start..end {
                let step = d[k].abs();
                if done + step >= half {
                    let frac = if step > 0.0 {
                        (half - done) / step
                    } else {
                        0.0
                    };
                    out.push(grid[k] + frac * (grid[k + 1] - grid[k]));
                    break;
                }
                done += step;
            }
        }
        start = end;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use fathom_core::units::mps_to_knots;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    const SEEDS: [u64; 4] = [1, 7, 42, 2024];

    fn mission(seed: u64) -> FusionMission {
        let params = FusionMissionParams::default().check().unwrap();
        generate_fusion_mission(&params, &mut ChaCha8Rng::seed_from_u64(seed)).unwrap()
    }

    /// Found by fuzzing the scenario checks: a huge course-change count is an error,
    /// not an overflow in the knot count.
    #[test]
    fn huge_course_change_count_is_an_error() {
        let params = FusionMissionParams {
            n_course_changes: usize::MAX / 2,
            ..FusionMissionParams::default()
        };
        let e = params.check().unwrap_err().to_string();
        assert!(e.contains("is too large"), "{e}");
    }

    #[test]
    fn default_layout() {
        let params = FusionMissionParams::default().check().unwrap();
        assert_abs_diff_eq!(params.knot_spacing(), 1000.0 / 24.0, epsilon = 1e-12);
        let (t, k) = nominal_knots(&params);
        assert_eq!((t.len(), k.len()), (25, 25));
        assert_eq!(t[24], 1000.0);
        assert_eq!(k[0], Vector3::zeros());
        assert_eq!(k[24].z, 0.0);
        let (s0, s1) = params.search_interval();
        assert_abs_diff_eq!(s0, 2000.0 / 24.0, epsilon = 1e-12);
        assert_abs_diff_eq!(s1, 22000.0 / 24.0, epsilon = 1e-12);
        for knot in &k[2..=22] {
            assert_eq!(knot.z, 100.0);
        }
    }

    #[test]
    fn speed_within_1_to_6_knots_during_search() {
        for seed in SEEDS {
            let m = mission(seed);
            let (s0, s1) = m.search_interval();
            let (mut lo, mut hi) = (f64::MAX, 0.0_f64);
            for t in uniform_grid(s0, s1, 1.0) {
                let v = mps_to_knots(m.trajectory().state_at(t).unwrap().vel_in_nav.norm());
                lo = lo.min(v);
                hi = hi.max(v);
            }
            assert!(lo >= 1.0 && hi <= 6.0, "seed {seed}: {lo}..{hi} kt");
            // The speeds do vary over the band (not a constant-speed mission).
            assert!(hi - lo > 2.0, "seed {seed}: {lo}..{hi} kt");
        }
    }

    #[test]
    fn depth_is_exactly_constant_during_search() {
        for seed in SEEDS {
            let m = mission(seed);
            let (s0, s1) = m.search_interval();
            for t in uniform_grid(s0, s1, 1.0) {
                let s = m.trajectory().state_at(t).unwrap();
                assert_abs_diff_eq!(s.pos_in_nav.z, 100.0, epsilon = 1e-9);
                assert_abs_diff_eq!(s.vel_in_nav.z, 0.0, epsilon = 1e-9);
            }
            // Outside the search the vehicle dives from / returns to the surface.
            let tr = m.trajectory();
            assert_eq!(tr.state_at(0.0).unwrap().pos_in_nav, Vector3::zeros());
            assert_abs_diff_eq!(
                tr.state_at(1000.0).unwrap().pos_in_nav.z,
                0.0,
                epsilon = 1e-9
            );
            assert!(tr.state_at(40.0).unwrap().pos_in_nav.z > 50.0);
        }
    }

    #[test]
    fn ten_course_changes_one_near_440_s() {
        for seed in SEEDS {
            let m = mission(seed);
            // Whole mission sampled at 1 s (1001 samples).
            assert_eq!(uniform_grid(0.0, 1000.0, 1.0).len(), 1001);
            let cc =
                detect_course_changes(m.trajectory(), 0.0, 1000.0, 1.0, deg_to_rad(45.0)).unwrap();
            assert_eq!(cc.len(), 10, "seed {seed}: {cc:?}");
            let (s0, s1) = m.search_interval();
            assert!(cc.iter().all(|&t| t > s0 && t < s1), "seed {seed}: {cc:?}");
            let near: Vec<_> = cc.iter().filter(|&&t| (t - 440.0).abs() <= 7.0).collect();
            assert_eq!(near.len(), 1, "seed {seed}: {cc:?}");
            assert_eq!(m.course_changes().len(), 10);
        }
    }

    #[test]
    fn deterministic_per_seed() {
        let a = mission(5);
        let b = mission(5);
        assert_eq!(a.knots(), b.knots());
        let c = mission(6);
        assert_ne!(a.knots(), c.knots());
        assert_eq!(a.nominal_knots(), c.nominal_knots());
        // Perturbation is horizontal only and small.
        for (p, q) in a.knots().iter().zip(a.nominal_knots()) {
            assert_eq!(p.z, q.z);
            assert!((p - q).norm() < 6.0);
        }
    }

    #[test]
    fn zero_sigma_gives_nominal_pattern() {
        let params = FusionMissionParams {
            perturbation_sigma: 0.0,
            ..Default::default()
        }
        .check()
        .unwrap();
        let m = generate_fusion_mission(&params, &mut ChaCha8Rng::seed_from_u64(3)).unwrap();
        assert_eq!(m.knots(), m.nominal_knots());
    }

    #[test]
    fn large_perturbation_is_reported_not_hidden() {
        let params = FusionMissionParams {
            perturbation_sigma: 40.0,
            ..Default::default()
        }
        .check()
        .unwrap();
        let failures = (0..5)
            .filter(|&s| {
                generate_fusion_mission(&params, &mut ChaCha8Rng::seed_from_u64(s)).is_err()
            })
            .count();
        assert!(failures > 0);
    }

    #[test]
    fn detector_counts_an_s_curve_and_ignores_a_gentle_bend() {
        // North, U-turn east to south, U-turn back to north, then a 20 deg bend.
        let t = [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0];
        let pts = [
            Vector3::new(0.0, 0.0, 5.0),
            Vector3::new(20.0, 0.0, 5.0),
            Vector3::new(20.0, 10.0, 5.0),
            Vector3::new(0.0, 10.0, 5.0),
            Vector3::new(0.0, 20.0, 5.0),
            Vector3::new(20.0, 20.0, 5.0),
            Vector3::new(40.0, 20.0, 5.0),
            Vector3::new(60.0, 27.0, 5.0),
        ];
        let tr = SplineTrajectory::new(CubicSpline3::new(&t, &pts).unwrap());
        let cc = detect_course_changes(&tr, 0.0, 70.0, 0.1, deg_to_rad(45.0)).unwrap();
        assert_eq!(cc.len(), 2, "{cc:?}");
        assert!(
            (cc[0] - 15.0).abs() < 3.0 && (cc[1] - 35.0).abs() < 3.0,
            "{cc:?}"
        );
        // A low threshold also picks up the bend.
        let cc = detect_course_changes(&tr, 0.0, 70.0, 0.1, deg_to_rad(10.0)).unwrap();
        assert_eq!(cc.len(), 3, "{cc:?}");
    }

    #[test]
    fn detector_errors() {
        let m = mission(1);
        let tr = m.trajectory();
        assert!(detect_course_changes(tr, 0.0, 10.0, 0.0, 1.0).is_err());
        assert!(detect_course_changes(tr, 0.0, 10.0, 1.0, f64::NAN).is_err());
        assert!(detect_course_changes(tr, 10.0, 0.0, 1.0, 1.0).is_err());
        assert!(matches!(
            detect_course_changes(tr, 0.0, 1001.0, 1.0, 1.0),
            Err(TrajError::OutOfRange { .. })
        ));
    }

    #[test]
    fn params_check() {
        let ok = FusionMissionParams::default();
        assert!(ok.check().is_ok());
        let bad = |f: fn(&mut FusionMissionParams)| {
            let mut p = FusionMissionParams::default();
            f(&mut p);
            p.check().unwrap_err()
        };
        assert!(matches!(bad(|p| p.duration = 0.0), TrajError::Core(_)));
        assert!(matches!(
            bad(|p| p.search_depth = f64::NAN),
            TrajError::Core(_)
        ));
        assert!(matches!(
            bad(|p| p.perturbation_sigma = -1.0),
            TrajError::Core(_)
        ));
        assert!(matches!(
            bad(|p| p.n_knots = 24),
            TrajError::InvalidParameter { field, .. } if field == "n_knots"
        ));
        assert!(matches!(
            bad(|p| p.min_speed = p.max_speed),
            TrajError::InvalidParameter { field, .. } if field == "min_speed"
        ));
        assert!(matches!(
            bad(|p| p.leg_speeds.pop().map(|_| ()).unwrap_or(())),
            TrajError::InvalidParameter { field, .. } if field == "leg_speeds"
        ));
        assert!(matches!(
            bad(|p| p.leg_speeds[3] = 10.0),
            TrajError::InvalidParameter { field, .. } if field == "leg_speeds"
        ));
        assert!(matches!(
            bad(|p| p.min_course_change = 4.0),
            TrajError::InvalidParameter { field, .. } if field == "min_course_change"
        ));
        assert!(matches!(
            bad(|p| p.n_course_changes = 0),
            TrajError::InvalidParameter { field, .. } if field == "n_course_changes"
        ));
    }

    #[test]
    fn other_pattern_sizes_work() {
        let params = FusionMissionParams {
            n_course_changes: 4,
            n_knots: 13,
            duration: 520.0,
            leg_speeds: vec![knots_to_mps(3.0); 5],
            ..Default::default()
        }
        .check()
        .unwrap();
        let m = generate_fusion_mission(&params, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        assert_eq!(m.course_changes().len(), 4);
        assert_eq!(m.knots().len(), 13);
    }
}
