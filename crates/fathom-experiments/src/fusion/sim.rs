//! One Monte Carlo run of the `fusion` experiment: the INS and DVL integrators on
//! the fixed mission, and every fusion method on the same noise realization.
//!
//! # Common random numbers
//! A run draws two seeds, one for the INS and one for the DVL. Every method that
//! needs its own INS (the feedback variants reset it) rebuilds it from the same INS
//! seed, so all methods see the same accelerometer bias, the same noise samples, the
//! same DVL scale factors and velocity noise: the differences between methods are
//! paired, and the comparison between them is far sharper than their spreads.
//!
//! # Feedback
//! The EFF feedback reaches the INS through [`InsFeedback`], a small adapter that
//! implements the estimators' [`FeedbackSink`] for the sensors'
//! [`InsIntegrator`] (reset of position and velocity); the estimator crate never
//! sees the sensor crate.

use fathom_core::{Gaussian, Time};
use fathom_estimators::architectures::{
    ArchitectureError, EffSwitches, Equalization, EqualizeFuseFeedback, FeedbackSink, FusionRule,
    MeasurementFusion, NoFeedback, SensorBlock, TrackModel, TrackToTrack, cv_layout_3d,
};
use fathom_sensors::{
    SensorError,
    integrated::{DvlDeadReckoning, DvlDrConfig, InsConfig, InsIntegrator},
};
use fathom_stats::{RunStats, error_series::distance_2d, error_series::distance_3d};
use fathom_traj::{SplineTrajectory, Trajectory};
use nalgebra::{DMatrix, SMatrix, Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use fathom_sim::SimError;

/// The compared methods (filters, ablations, extra fusion rules and the two raw
/// sensors as references).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// Measurement fusion: one KF on `[z_INS; z_DVL]`.
    Mf,
    /// Track-to-track fusion with eq. (10).
    T2t,
    /// The proposed equalize-fuse-feedback filter.
    Eff,
    /// EFF without step 4 (feedback).
    EffNoFeedback,
    /// EFF without step 1 (= T2T + feedback).
    EffNoEqualization,
    /// Track-to-track with Bar-Shalom–Campo fusion.
    T2tBc,
    /// Track-to-track with covariance intersection.
    T2tCi,
    /// The unaided INS integrator (no filter).
    InsOnly,
    /// The DVL dead reckoning (no filter).
    DvlDr,
}

impl Method {
    /// Every method, in table order.
    pub const ALL: [Method; 9] = [
        Method::Mf,
        Method::T2t,
        Method::Eff,
        Method::EffNoFeedback,
        Method::EffNoEqualization,
        Method::T2tBc,
        Method::T2tCi,
        Method::InsOnly,
        Method::DvlDr,
    ];

    /// Name in tables and `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Mf => "MF",
            Method::T2t => "T2T",
            Method::Eff => "EFF",
            Method::EffNoFeedback => "EFF-no-feedback",
            Method::EffNoEqualization => "EFF-no-equalization",
            Method::T2tBc => "T2T-BC",
            Method::T2tCi => "T2T-CI",
            Method::InsOnly => "INS-only",
            Method::DvlDr => "DVL-DR",
        }
    }

    /// File-name slug.
    pub fn slug(self) -> &'static str {
        match self {
            Method::Mf => "mf",
            Method::T2t => "t2t",
            Method::Eff => "eff",
            Method::EffNoFeedback => "eff_no_feedback",
            Method::EffNoEqualization => "eff_no_equalization",
            Method::T2tBc => "t2t_bc",
            Method::T2tCi => "t2t_ci",
            Method::InsOnly => "ins_only",
            Method::DvlDr => "dvl_dr",
        }
    }

    /// Index in [`Method::ALL`].
    pub fn index(self) -> usize {
        Method::ALL.iter().position(|&m| m == self).unwrap_or(0)
    }
}

/// How the paper's printed tuning letters `w` and `v` are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reading {
    /// The notation of the paper's references (Bar-Shalom; Li and Jilkov): `v` is the
    /// process noise (white acceleration std, m/s^2, discrete white-noise-acceleration
    /// `Q`) and `w` the measurement noise (position std, m). Every printed unit is
    /// consistent.
    BarShalom,
    /// The letters as in Welch and Bishop: `Q = w^2 I6`, `R = v^2 I3`, which needs two
    /// unit repairs (m/s^2 read as m in `R`; a metre std on the velocity states).
    AsPrinted,
}

