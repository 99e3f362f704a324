//! The sensor suite of the beacons paper (B): DVL, AHRS rate, ranges to `K`
//! beacons and depth, with synchronous or asynchronous jittered timing, white
//! Gaussian noise, held common-mode range noise and outliers.
//!
//! # Noise model (eq. 4)
//! Range `k` at sample `i`: `r = |B_k - p(t_i)| + n_r + n_c(t_i) + o_i`, with
//! `n_r ~ N(0, sigma_r^2)` white, `n_c` the common-mode value of the interval
//! `[m t_gap, (m+1) t_gap)` containing `t_i` (shared by all beacons; see
//! [`HeldCommonMode`]) and `o_i = +-sigma_o` on the `N` samples chosen as
//! outliers (uniformly among all range samples of all beacons), 0 elsewhere. Depth
//! gets white noise only. The switches zero a contribution without changing the
//! random draws, so the cases of the `noise` experiment run with common random
//! numbers.
//!
//! # RNG draw order (fixed; same seed and config give bit-identical data)
//! 1. Sample times. Synchronous: one clock for everything. Asynchronous: clocks in
//!    the order DVL, AHRS, range 0..K-1, depth. (Per clock see
//!    [`crate::schedule`]: step jitters, then stamp jitters.)
//! 2. Common-mode values over `[0, t_end]`, one per interval (always drawn).
//! 3. DVL measurements in time order, 3 normals each (u, v, w).
//! 4. AHRS rate measurements in time order, 3 normals each (p, q, r).
//! 5. Ranges: beacon 0 all samples in time order, then beacon 1, ...; 1 normal each.
//! 6. Depth in time order, 1 normal each.
//! 7. Outliers, only when switched on and `N > 0`:
//!    `rand::seq::index::sample` over the flattened range list (beacon-major),
//!    then one sign `bool` per chosen sample.

use fathom_core::Measurement;
use fathom_traj::Trajectory;
use nalgebra::{DMatrix, Vector3};
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::{
    SensorError,
    error::{check_positive, check_sigma},
    models::{
        AhrsRate, AhrsRateParams, DepthParams, DepthSensor, Dvl, DvlParams, RangeParams,
        RangeSensor, SensorModel, default_beacons_in_nav,
    },
    noise::{HeldCommonMode, OutlierInjector, OutlierParams},
    schedule::{Clock, ClockParams, DEFAULT_JITTER_SIGMA, SampleTimes},
};

/// Sensor timing (Tables 2-3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Timing {
    /// All sensors share one clock and therefore the same jittered sample instants.
    Synchronous {
        /// Common period, s (paper: 0.1).
        period: f64,
    },
    /// Each sensor has its own clock with independent jitter (each range sensor too).
    Asynchronous {
        /// DVL period, s (Table 3: 0.20).
        dvl: f64,
        /// AHRS period, s (Table 3: 0.01).
        ahrs: f64,
        /// Period of every range sensor, s (Table 3: 0.10).
        range: f64,
        /// Depth period, s (Table 3: 0.02).
        depth: f64,
    },
}

impl Timing {
    /// Synchronous timing with the paper's 0.1 s period.
    pub fn paper_sync() -> Self {
        Self::Synchronous { period: 0.1 }
    }

    /// Asynchronous timing with the periods of Table 3.
    pub fn paper_async() -> Self {
        Self::Asynchronous {
            dvl: 0.20,
            ahrs: 0.01,
            range: 0.10,
            depth: 0.02,
        }
    }
}

/// Which noise kinds are on. Off zeroes the contribution; the draws still happen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct NoiseSwitches {
    /// White Gaussian noise on every sensor (DVL, AHRS, ranges, depth).
    pub gaussian: bool,
    /// Held common-mode noise on the ranges.
    pub correlation: bool,
    /// Outliers on the ranges.
    pub outliers: bool,
}

impl Default for NoiseSwitches {
    fn default() -> Self {
        Self {
            gaussian: true,
            correlation: true,
            outliers: true,
        }
    }
}

