//! End-to-end check of the bad-input policy (`fathom_estimators` crate docs, "Bad
//! input") on a whole beacon-EKF run: simulated seed-003 data with some ranges, depths
//! and DVL samples replaced by NaN / +-inf are dropped and counted by the scheme
//! filter, never applied, and every estimate stays finite; a filter error surfaces
//! as an error naming the scheme and the time, not a panic or NaN.

use fathom_estimators::schemes::UpdateScheme;
use fathom_experiments::beacons::{EkfSettings, FilterSetup, SchemeRun, run_scheme};
use fathom_sensors::{BeaconSuiteData, simulate_beacon_suite};
use fathom_sim::montecarlo::run_rng;
use fathom_traj::velocity_command::VelocityCommandMotion;
use nalgebra::{Vector3, Vector4};

/// Run length, s.
const DURATION: f64 = 30.0;
/// Every `STRIDE`-th range / depth / DVL sample is replaced by a bad value.
const STRIDE: usize = 7;
const BAD: [f64; 3] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];

struct Fixture {
    motion: VelocityCommandMotion,
    data: BeaconSuiteData,
    setup: FilterSetup,
    initial_error: Vector4<f64>,
}

fn fixture() -> Fixture {
    let (motion_params, suite) = crate::support::beacon_mission(DURATION, true, true);
    let setup = FilterSetup::new(&EkfSettings::default(), &suite, &motion_params).unwrap();
    let mut rng = run_rng(77, 0);
    let motion =
        VelocityCommandMotion::generate(&motion_params.check().unwrap(), &mut rng).unwrap();
    let initial_error = setup.draw_initial_error(&mut rng);
    let data = simulate_beacon_suite(&motion, &suite, &mut rng).unwrap();
    Fixture {
        motion,
        data,
        setup,
        initial_error,
    }
}

/// Which samples are bad: every `STRIDE`-th one stamped at least 1 s before the end
/// (later samples are never fed to the filter, so they could not be counted).
fn is_bad(i: usize, stamp: f64) -> bool {
    i % STRIDE == 3 && stamp < DURATION - 1.0
}

/// `data` with the bad samples replaced by NaN / +-inf (`replace`) or removed;
/// returns the data, the number of bad measurements and the number of bad inputs.
fn corrupt(data: &BeaconSuiteData, replace: bool) -> (BeaconSuiteData, usize, usize) {
    let mut out = data.clone();
    let mut measurements = 0;
    for list in out.ranges.iter_mut().chain(std::iter::once(&mut out.depth)) {
        let mut kept = Vec::with_capacity(list.len());
        for (i, mut m) in list.drain(..).enumerate() {
            if is_bad(i, m.stamp) {
                measurements += 1;
                if !replace {
                    continue;
                }
                m.value = BAD[measurements % 3];
            }
            kept.push(m);
        }
        *list = kept;
    }
    let mut inputs = 0;
    let mut kept = Vec::with_capacity(out.dvl.len());
    for (i, mut m) in out.dvl.drain(..).enumerate() {
        if is_bad(i, m.stamp) {
            inputs += 1;
            if !replace {
                continue;
            }
            m.value = Vector3::new(0.3, BAD[inputs % 3], 0.0);
        }
        kept.push(m);
    }
    out.dvl = kept;
    (out, measurements, inputs)
}

fn run(f: &Fixture, data: &BeaconSuiteData, scheme: UpdateScheme) -> SchemeRun {
    run_scheme(&f.motion, data, &f.setup, scheme, &f.initial_error).unwrap()
}

/// In every scheme: the dropped counts equal the numbers of injected bad
/// measurements and inputs, all outputs are finite, and the run equals, bit for bit,
/// the run on the data with the bad samples removed. Negative control: with the
/// original values in those places the estimates differ (the samples matter, so
/// applying anything there would show), and the clean run counts no drop.
#[test]
fn beacon_ekf_drops_and_counts_non_finite_samples() {
    let f = fixture();
    let (dirty, bad_meas, bad_inputs) = corrupt(&f.data, true);
    let (removed, _, _) = corrupt(&f.data, false);
    assert!(bad_meas > 100 && bad_inputs > 20, "{bad_meas} {bad_inputs}");
    for scheme in UpdateScheme::ALL {
        let d = run(&f, &dirty, scheme);
        let r = run(&f, &removed, scheme);
        let c = run(&f, &f.data, scheme);
        let dropped: usize = d.counts.iter().map(|c| c.non_finite).sum();
        assert_eq!(dropped, bad_meas, "{scheme:?}");
        assert_eq!(d.non_finite_inputs, bad_inputs, "{scheme:?}");
        assert!(
            d.estimates.iter().all(|x| x.iter().all(|v| v.is_finite()))
                && d.errors_3d.iter().all(|e| e.is_finite())
                && d.nees.iter().all(|e| e.is_finite()),
            "{scheme:?}: non-finite output"
        );
        assert_eq!(d.estimates, r.estimates, "{scheme:?}");
        assert_eq!(d.nees, r.nees, "{scheme:?}");
        // Negative control.
        assert_ne!(c.estimates, r.estimates, "{scheme:?}");
        assert_eq!(c.counts.iter().map(|c| c.non_finite).sum::<usize>(), 0);
        assert_eq!(c.non_finite_inputs, 0);
    }
}

/// A covariance that cannot stay positive definite (absurd DVL speeds make the
/// prediction overflow) is an error naming the scheme and the time of the failing
/// step, not a panic and not NaN estimates.
#[test]
fn covariance_overflow_is_an_error_with_scheme_and_time() {
    let f = fixture();
    let mut absurd = f.data.clone();
    for m in absurd.dvl.iter_mut().filter(|m| m.stamp > 10.0) {
        m.value = Vector3::new(1e300, 0.0, 0.0);
    }
    for scheme in UpdateScheme::ALL {
        let e = run_scheme(&f.motion, &absurd, &f.setup, scheme, &f.initial_error).unwrap_err();
        let chain = fathom_sim::error_chain(&e);
        assert!(chain.contains(scheme.short_name()), "{chain}");
        assert!(chain.contains("covariance"), "{chain}");
        assert!(chain.contains(" at t = 1"), "{chain}");
    }
}