impl Reading {
    /// The scenario spelling (`bar_shalom`, `as_printed`).
    pub fn name(self) -> &'static str {
        match self {
            Reading::BarShalom => "bar_shalom",
            Reading::AsPrinted => "as_printed",
        }
    }

    /// The other reading.
    pub fn other(self) -> Reading {
        match self {
            Reading::BarShalom => Reading::AsPrinted,
            Reading::AsPrinted => Reading::BarShalom,
        }
    }
}

/// Filter tuning (the paper's `w`, `v` under a [`Reading`]) and the initial covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilterTuning {
    /// How `w` and `v` are read.
    pub reading: Reading,
    /// The paper's `w_INS` (10): INS position std, m (`bar_shalom`), or process
    /// noise scale, m (`as_printed`).
    pub w_ins: f64,
    /// The paper's `w_DVL` (1), read like `w_ins`.
    pub w_dvl: f64,
    /// The paper's `v_INS` (9.8, "1 g"): INS-filter acceleration std, m/s^2
    /// (`bar_shalom`), or INS position std, m (`as_printed`).
    pub v_ins: f64,
    /// The paper's `v_DVL` (0.02), read like `v_ins`.
    pub v_dvl: f64,
    /// Process noise scale of the MF filter under `as_printed`, m (setting).
    pub w_mf: f64,
    /// Acceleration std of the MF filter under `bar_shalom`, m/s^2 (setting).
    pub mf_accel_sigma: f64,
    /// Initial position std of every filter, m.
    pub p0_pos: f64,
    /// Initial velocity std of every filter, m/s.
    pub p0_vel: f64,
}

/// Everything one run needs (checked).
#[derive(Debug, Clone)]
pub struct RunConfig {
    /// Filter and sensor step, s (paper: 1).
    pub step: f64,
    /// Number of steps (`duration / step`).
    pub n_steps: usize,
    /// INS parameters.
    pub ins: InsConfig,
    /// DVL dead-reckoning parameters.
    pub dvl: DvlDrConfig,
    /// Filter tuning.
    pub tuning: FilterTuning,
}

/// Per-time errors of one run.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunOutput {
    /// Evaluation times `k step`, `k = 1..=n_steps`, s.
    pub times: Vec<Time>,
    /// 3D distance error per method (index of [`Method::ALL`]); empty for a method
    /// not computed.
    pub err_3d: Vec<Vec<f64>>,
    /// 2D (x-y) distance error per method.
    pub err_2d: Vec<Vec<f64>>,
    /// Position error of the INS integrator under EFF feedback, before each reset
    /// (i.e. the error of the INS measurement the EFF filter sees), m.
    pub ins_err_with_feedback: Vec<f64>,
    /// Estimated positions per method (only when asked for), NED, m.
    pub paths: Option<Vec<Vec<Vector3<f64>>>>,
    /// True positions (only when paths are asked for), NED, m.
    pub true_path: Option<Vec<Vector3<f64>>>,
}

/// Per-run statistics of one method.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MethodMetrics {
    /// Mean 3D error over time, m.
    pub mean_3d: f64,
    /// Std (population) of the 3D error over time, m.
    pub std_3d: f64,
    /// Mean 2D error, m.
    pub mean_2d: f64,
    /// Std of the 2D error, m.
    pub std_2d: f64,
    /// Largest 3D error, m.
    pub max_3d: f64,
    /// Mean 3D error within the course-change windows over the mean elsewhere.
    pub turn_ratio_3d: f64,
    /// Mean 3D error at the end of the run (last 10 % of the samples), m.
    pub final_3d: f64,
}

/// `[x, vx, y, vy, z, vz]` from position and velocity.
pub fn to_state(pos: &Vector3<f64>, vel: &Vector3<f64>) -> Vector6<f64> {
    Vector6::new(pos.x, vel.x, pos.y, vel.y, pos.z, vel.z)
}

/// Position part of a paper-layout state.
pub fn pos_of(x: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(x[0], x[2], x[4])
}

/// Velocity part of a paper-layout state.
pub fn vel_of(x: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(x[1], x[3], x[5])
}

/// The narrow feedback adapter: the EFF fused state resets the INS integrator's
/// position and velocity (bias and the latest acceleration sample are kept).
pub struct InsFeedback<'a>(pub &'a mut InsIntegrator);

impl FeedbackSink<6> for InsFeedback<'_> {
    type Error = SensorError;

    fn feed_back(&mut self, _time: Time, fused: &Gaussian<6>) -> Result<(), SensorError> {
        self.0.reset(pos_of(fused.mean()), vel_of(fused.mean()))
    }
}