/// Unchecked parameters of the beacons-paper sensor suite. `Default` is the
/// paper's main case: asynchronous timing, all noises on, high correlation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BeaconSuiteParams {
    /// Timing mode and periods. Default [`Timing::paper_async`].
    pub timing: Timing,
    /// Sample-time jitter sigma_t, s (same for every clock). Default 1e-3.
    pub jitter_sigma: f64,
    /// Constant time-stamp error, s. Default 0.
    pub stamp_offset: f64,
    /// White time-stamp error sigma, s. Default 0.
    pub stamp_jitter_sigma: f64,
    /// Velocity-sensor sigmas `(u, v, w, p, q, r)`: DVL then AHRS rate. Default
    /// `(0.1, 0, 0.1, 0, 0, 0.1)` (Table 10).
    pub velocity_sigma: [f64; 6],
    /// Range white-noise sigma_r, m. Default 0.1.
    pub range_sigma: f64,
    /// Depth white-noise sigma_d, m. Default 0.2.
    pub depth_sigma: f64,
    /// Common-mode sigma_c, m (0 = none). Default 0.2 (high); low is 0.05.
    pub corr_sigma: f64,
    /// Common-mode hold interval t_gap, s. Default 1.
    pub t_gap: f64,
    /// Outlier count N and magnitude sigma_o. Default 276 and 1 m.
    pub outliers: OutlierParams,
    /// Noise on/off switches. Default all on.
    pub switches: NoiseSwitches,
    /// Beacon positions, NED, m (at least one). Default
    /// [`crate::models::DEFAULT_BEACONS_IN_NAV`].
    pub beacons_in_nav: Vec<Vector3<f64>>,
}

