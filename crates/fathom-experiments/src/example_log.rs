//! Simulated logs in fathom's CSV layout, for trying `fathom replay` without data of
//! one's own (`fathom log example <kind>`) and for the tests. Each is simulated with
//! the noise the built-in settings of its replay assume (`scenarios/<kind>.toml`), so
//! that `fathom replay <kind>` with them finds consistent filters:
//!
//! - [`ins_dvl_example`]: the `vkf` experiment's mission (the preset's route, seabed,
//!   IMU, echo sounder and RPM) cut to `duration` seconds, one noise draw: the IMU
//!   increments at 100 Hz, the DVL velocity (white noise of the settings'
//!   `dvl.sigma_mps`, no scale factor or bias) rotated into the body frame with the
//!   true attitude (unflagged garbage beyond its range, as in the experiment: the
//!   first ~300 s stay in range), altitude, RPM and depth (the settings'
//!   `depth.sigma_m`) at 5 Hz, truth at 1 Hz;
//! - [`range_beacon_example`]: a vehicle at 1 m/s on a 20 m circle at 10 m depth; a
//!   DVL at 5 Hz with white noise of the settings' `dvl.velocity_sigma_mps`, a DVL row
//!   at the start (a replay holds each DVL row until the next, and a velocity of zero
//!   before the first); headings at 10 Hz whose differences carry the settings'
//!   `dvl.yaw_rate_sigma_rad_per_s` (the replay uses heading only as the yaw rate of
//!   consecutive rows); four beacons ranged in turn every 0.3 s with the settings'
//!   `ranges.sigma_m`, 2 % of them outliers of `2 robust.reject_sigma` range σ that
//!   the robust filters reject; depth (`depth.sigma_m`) at 5 Hz; truth at 1 Hz.
//!
//! Both are deterministic for a seed (run stream 0 of it).

use fathom_core::frames::euler_from_nav_from_body;
use fathom_core::units::wrap_pi;
use fathom_ins::earth::curvilinear_offset;
use fathom_sensors::noise::gauss;
use rand::Rng;

use crate::vkf::Vkf;
use crate::vkf::scenario::VkfScenario;
use fathom_data::layout::ins_dvl::{DvlRow, ImuForm, InsDvlLog, InsStart, InsTruthRow};
use fathom_data::layout::range_beacon::{
    Beacon, Motion, RangeBeaconLog, RangeRow, Start, TruthRow,
};
use fathom_replay::own_log::{INS_DVL_PRESET, RANGE_BEACON_PRESET};
use fathom_sim::SimError;
use fathom_sim::experiment::Experiment;
use fathom_sim::montecarlo::run_rng;

/// The `ins-dvl` example (module docs): `duration_s` seconds of the `vkf` preset's
/// mission (at most its 1620 s), with or without `truth.csv`.
///
/// # Errors
/// [`SimError::Invalid`] naming `duration` for a duration that is not a whole number
/// of IMU intervals between 2 s and 1620 s; model errors of the simulation.
pub fn ins_dvl_example(
    duration_s: f64,
    seed: u64,
    with_truth: bool,
) -> Result<InsDvlLog, SimError> {
    let label = "fathom log example ins-dvl";
    let mut sc: VkfScenario =
        fathom_sim::scenario::parse_toml(Vkf::PRESET, "built-in scenarios/vkf.toml")?;
    if !(duration_s.is_finite() && (2.0..=sc.route.duration_s).contains(&duration_s)) {
        return Err(SimError::invalid(
            label,
            "--duration",
            format!(
                "must be between 2 and {} s, got {duration_s}",
                sc.route.duration_s
            ),
        ));
    }
    sc.route.duration_s = duration_s;
    // The sensors as the replay's built-in settings model them.
    let settings =
        fathom_replay::ins_dvl::parse_settings(INS_DVL_PRESET, "built-in scenarios/ins-dvl.toml")?;
    sc.dvl.sigma_mps = settings.dvl_sigma;
    sc.dvl.scale_factor_half_width = 0.0;
    sc.dvl.bias_half_width_mps = 0.0;
    sc.depth_gauge.sigma_m = settings.depth_sigma;
    let c = sc
        .check(label)
        .map_err(|e| SimError::invalid(label, "--duration", e.to_string()))?;
    let sh = crate::vkf::sim::build_shared(&c)?;
    let mut rng = run_rng(seed, 0);
    let mut imu = c.imu.draw(&mut rng);
    let dvl = c
        .dvl
        .draw(&mut rng)
        .map_err(|e| SimError::model("example DVL", e))?;
    let t0 = sh.truth[0];
    let start_geo = t0.position();
    let e0 = euler_from_nav_from_body(&t0.nav_from_body.to_rotation_matrix());
    let mut log = InsDvlLog {
        start: InsStart {
            time: t0.time,
            lat_lon: [t0.lat, t0.lon],
            depth: -t0.h,
            vel_in_nav: t0.vel_in_nav.into(),
            euler: [e0.roll, e0.pitch, e0.yaw],
        },
        imu_form: ImuForm::Increments,
        imu: Vec::with_capacity(c.n_steps),
        dvl: Vec::new(),
        depth: Some(Vec::new()),
        altitude: Some(Vec::new()),
        rpm: Some(Vec::new()),
        truth: with_truth.then(Vec::new),
    };
    for k in 0..=c.n_steps {
        let truth = &sh.truth[k];
        let t = truth.time;
        if k > 0 {
            let inc = &sh.increments[k - 1];
            let (dth, dv) = imu
                .corrupt(inc.dt, &inc.delta_theta, &inc.delta_v, &mut rng)
                .map_err(|e| SimError::model("example IMU", e))?;
            log.imu.push((t, dth.into(), dv.into()));
        }
        if k > 0 && k % c.sensor_every == 0 {
            let reading = dvl
                .measure(&truth.vel_in_nav, sh.altitude[k], &mut rng)
                .map_err(|e| SimError::model("example DVL", e))?;
            let v_body = truth.nav_from_body.inverse() * reading.vel_in_nav;
            log.dvl.push(DvlRow {
                time: t,
                vel_in_body: v_body.into(),
                bottom_lock: None,
            });
            let alt = c.echo.measure(sh.altitude[k], &mut rng).max(0.0);
            let rpm = c.rpm.measure(sh.forward_speed[k], &mut rng);
            let depth = -truth.h + gauss(&mut rng, c.depth_sigma);
            if let Some(v) = log.altitude.as_mut() {
                v.push((t, alt));
            }
            if let Some(v) = log.rpm.as_mut() {
                v.push((t, rpm));
            }
            if let Some(v) = log.depth.as_mut() {
                v.push((t, depth));
            }
        }
        if k % c.record_every == 0
            && let Some(v) = log.truth.as_mut()
        {
            let o = curvilinear_offset(&start_geo, &truth.position());
            v.push(InsTruthRow {
                time: t,
                pos_in_nav: [o.x, o.y, -truth.h],
                vel_in_nav: Some(truth.vel_in_nav.into()),
            });
        }
    }
    Ok(log)
}