fn arch(context: &'static str) -> impl Fn(ArchitectureError) -> SimError {
    move |e| SimError::model(context, e)
}

fn sensor(context: &'static str) -> impl Fn(SensorError) -> SimError {
    move |e| SimError::model(context, e)
}

/// Open-loop sensor outputs at `k = 0..=n_steps`.
struct OpenLoop {
    ins_state: Vec<Vector6<f64>>,
    dvl_state: Vec<Vector6<f64>>,
    truth: Vec<Vector3<f64>>,
}

fn open_loop(
    cfg: &RunConfig,
    traj: &SplineTrajectory,
    ins_seed: u64,
    dvl_seed: u64,
) -> Result<OpenLoop, SimError> {
    let t0 = traj.start_time();
    let mut ins_rng = ChaCha8Rng::seed_from_u64(ins_seed);
    let mut dvl_rng = ChaCha8Rng::seed_from_u64(dvl_seed);
    let mut ins =
        InsIntegrator::start(&cfg.ins, traj, t0, &mut ins_rng).map_err(sensor("INS start"))?;
    let mut dvl =
        DvlDeadReckoning::start(&cfg.dvl, traj, t0, &mut dvl_rng).map_err(sensor("DVL start"))?;
    let n = cfg.n_steps + 1;
    let mut out = OpenLoop {
        ins_state: Vec::with_capacity(n),
        dvl_state: Vec::with_capacity(n),
        truth: Vec::with_capacity(n),
    };
    let st0 = traj.state_at(t0).map_err(|e| SimError::model("truth", e))?;
    out.ins_state
        .push(to_state(&ins.pos_in_nav(), &ins.vel_in_nav()));
    out.dvl_state
        .push(to_state(&dvl.pos_in_nav(), &dvl.vel_meas_in_nav()));
    out.truth.push(st0.pos_in_nav);
    for _ in 0..cfg.n_steps {
        let mi = ins
            .step(traj, cfg.step, &mut ins_rng)
            .map_err(sensor("INS step"))?;
        let md = dvl
            .step(traj, cfg.step, &mut dvl_rng)
            .map_err(sensor("DVL step"))?;
        out.ins_state
            .push(to_state(&ins.pos_in_nav(), &ins.vel_in_nav()));
        out.dvl_state
            .push(to_state(&dvl.pos_in_nav(), &dvl.vel_meas_in_nav()));
        out.truth.push(mi.true_value);
        debug_assert_eq!(mi.true_value, md.true_value);
    }
    Ok(out)
}

fn prior(cfg: &RunConfig, traj: &SplineTrajectory) -> Result<Gaussian<6>, SimError> {
    let st = traj
        .state_at(traj.start_time())
        .map_err(|e| SimError::model("truth", e))?;
    let (sp, sv) = (cfg.tuning.p0_pos.powi(2), cfg.tuning.p0_vel.powi(2));
    let p0 = SMatrix::<f64, 6, 6>::from_diagonal(&Vector6::new(sp, sv, sp, sv, sp, sv));
    Gaussian::new(to_state(&st.pos_in_nav, &st.vel_in_nav), p0)
        .map_err(|e| SimError::model("filter prior", e))
}

/// The INS and DVL track models under the tuning's reading.
fn models(cfg: &RunConfig) -> Result<(TrackModel<6, 3>, TrackModel<6, 3>), SimError> {
    let t = &cfg.tuning;
    let track = |w: f64, v: f64| match t.reading {
        Reading::BarShalom => TrackModel::cv_position_3d_dwna(cfg.step, v, w),
        Reading::AsPrinted => TrackModel::cv_position_3d(cfg.step, w, v),
    };
    Ok((
        track(t.w_ins, t.v_ins).map_err(arch("INS track model"))?,
        track(t.w_dvl, t.v_dvl).map_err(arch("DVL track model"))?,
    ))
}

/// The MF filter's process noise under the tuning's reading.
fn mf_process_noise(cfg: &RunConfig) -> Result<SMatrix<f64, 6, 6>, SimError> {
    let t = &cfg.tuning;
    match t.reading {
        Reading::BarShalom => {
            fathom_estimators::models::cv_discrete_white_accel_q_3d(cfg.step, t.mf_accel_sigma)
        }
        Reading::AsPrinted => fathom_estimators::models::cv_scaled_identity_q_3d(t.w_mf),
    }
    .map_err(|e| SimError::model("MF process noise", e))
}