impl Default for BeaconSuiteParams {
    fn default() -> Self {
        Self {
            timing: Timing::paper_async(),
            jitter_sigma: DEFAULT_JITTER_SIGMA,
            stamp_offset: 0.0,
            stamp_jitter_sigma: 0.0,
            velocity_sigma: [0.1, 0.0, 0.1, 0.0, 0.0, 0.1],
            range_sigma: 0.1,
            depth_sigma: 0.2,
            corr_sigma: 0.2,
            t_gap: 1.0,
            outliers: OutlierParams::default(),
            switches: NoiseSwitches::default(),
            beacons_in_nav: default_beacons_in_nav(),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Clocks {
    Sync(Clock),
    Async {
        dvl: Clock,
        ahrs: Clock,
        ranges: Vec<Clock>,
        depth: Clock,
    },
}

/// Validated suite configuration (from [`BeaconSuiteParams::check`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BeaconSuiteConfig {
    params: BeaconSuiteParams,
    clocks: Clocks,
    dvl: Dvl,
    ahrs: AhrsRate,
    ranges: Vec<RangeSensor>,
    depth: DepthSensor,
    corr_sigma: f64,
    outliers: Option<OutlierInjector>,
}

impl BeaconSuiteParams {
    /// Validates the parameters. With `switches.gaussian` off every white sigma
    /// becomes 0; with `switches.correlation` off `sigma_c` becomes 0.
    ///
    /// # Errors
    /// [`SensorError::Empty`] without beacons; [`SensorError::InvalidParameter`] /
    /// [`SensorError::JitterTooLarge`] for bad periods, sigmas or positions.
    pub fn check(&self) -> Result<BeaconSuiteConfig, SensorError> {
        if self.beacons_in_nav.is_empty() {
            return Err(SensorError::Empty {
                what: "beacons_in_nav".into(),
            });
        }
        let clock = |name: &str, period: f64| {
            ClockParams {
                period,
                jitter_sigma: self.jitter_sigma,
                stamp_offset: self.stamp_offset,
                stamp_jitter_sigma: self.stamp_jitter_sigma,
            }
            .check(name)
        };
        let k = self.beacons_in_nav.len();
        let clocks = match self.timing {
            Timing::Synchronous { period } => Clocks::Sync(clock("sync", period)?),
            Timing::Asynchronous {
                dvl,
                ahrs,
                range,
                depth,
            } => Clocks::Async {
                dvl: clock("dvl", dvl)?,
                ahrs: clock("ahrs", ahrs)?,
                ranges: (0..k)
                    .map(|i| clock(&format!("range{}", i + 1), range))
                    .collect::<Result<_, _>>()?,
                depth: clock("depth", depth)?,
            },
        };
        for (i, s) in self.velocity_sigma.iter().enumerate() {
            check_sigma(&format!("velocity_sigma[{i}]"), *s)?;
        }
        check_sigma("range_sigma", self.range_sigma)?;
        check_sigma("depth_sigma", self.depth_sigma)?;
        let corr_sigma = check_sigma("corr_sigma", self.corr_sigma)?;
        check_positive("t_gap", self.t_gap)?;
        let gain = if self.switches.gaussian { 1.0 } else { 0.0 };
        let vs = self.velocity_sigma.map(|s| gain * s);
        let dvl = DvlParams {
            sigma: Vector3::new(vs[0], vs[1], vs[2]),
        }
        .check()?;
        let ahrs = AhrsRateParams {
            sigma: Vector3::new(vs[3], vs[4], vs[5]),
        }
        .check()?;
        let ranges = self
            .beacons_in_nav
            .iter()
            .enumerate()
            .map(|(i, b)| {
                RangeParams {
                    beacon_index: i,
                    beacon_in_nav: *b,
                    sigma: gain * self.range_sigma,
                }
                .check()
            })
            .collect::<Result<_, _>>()?;
        let depth = DepthParams {
            sigma: gain * self.depth_sigma,
        }
        .check()?;
        let injector = self.outliers.check()?;
        Ok(BeaconSuiteConfig {
            params: self.clone(),
            clocks,
            dvl,
            ahrs,
            ranges,
            depth,
            corr_sigma: if self.switches.correlation {
                corr_sigma
            } else {
                0.0
            },
            outliers: (self.switches.outliers && injector.count() > 0).then_some(injector),
        })
    }
}

impl BeaconSuiteConfig {
    /// The parameters this configuration was checked from.
    pub fn params(&self) -> &BeaconSuiteParams {
        &self.params
    }

    /// Number of beacons `K`.
    pub fn beacon_count(&self) -> usize {
        self.ranges.len()
    }

    /// Effective range white sigma (0 when Gaussian noise is off).
    pub fn range_sigma(&self) -> f64 {
        self.ranges[0].sigma()
    }

    /// Effective depth white sigma (0 when Gaussian noise is off).
    pub fn depth_sigma(&self) -> f64 {
        self.depth.sigma()
    }

    /// Effective common-mode sigma_c (0 when correlation is off).
    pub fn corr_sigma(&self) -> f64 {
        self.corr_sigma
    }

    /// Whether the timing is synchronous.
    pub fn is_synchronous(&self) -> bool {
        matches!(self.clocks, Clocks::Sync(_))
    }
}

/// One injected range outlier.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OutlierHit {
    /// Zero-based beacon index.
    pub beacon: usize,
    /// Index into that beacon's measurement list.
    pub sample: usize,
    /// The added constant, `+-sigma_o`.
    pub offset: f64,
}

/// Everything the suite measured in one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BeaconSuiteData {
    /// DVL body velocity.
    pub dvl: Vec<Measurement<Vector3<f64>>>,
    /// AHRS body angular rate.
    pub ahrs_rate: Vec<Measurement<Vector3<f64>>>,
    /// Ranges, one list per beacon.
    pub ranges: Vec<Vec<Measurement<f64>>>,
    /// Depth.
    pub depth: Vec<Measurement<f64>>,
    /// Injected outliers, sorted by (beacon, sample).
    pub outliers: Vec<OutlierHit>,
    /// The common-mode sequence used (zero values when correlation is off).
    pub common_mode: HeldCommonMode,
}