/// The `range-beacon` example and how many outliers it holds.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeBeaconExample {
    /// The log.
    pub log: RangeBeaconLog,
    /// Ranges with an outlier added (the robust filters reject them).
    pub outliers: usize,
    /// The outliers' size, m.
    pub outlier_m: f64,
}

/// The `range-beacon` example (module docs): `duration_s` seconds (10 to 36,000),
/// with or without `truth.csv`.
///
/// # Errors
/// [`SimError::Invalid`] naming `--duration` out of range.
pub fn range_beacon_example(
    duration_s: f64,
    seed: u64,
    with_truth: bool,
) -> Result<RangeBeaconExample, SimError> {
    if !(duration_s.is_finite() && (10.0..=36_000.0).contains(&duration_s)) {
        return Err(SimError::invalid(
            "fathom log example range-beacon",
            "--duration",
            format!("must be between 10 and 36000 s, got {duration_s}"),
        ));
    }
    let settings = fathom_replay::range_beacon::parse_settings(
        RANGE_BEACON_PRESET,
        "built-in scenarios/range-beacon.toml",
    )?;
    let range_sigma = settings.engine.range_sigma;
    let outlier_m = 2.0 * settings.engine.reject_sigma * range_sigma;
    let mut rng = run_rng(seed, 0);
    let (radius, rate) = (20.0f64, 0.05f64);
    let pos = |t: f64| [radius * (rate * t).cos(), radius * (rate * t).sin(), 10.0];
    let heading = |t: f64| wrap_pi(rate * t + std::f64::consts::FRAC_PI_2);
    let beacons = [
        [30.0, 30.0, 0.0],
        [-30.0, 30.0, 40.0],
        [-30.0, -30.0, 0.0],
        [30.0, -30.0, 40.0],
    ];
    let steps = (duration_s * 10.0).round() as usize;
    let dt = 0.1;
    let speed = radius * rate;
    let dvl_row = |rng: &mut rand_chacha::ChaCha8Rng, t: f64| {
        let s = settings.dvl_velocity_sigma;
        (
            t,
            [speed + gauss(rng, s[0]), gauss(rng, s[1]), gauss(rng, s[2])],
        )
    };
    let mut dvl = vec![dvl_row(&mut rng, 0.0)];
    let mut head = Vec::new();
    let mut ranges = Vec::new();
    let mut depth = Vec::new();
    let mut truth = Vec::new();
    // The heading error is a random walk whose steps are the yaw-rate error times the
    // interval: the rate of consecutive headings then has the settings' σ.
    let mut heading_error = 0.0;
    let mut outliers = 0;
    for k in 1..=steps {
        let t = k as f64 * dt;
        let p = pos(t);
        heading_error += gauss(&mut rng, settings.yaw_rate_sigma * dt);
        head.push((t, wrap_pi(heading(t) + heading_error)));
        if k % 2 == 0 {
            dvl.push(dvl_row(&mut rng, t));
            depth.push((t, p[2] + gauss(&mut rng, settings.depth_sigma)));
        }
        if k % 3 == 0 {
            let b = (k / 3) % beacons.len();
            let d = (0..3)
                .map(|i| (p[i] - beacons[b][i]).powi(2))
                .sum::<f64>()
                .sqrt();
            let outlier = if rng.random::<f64>() < 0.02 {
                outliers += 1;
                outlier_m
            } else {
                0.0
            };
            ranges.push(RangeRow {
                time: t,
                beacon: b,
                range: (d + gauss(&mut rng, range_sigma) + outlier).max(0.0),
            });
        }
        if k % 10 == 0 && with_truth {
            truth.push(TruthRow {
                time: t,
                north_east: [p[0], p[1]],
                down: Some(p[2]),
                heading: Some(heading(t)),
            });
        }
    }
    let p0 = pos(0.0);
    let log = RangeBeaconLog {
        beacons: beacons
            .iter()
            .enumerate()
            .map(|(i, b)| Beacon {
                id: i as i64 + 1,
                pos_in_nav: *b,
            })
            .collect(),
        beacons_have_down: true,
        start: Start {
            time: 0.0,
            north_east: [p0[0], p0[1]],
            down: Some(p0[2]),
            heading: heading(0.0),
        },
        motion: Motion::Dvl { dvl, heading: head },
        ranges,
        depth: Some(depth),
        truth: with_truth.then_some(truth),
    };
    Ok(RangeBeaconExample {
        log,
        outliers,
        outlier_m,
    })
}