fn tracks(
    cfg: &RunConfig,
    traj: &SplineTrajectory,
    rule: FusionRule<6>,
) -> Result<TrackToTrack<6, 3, 3>, SimError> {
    let (mi, md) = models(cfg)?;
    let p = prior(cfg, traj)?;
    // Both tracks start from the true initial state: their initial errors are zero,
    // so any initial cross-covariance is consistent; zero keeps BC well defined.
    TrackToTrack::new(
        p.clone(),
        p,
        SMatrix::zeros(),
        traj.start_time(),
        mi,
        md,
        rule,
    )
    .map_err(arch("track-to-track"))
}

fn equalization(cfg: &RunConfig) -> Result<Equalization<6>, SimError> {
    let (mi, md) = models(cfg)?;
    Equalization::from_measurement_noise(mi.r(), md.r(), &cv_layout_3d())
        .map_err(arch("equalization"))
}

/// Runs the methods in `methods` on one noise realization (seeds drawn from `rng`:
/// INS seed, then DVL seed). `keep_paths` keeps the estimated positions.
///
/// # Errors
/// [`SimError::Model`] naming the failing sensor, filter or fusion step.
pub fn simulate_run(
    cfg: &RunConfig,
    traj: &SplineTrajectory,
    methods: &[Method],
    keep_paths: bool,
    rng: &mut impl Rng,
) -> Result<RunOutput, SimError> {
    let ins_seed: u64 = rng.random();
    let dvl_seed: u64 = rng.random();
    let ol = open_loop(cfg, traj, ins_seed, dvl_seed)?;
    let t0 = traj.start_time();
    let n = cfg.n_steps;
    let times: Vec<Time> = (1..=n).map(|k| t0 + k as f64 * cfg.step).collect();
    let pos_ins = |k: usize| pos_of(&ol.ins_state[k]);
    let pos_dvl = |k: usize| pos_of(&ol.dvl_state[k]);
    let mut paths: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); Method::ALL.len()];
    let mut ins_err_with_feedback = Vec::new();
    for &m in methods {
        let mut est = Vec::with_capacity(n);
        match m {
            Method::InsOnly => est.extend((1..=n).map(pos_ins)),
            Method::DvlDr => est.extend((1..=n).map(pos_dvl)),
            Method::Mf => {
                let h = DMatrix::from_fn(3, 6, |r, c| if c == 2 * r { 1.0 } else { 0.0 });
                // The sensors' R are those of their tracks (the reading decides them).
                let (mi, md) = models(cfg)?;
                let r_of = |m: &TrackModel<6, 3>| DMatrix::from_fn(3, 3, |i, j| m.r()[(i, j)]);
                let blocks = [
                    SensorBlock {
                        name: "INS".into(),
                        h: h.clone(),
                        r: r_of(&mi),
                    },
                    SensorBlock {
                        name: "DVL".into(),
                        h,
                        r: r_of(&md),
                    },
                ];
                let q = mf_process_noise(cfg)?;
                let mut mf =
                    MeasurementFusion::<6, 6>::new(prior(cfg, traj)?, t0, *mi.f(), q, &blocks)
                        .map_err(arch("measurement fusion"))?;
                for k in 1..=n {
                    let (zi, zd) = (pos_ins(k), pos_dvl(k));
                    let g = mf
                        .step(times[k - 1], &[zi.as_slice(), zd.as_slice()])
                        .map_err(arch("measurement fusion"))?;
                    est.push(pos_of(g.mean()));
                }
            }
            Method::T2t | Method::T2tBc | Method::T2tCi => {
                let rule = match m {
                    Method::T2t => FusionRule::Independent,
                    Method::T2tCi => FusionRule::CovarianceIntersection,
                    _ => {
                        let (mi, md) = models(cfg)?;
                        FusionRule::bar_shalom_campo_common_noise(mi.q(), md.q())
                    }
                };
                let mut t2t = tracks(cfg, traj, rule)?;
                for k in 1..=n {
                    let g = t2t
                        .step(times[k - 1], &pos_ins(k), &pos_dvl(k))
                        .map_err(arch("track-to-track"))?;
                    est.push(pos_of(g.mean()));
                }
            }
            Method::EffNoFeedback => {
                let mut eff = EqualizeFuseFeedback::new(
                    tracks(cfg, traj, FusionRule::Independent)?,
                    equalization(cfg)?,
                    EffSwitches::NO_FEEDBACK,
                );
                for k in 1..=n {
                    let out = eff
                        .step(
                            times[k - 1],
                            &ol.ins_state[k - 1],
                            &ol.dvl_state[k - 1],
                            &pos_ins(k),
                            &pos_dvl(k),
                            &mut NoFeedback,
                        )
                        .map_err(arch("EFF"))?;
                    est.push(pos_of(out.fused.mean()));
                }
            }
            Method::Eff | Method::EffNoEqualization => {
                let switches = if m == Method::Eff {
                    EffSwitches::FULL
                } else {
                    EffSwitches::NO_EQUALIZATION
                };
                let mut eff = EqualizeFuseFeedback::new(
                    tracks(cfg, traj, FusionRule::Independent)?,
                    equalization(cfg)?,
                    switches,
                );
                // A fresh INS on the same noise (same seed), reset by the feedback.
                let mut ins_rng = ChaCha8Rng::seed_from_u64(ins_seed);
                let mut ins = InsIntegrator::start(&cfg.ins, traj, t0, &mut ins_rng)
                    .map_err(sensor("INS start"))?;
                for k in 1..=n {
                    let ins_prev = to_state(&ins.pos_in_nav(), &ins.vel_in_nav());
                    let zi = ins
                        .step(traj, cfg.step, &mut ins_rng)
                        .map_err(sensor("INS step"))?;
                    if m == Method::Eff {
                        ins_err_with_feedback.push(distance_3d(&zi.value, &zi.true_value));
                    }
                    let out = eff
                        .step(
                            times[k - 1],
                            &ins_prev,
                            &ol.dvl_state[k - 1],
                            &zi.value,
                            &pos_dvl(k),
                            &mut InsFeedback(&mut ins),
                        )
                        .map_err(arch("EFF"))?;
                    est.push(pos_of(out.fused.mean()));
                }
            }
        }
        paths[m.index()] = est;
    }
    let truth = &ol.truth[1..];
    let err = |f: fn(&Vector3<f64>, &Vector3<f64>) -> f64| -> Vec<Vec<f64>> {
        paths
            .iter()
            .map(|p| p.iter().zip(truth).map(|(e, t)| f(e, t)).collect())
            .collect()
    };
    let err_3d = err(distance_3d);
    let err_2d = err(distance_2d);
    Ok(RunOutput {
        times,
        err_3d,
        err_2d,
        ins_err_with_feedback,
        true_path: keep_paths.then(|| truth.to_vec()),
        paths: keep_paths.then_some(paths),
    })
}

