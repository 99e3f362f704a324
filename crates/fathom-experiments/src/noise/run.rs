//! One `noise` run: the realised noise of every case and its zero-mean covariance,
//! and the long convergence run.

use fathom_sensors::schedule::ClockParams;
use fathom_sensors::{BeaconSuiteConfig, Timing, simulate_beacon_suite};
use fathom_stats::covariance::max_relative_deviation;
use nalgebra::DMatrix;
use rand_chacha::ChaCha8Rng;

use super::scenario::{Case, Checked};
use crate::common::generate_motion;
use fathom_sim::SimError;
use fathom_sim::montecarlo::run_rng;

/// The realised noise rows `[range1..4, depth]` (one row per epoch) of one case.
pub(super) fn noise_rows(
    motion: &fathom_traj::velocity_command::VelocityCommandMotion,
    config: &BeaconSuiteConfig,
    rng: &mut ChaCha8Rng,
) -> Result<DMatrix<f64>, SimError> {
    let data = simulate_beacon_suite(motion, config, rng)
        .map_err(|e| SimError::model("sensor suite", e))?;
    data.sync_noise_rows()
        .map_err(|e| SimError::model("sensor suite noise rows", e))
}

/// `1/n X^T X`: covariance of zero-mean samples (one per row).
fn zero_mean_cov(rows: &DMatrix<f64>) -> DMatrix<f64> {
    rows.transpose() * rows / rows.nrows() as f64
}

/// One Monte Carlo run: the per-case covariance matrices. The motion is drawn
/// once per run and every case starts from the same RNG state (common random
/// numbers), so the cases differ only by their noise switches.
pub(super) fn one_run(
    checked: &Checked,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<DMatrix<f64>>, SimError> {
    let motion = generate_motion(&checked.motion, rng)?;
    checked
        .cases
        .iter()
        .map(|case| {
            let mut case_rng = rng.clone();
            noise_rows(&motion, &case.config, &mut case_rng).map(|rows| zero_mean_cov(&rows))
        })
        .collect()
}

/// Convergence of the long run: max relative deviation after each prefix length.
#[derive(Debug, Clone)]
pub(super) struct LongRun {
    pub(super) cov: DMatrix<f64>,
    pub(super) max_rel_dev: f64,
    pub(super) worst: (usize, usize),
    /// `(prefix duration s, max relative deviation)`.
    pub(super) convergence: Vec<(f64, f64)>,
}

pub(super) fn long_run(
    checked: &Checked,
    case: &Case,
    design: &DMatrix<f64>,
    period: f64,
) -> Result<LongRun, SimError> {
    // Stream u64::MAX of the base seed: independent of the Monte Carlo runs and of
    // their number.
    let mut rng = run_rng(checked.base_seed, usize::MAX);
    let motion = generate_motion(&checked.long_motion, &mut rng)?;
    let rows = noise_rows(&motion, &case.long_config, &mut rng)?;
    let n = rows.nrows();
    let mut acc = DMatrix::<f64>::zeros(5, 5);
    let mut convergence = Vec::new();
    let mut next_mark = checked.motion.duration; // first point: one paper-length run
    for k in 0..n {
        let r = rows.row(k);
        acc += r.transpose() * r;
        let t = (k + 1) as f64 * period;
        if t >= next_mark - 0.5 * period || k + 1 == n {
            let cov = &acc / (k + 1) as f64;
            let dev = max_relative_deviation(&cov, design)
                .map_err(|e| SimError::model("long-run deviation", e))?;
            convergence.push((t, dev.value));
            next_mark *= 1.25;
        }
    }
    let cov = acc / n as f64;
    let dev = max_relative_deviation(&cov, design)
        .map_err(|e| SimError::model("long-run deviation", e))?;
    Ok(LongRun {
        cov,
        max_rel_dev: dev.value,
        worst: (dev.row, dev.col),
        convergence,
    })
}

/// Labelled rows of sample times, s.
pub(super) type SampleRows = Vec<(String, Vec<f64>)>;

/// The sample-time diagram's window, s.
pub(super) const SAMPLE_WINDOW: (f64, f64) = (0.0, 1.0);

/// The sample times of the synchronous clock and of each asynchronous sensor clock
/// over [`SAMPLE_WINDOW`] (stream `usize::MAX - 1` of the base seed: independent of the
/// Monte Carlo runs); `None` when the paper's timing is not asynchronous.
///
/// # Errors
/// A clock that does not check.
pub(super) fn sample_time_rows(checked: &Checked) -> Result<Option<SampleRows>, SimError> {
    let mut rng = run_rng(checked.base_seed, usize::MAX - 1);
    let window = SAMPLE_WINDOW;
    let jitter = checked.jitter_sigma;
    let make = |name: &str, period: f64, rng: &mut ChaCha8Rng| -> Result<Vec<f64>, SimError> {
        let clock = ClockParams {
            jitter_sigma: jitter.min(period / 5.0),
            ..ClockParams::with_period(period)
        }
        .check(name)
        .map_err(|e| SimError::model("sample-time diagram", e))?;
        Ok(clock
            .generate(0.0, window.1, rng)
            .map_err(|e| SimError::model("sample-time diagram", e))?
            .sample_times()
            .to_vec())
    };
    let sync = make("sync", checked.period, &mut rng)?;
    let Timing::Asynchronous {
        dvl,
        ahrs,
        range,
        depth,
    } = Timing::paper_async()
    else {
        return Ok(None);
    };
    let mut rows = vec![("sync: all sensors".to_owned(), sync)];
    rows.push((
        format!("async: DVL ({dvl:.2} s)"),
        make("dvl", dvl, &mut rng)?,
    ));
    rows.push((
        format!("async: AHRS ({ahrs:.2} s)"),
        make("ahrs", ahrs, &mut rng)?,
    ));
    for k in 1..=4 {
        rows.push((
            format!("async: range{k} ({range:.2} s)"),
            make("range", range, &mut rng)?,
        ));
    }
    rows.push((
        format!("async: depth ({depth:.2} s)"),
        make("depth", depth, &mut rng)?,
    ));
    Ok(Some(rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::scenario::NoiseScenario;

    #[test]
    fn one_run_matches_design_roughly() {
        let text = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/noise.toml"),
        )
        .unwrap();
        let mut s: NoiseScenario = fathom_sim::scenario::parse_toml(&text, "noise.toml").unwrap();
        s.runs = 2;
        let c = s.check("noise.toml").unwrap();
        let mut rng = run_rng(7, 0);
        let covs = one_run(&c, &mut rng).unwrap();
        // gaussian case: depth variance 0.04 within 15 % for ~1800 samples (sd ~3.3 %).
        assert!(
            (covs[0][(4, 4)] - 0.04).abs() < 0.006,
            "{}",
            covs[0][(4, 4)]
        );
        // corr_high: no depth noise at all.
        assert_eq!(covs[1][(4, 4)], 0.0);
    }
}