/// Simulates the suite over `[traj.start_time(), traj.end_time()]` (see the module
/// docs for the model and the RNG draw order).
///
/// # Errors
/// [`SensorError::BadInterval`] when the trajectory starts before 0 (the
/// common-mode intervals are anchored at t = 0); [`SensorError::TooManyOutliers`]
/// when `N` exceeds the number of range samples; [`SensorError::Traj`] when the
/// trajectory cannot be evaluated.
pub fn simulate_beacon_suite(
    traj: &impl Trajectory,
    config: &BeaconSuiteConfig,
    rng: &mut impl Rng,
) -> Result<BeaconSuiteData, SensorError> {
    let (t0, t_end) = (traj.start_time(), traj.end_time());
    if !(t0 >= 0.0 && t_end.is_finite() && t_end >= t0) {
        return Err(SensorError::BadInterval {
            what: "trajectory span (must start at t >= 0)".into(),
            start: t0,
            end: t_end,
        });
    }
    let k = config.ranges.len();
    // 1. sample times
    let (t_dvl, t_ahrs, t_ranges, t_depth): (_, _, Vec<SampleTimes>, _) = match &config.clocks {
        Clocks::Sync(c) => {
            let s = c.generate(t0, t_end, rng)?;
            (s.clone(), s.clone(), vec![s.clone(); k], s)
        }
        Clocks::Async {
            dvl,
            ahrs,
            ranges,
            depth,
        } => {
            let a = dvl.generate(t0, t_end, rng)?;
            let b = ahrs.generate(t0, t_end, rng)?;
            let r = ranges
                .iter()
                .map(|c| c.generate(t0, t_end, rng))
                .collect::<Result<_, _>>()?;
            let d = depth.generate(t0, t_end, rng)?;
            (a, b, r, d)
        }
    };
    // 2. common mode
    let common_mode = HeldCommonMode::generate(config.corr_sigma, config.params.t_gap, t_end, rng)?;
    // 3.-6. white-noise measurements
    let dvl = config.dvl.measure_all(traj, &t_dvl, rng)?;
    let ahrs_rate = config.ahrs.measure_all(traj, &t_ahrs, rng)?;
    let mut ranges = Vec::with_capacity(k);
    for (sensor, times) in config.ranges.iter().zip(&t_ranges) {
        let mut ms = sensor.measure_all(traj, times, rng)?;
        for m in &mut ms {
            m.value += common_mode.value_at(m.sample_time)?;
        }
        ranges.push(ms);
    }
    let depth = config.depth.measure_all(traj, &t_depth, rng)?;
    // 7. outliers
    let mut outliers = Vec::new();
    if let Some(inj) = &config.outliers {
        let total: usize = ranges.iter().map(Vec::len).sum();
        for o in inj.choose(total, rng)? {
            let (mut beacon, mut sample) = (0, o.index);
            while sample >= ranges[beacon].len() {
                sample -= ranges[beacon].len();
                beacon += 1;
            }
            ranges[beacon][sample].value += o.offset;
            outliers.push(OutlierHit {
                beacon,
                sample,
                offset: o.offset,
            });
        }
    }
    Ok(BeaconSuiteData {
        dvl,
        ahrs_rate,
        ranges,
        depth,
        outliers,
        common_mode,
    })
}

impl BeaconSuiteData {
    /// For synchronous data: one row per epoch holding the realized noises
    /// `value - true_value` of `[range_1, ..., range_K, depth]` (the vectors of the
    /// paper's eqs. 5-9), as an `n_epochs x (K+1)` matrix.
    ///
    /// # Errors
    /// [`SensorError::NotSynchronous`] when the range and depth lists differ in
    /// length or sample time at some epoch; [`SensorError::Empty`] without ranges.
    pub fn sync_noise_rows(&self) -> Result<DMatrix<f64>, SensorError> {
        if self.ranges.is_empty() {
            return Err(SensorError::Empty {
                what: "ranges".into(),
            });
        }
        let n = self.depth.len();
        let k = self.ranges.len();
        for (b, r) in self.ranges.iter().enumerate() {
            if r.len() != n {
                return Err(SensorError::NotSynchronous {
                    what: format!("range{} vs depth", b + 1),
                    index: r.len().min(n),
                    detail: format!("{} range samples, {} depth samples", r.len(), n),
                });
            }
        }
        let mut rows = DMatrix::zeros(n, k + 1);
        for i in 0..n {
            let t = self.depth[i].sample_time;
            for (b, r) in self.ranges.iter().enumerate() {
                if r[i].sample_time != t {
                    return Err(SensorError::NotSynchronous {
                        what: format!("range{} vs depth", b + 1),
                        index: i,
                        detail: format!("sample times {} s and {} s", r[i].sample_time, t),
                    });
                }
                rows[(i, b)] = r[i].noise();
            }
            rows[(i, k)] = self.depth[i].noise();
        }
        Ok(rows)
    }
}