/// Whether `t` lies within `half_window` of a course change.
pub fn near_turn(t: Time, course_changes: &[Time], half_window: f64) -> bool {
    course_changes.iter().any(|c| (t - c).abs() <= half_window)
}

/// Per-run statistics of one method's error series (`times` as in [`RunOutput`]).
///
/// # Errors
/// [`SimError::Model`] for an empty or non-finite series, or no samples inside /
/// outside the course-change windows.
pub fn method_metrics(
    times: &[Time],
    err_3d: &[f64],
    err_2d: &[f64],
    course_changes: &[Time],
    half_window: f64,
) -> Result<MethodMetrics, SimError> {
    let s3 = RunStats::of(err_3d).map_err(|e| SimError::model("3D error statistics", e))?;
    let s2 = RunStats::of(err_2d).map_err(|e| SimError::model("2D error statistics", e))?;
    let (mut sum_in, mut n_in, mut sum_out, mut n_out) = (0.0, 0usize, 0.0, 0usize);
    for (&t, &e) in times.iter().zip(err_3d) {
        if near_turn(t, course_changes, half_window) {
            sum_in += e;
            n_in += 1;
        } else {
            sum_out += e;
            n_out += 1;
        }
    }
    if n_in == 0 || n_out == 0 || sum_out <= 0.0 {
        return Err(SimError::invalid_argument(
            "turn ratio",
            format!("{n_in} samples near course changes, {n_out} elsewhere (need both)"),
        ));
    }
    let tail = (err_3d.len() / 10).max(1);
    let final_3d = err_3d[err_3d.len() - tail..].iter().sum::<f64>() / tail as f64;
    Ok(MethodMetrics {
        mean_3d: s3.mean,
        std_3d: s3.std,
        mean_2d: s2.mean,
        std_2d: s2.std,
        max_3d: s3.max,
        turn_ratio_3d: (sum_in / n_in as f64) / (sum_out / n_out as f64),
        final_3d,
    })
}