/// Design covariance of `[range_1..range_K, depth]` noise (eqs. 5-9):
/// `diag(sigma_r^2 x K, sigma_d^2) + sigma_c^2 (ones(K, K) (+) 0)`, using the
/// effective sigmas (switches applied). Outliers are not included.
pub fn design_covariance(config: &BeaconSuiteConfig) -> DMatrix<f64> {
    let k = config.beacon_count();
    let (sr2, sd2, sc2) = (
        config.range_sigma().powi(2),
        config.depth_sigma().powi(2),
        config.corr_sigma().powi(2),
    );
    DMatrix::from_fn(k + 1, k + 1, |i, j| {
        if i == k || j == k {
            if i == j { sd2 } else { 0.0 }
        } else if i == j {
            sr2 + sc2
        } else {
            sc2
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::tests::{Helix, helix};
    use approx::assert_abs_diff_eq;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn sync_params(switches: NoiseSwitches) -> BeaconSuiteParams {
        BeaconSuiteParams {
            timing: Timing::paper_sync(),
            switches,
            ..Default::default()
        }
    }

    const ONLY_CORR: NoiseSwitches = NoiseSwitches {
        gaussian: false,
        correlation: true,
        outliers: false,
    };

    #[test]
    fn sync_correlation_only_ranges_share_the_common_value() {
        let cfg = sync_params(ONLY_CORR).check().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(30);
        let data = simulate_beacon_suite(&helix(), &cfg, &mut rng).unwrap();
        let rows = data.sync_noise_rows().unwrap();
        assert!(rows.nrows() > 1900);
        let mut distinct = 0;
        for i in 0..rows.nrows() {
            let t = data.depth[i].sample_time;
            let c = data.common_mode.value_at(t).unwrap();
            for b in 0..4 {
                assert_eq!(data.ranges[b][i].sample_time, t);
                // noise minus the common value is zero (up to the rounding of
                // adding c to the true range and subtracting the true range again)
                assert_abs_diff_eq!(rows[(i, b)] - c, 0.0, epsilon = 1e-12);
            }
            assert_eq!(rows[(i, 4)], 0.0);
            assert_eq!(data.dvl[i].sample_time, t);
            assert_eq!(data.ahrs_rate[i].value, data.ahrs_rate[i].true_value);
            if i > 0 && rows[(i, 0)] != rows[(i - 1, 0)] {
                distinct += 1;
            }
        }
        // changes at (almost) every 1 s boundary of a 200 s run
        assert!(distinct >= 190, "{distinct}");
        assert!(data.outliers.is_empty());
    }

    #[test]
    fn outliers_hit_exactly_n_range_samples() {
        let params = sync_params(NoiseSwitches {
            gaussian: false,
            correlation: false,
            outliers: true,
        });
        let cfg = params.check().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        let data = simulate_beacon_suite(&helix(), &cfg, &mut rng).unwrap();
        assert_eq!(data.outliers.len(), 276);
        let mut hit = 0;
        for (b, r) in data.ranges.iter().enumerate() {
            for (i, m) in r.iter().enumerate() {
                let n = m.noise();
                if n.abs() > 1e-9 {
                    hit += 1;
                    assert_abs_diff_eq!(n.abs(), 1.0, epsilon = 1e-12);
                    let o = data
                        .outliers
                        .iter()
                        .find(|o| o.beacon == b && o.sample == i)
                        .unwrap();
                    assert_abs_diff_eq!(n, o.offset, epsilon = 1e-12);
                }
            }
        }
        assert_eq!(hit, 276);
        assert!(data.depth.iter().all(|m| m.noise() == 0.0));
        // more outliers than samples is an error
        let too_many = BeaconSuiteParams {
            outliers: OutlierParams {
                count: 100_000,
                magnitude: 1.0,
            },
            ..params
        }
        .check()
        .unwrap();
        assert!(matches!(
            simulate_beacon_suite(&helix(), &too_many, &mut rng),
            Err(SensorError::TooManyOutliers { .. })
        ));
    }

    #[test]
    fn switches_keep_the_draws_common() {
        // Same seed, correlation on vs off: range noise differs by exactly the
        // common value, depth and DVL are identical (documented draw order).
        let on = sync_params(NoiseSwitches {
            outliers: false,
            ..Default::default()
        });
        let off = BeaconSuiteParams {
            switches: NoiseSwitches {
                correlation: false,
                outliers: false,
                gaussian: true,
            },
            ..on.clone()
        };
        let a = simulate_beacon_suite(
            &helix(),
            &on.check().unwrap(),
            &mut ChaCha8Rng::seed_from_u64(32),
        )
        .unwrap();
        let b = simulate_beacon_suite(
            &helix(),
            &off.check().unwrap(),
            &mut ChaCha8Rng::seed_from_u64(32),
        )
        .unwrap();
        assert_eq!(a.depth, b.depth);
        assert_eq!(a.dvl, b.dvl);
        for (ra, rb) in a.ranges[2].iter().zip(&b.ranges[2]) {
            let c = a.common_mode.value_at(ra.sample_time).unwrap();
            assert_abs_diff_eq!(ra.noise() - rb.noise(), c, epsilon = 1e-12);
        }
        // bit-identical with the same seed
        let a2 = simulate_beacon_suite(
            &helix(),
            &on.check().unwrap(),
            &mut ChaCha8Rng::seed_from_u64(32),
        )
        .unwrap();
        assert_eq!(a, a2);
    }

    #[test]
    fn async_timing_gives_independent_clocks() {
        let cfg = BeaconSuiteParams::default().check().unwrap();
        assert!(!cfg.is_synchronous());
        let mut rng = ChaCha8Rng::seed_from_u64(33);
        let data = simulate_beacon_suite(&helix(), &cfg, &mut rng).unwrap();
        // About T / period samples each: after n steps the clock has drifted by
        // N(0, n sigma_t^2), so the count deviates by ~ sqrt(n) sigma_t / period;
        // bound 4 of those plus 1 for the end effect.
        let near = |n: usize, period: f64| {
            let expect = 200.0 / period;
            (n as f64 - expect).abs() <= 1.0 + 4.0 * expect.sqrt() * 1e-3 / period
        };
        assert!(near(data.dvl.len(), 0.2));
        assert!(near(data.ahrs_rate.len(), 0.01));
        assert!(near(data.depth.len(), 0.02));
        assert!(!near(data.depth.len(), 0.01)); // control: wrong period rejected
        for r in &data.ranges {
            assert!(near(r.len(), 0.1));
            assert!(r.windows(2).all(|w| w[1].sample_time > w[0].sample_time));
        }
        assert_ne!(data.ranges[0][5].sample_time, data.ranges[1][5].sample_time);
        assert_eq!(data.outliers.len(), 276);
        assert!(matches!(
            data.sync_noise_rows(),
            Err(SensorError::NotSynchronous { .. })
        ));
    }

    #[test]
    fn design_covariance_entries() {
        let cfg = sync_params(NoiseSwitches::default()).check().unwrap();
        let d = design_covariance(&cfg);
        assert_eq!(d.shape(), (5, 5));
        assert_abs_diff_eq!(d[(0, 0)], 0.05, epsilon = 1e-15);
        assert_abs_diff_eq!(d[(0, 3)], 0.04, epsilon = 1e-15);
        assert_abs_diff_eq!(d[(4, 4)], 0.04, epsilon = 1e-15);
        assert_eq!(d[(4, 0)], 0.0);
        let gauss_only = sync_params(NoiseSwitches {
            gaussian: true,
            correlation: false,
            outliers: false,
        })
        .check()
        .unwrap();
        let d = design_covariance(&gauss_only);
        assert_abs_diff_eq!(d[(1, 1)], 0.01, epsilon = 1e-15);
        assert_eq!(d[(1, 2)], 0.0);
    }

    fn sample_covariance(rows: &DMatrix<f64>) -> DMatrix<f64> {
        let n = rows.nrows() as f64;
        let mean = rows.row_mean();
        let centered = DMatrix::from_fn(rows.nrows(), rows.ncols(), |i, j| rows[(i, j)] - mean[j]);
        centered.transpose() * &centered / (n - 1.0)
    }

    /// Largest deviation from the design, relative to the design entry (or, for a
    /// zero design entry, to `sqrt(D_ii D_jj)`).
    fn max_rel_dev(s: &DMatrix<f64>, d: &DMatrix<f64>) -> f64 {
        let mut worst: f64 = 0.0;
        for i in 0..d.nrows() {
            for j in 0..d.ncols() {
                let scale = if d[(i, j)] != 0.0 {
                    d[(i, j)]
                } else {
                    (d[(i, i)] * d[(j, j)]).sqrt()
                };
                worst = worst.max((s[(i, j)] - d[(i, j)]).abs() / scale);
            }
        }
        worst
    }

    #[test]
    fn long_sync_run_sample_covariance_matches_design_within_5_percent() {
        // 20 000 s at 0.1 s: 200 000 epochs, 20 000 common-mode draws, so the
        // sigma_c^2 terms have relative std ~ sqrt(2/20000) = 1 %; 5 % is ~5 sigma.
        let traj = Helix {
            t_end: 20_000.0,
            ..helix()
        };
        let params = sync_params(NoiseSwitches {
            outliers: false,
            ..Default::default()
        });
        let cfg = params.check().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(34);
        let data = simulate_beacon_suite(&traj, &cfg, &mut rng).unwrap();
        let s = sample_covariance(&data.sync_noise_rows().unwrap());
        let dev = max_rel_dev(&s, &design_covariance(&cfg));
        assert!(dev < 0.05, "max relative deviation {dev}");
        // Negative control: a 10 % larger sigma_c (21 % larger sigma_c^2) fails.
        let wrong = BeaconSuiteParams {
            corr_sigma: 0.22,
            ..params
        }
        .check()
        .unwrap();
        assert!(max_rel_dev(&s, &design_covariance(&wrong)) > 0.05);
    }

    #[test]
    fn bad_parameters_are_errors() {
        let no_beacons = BeaconSuiteParams {
            beacons_in_nav: vec![],
            ..Default::default()
        };
        assert!(matches!(no_beacons.check(), Err(SensorError::Empty { .. })));
        let bad = BeaconSuiteParams {
            range_sigma: -0.1,
            ..Default::default()
        };
        assert!(bad.check().is_err());
        let bad = BeaconSuiteParams {
            jitter_sigma: 0.003,
            ..Default::default()
        };
        // AHRS period 0.01 s cannot take 3 ms jitter
        assert!(matches!(
            bad.check(),
            Err(SensorError::JitterTooLarge { .. })
        ));
        let bad = BeaconSuiteParams {
            t_gap: 0.0,
            ..Default::default()
        };
        assert!(bad.check().is_err());
        // One beacon is fine.
        let one = BeaconSuiteParams {
            beacons_in_nav: vec![Vector3::new(1.0, 2.0, 3.0)],
            timing: Timing::paper_sync(),
            outliers: OutlierParams {
                count: 3,
                magnitude: 1.0,
            },
            ..Default::default()
        }
        .check()
        .unwrap();
        let data =
            simulate_beacon_suite(&helix(), &one, &mut ChaCha8Rng::seed_from_u64(35)).unwrap();
        assert_eq!(data.sync_noise_rows().unwrap().ncols(), 2);
        assert_eq!(design_covariance(&one).shape(), (2, 2));
    }
}
