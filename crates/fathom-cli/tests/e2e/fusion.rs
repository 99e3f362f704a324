//! End-to-end: a reduced `fusion` scenario (4 runs, a 520 s mission with 4 course
//! changes) through the experiment layer: per-run metrics are finite, the unaided
//! INS drifts far more than the DVL dead reckoning, and EFF's feedback keeps the INS
//! integrator's error bounded.

use fathom_experiments::fusion::{RunResult, run_once, scenario::FusionScenario, sim::Method};
use fathom_sim::montecarlo::try_run_monte_carlo;
use fathom_sim::scenario::parse_toml;

fn reduced_scenario() -> FusionScenario {
    let text =
        std::fs::read_to_string(crate::support::repo_root().join("scenarios/fusion.toml")).unwrap();
    let mut s: FusionScenario = parse_toml(&text, "scenarios/fusion.toml").unwrap();
    s.runs = 4;
    s.mission.duration_s = 520.0;
    s.mission.n_course_changes = 4;
    s.mission.leg_speeds_kt = vec![3.0, 4.0, 2.5, 4.5, 3.0];
    s
}

fn runs_with(reading: &str) -> Vec<RunResult> {
    let mut s = reduced_scenario();
    s.filters.reading = reading.to_string();
    let setup = s.check("reduced fusion").unwrap();
    let mission = setup.mission().unwrap();
    assert_eq!(mission.course_changes().len(), 4);
    try_run_monte_carlo(setup.runs, setup.base_seed, Some(2), |_, rng| {
        run_once(&setup, &setup.run, &mission, &Method::ALL, false, rng)
    })
    .unwrap()
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.collect();
    v.iter().sum::<f64>() / v.len() as f64
}

fn method_mean(results: &[RunResult], m: Method) -> f64 {
    mean(
        results
            .iter()
            .map(|r| r.metrics[m.index()].unwrap().mean_3d),
    )
}

#[test]
fn reduced_fusion_scenario_end_to_end() {
    let results = runs_with("as_printed");
    assert_eq!(results.len(), 4);
    for (run, r) in results.iter().enumerate() {
        assert_eq!(r.output.times.len(), 520);
        for m in Method::ALL {
            let mm = r.metrics[m.index()].unwrap_or_else(|| panic!("run {run}: {m:?} missing"));
            for (name, v) in [
                ("mean_3d", mm.mean_3d),
                ("std_3d", mm.std_3d),
                ("mean_2d", mm.mean_2d),
                ("std_2d", mm.std_2d),
                ("turn_ratio_3d", mm.turn_ratio_3d),
                ("max_3d", mm.max_3d),
            ] {
                assert!(v.is_finite() && v >= 0.0, "run {run} {m:?} {name} = {v}");
            }
            assert!(mm.mean_2d <= mm.mean_3d + 1e-12, "run {run} {m:?}");
        }
    }

    // The INS alone drifts (bias 2e-4 m/s^2: tens of metres after 520 s), the DVL
    // dead reckoning stays at the metre level.
    let ins = mean(
        results
            .iter()
            .map(|r| r.metrics[Method::InsOnly.index()].unwrap().mean_3d),
    );
    let dvl = mean(
        results
            .iter()
            .map(|r| r.metrics[Method::DvlDr.index()].unwrap().mean_3d),
    );
    assert!(ins > 10.0 * dvl, "INS-only {ins} m vs DVL-DR {dvl} m");

    // EFF feeds the fused estimate back into the INS integrator: its error (before
    // each reset) stays at the DVL level in every run and at every step.
    let bound = 5.0;
    for (run, r) in results.iter().enumerate() {
        let fb = &r.output.ins_err_with_feedback;
        assert_eq!(fb.len(), 520);
        let worst = fb.iter().copied().fold(0.0, f64::max);
        assert!(
            worst < bound,
            "run {run}: INS error under feedback reached {worst} m"
        );
    }
    // Negative control: the same bound fails for the open-loop INS.
    let open_loop_worst = results
        .iter()
        .map(|r| r.metrics[Method::InsOnly.index()].unwrap().max_3d)
        .fold(0.0, f64::max);
    assert!(
        open_loop_worst > 2.0 * bound,
        "open-loop INS max {open_loop_worst} m"
    );

    // Under the `as_printed` reading every filter ends up at the DVL dead reckoning's
    // level (the DVL measurement dominates every structure).
    for m in [Method::Mf, Method::T2t, Method::Eff] {
        let e = mean(
            results
                .iter()
                .map(|r| r.metrics[m.index()].unwrap().mean_3d),
        );
        assert!(
            (e - dvl).abs() < 0.05 * dvl + 1e-3,
            "{m:?}: {e} vs DVL-DR {dvl}"
        );
    }
}

#[test]
fn bar_shalom_reading_separates_the_structures() {
    // In the notation of the paper's references the DVL track smooths heavily (white
    // acceleration 0.02 m/s^2) and lags at the course changes; EFF's equalization
    // resets it from the sensors' states every step.
    let results = runs_with("bar_shalom");
    let (mf, t2t, eff, dvl) = (
        method_mean(&results, Method::Mf),
        method_mean(&results, Method::T2t),
        method_mean(&results, Method::Eff),
        method_mean(&results, Method::DvlDr),
    );
    assert!(
        eff < 0.5 * t2t && eff < 0.5 * mf,
        "EFF {eff}, T2T {t2t}, MF {mf}"
    );
    assert!((eff - dvl).abs() < 0.2 * dvl, "EFF {eff} vs DVL-DR {dvl}");
    // Negative control: the same separation does not appear under `as_printed`.
    let printed = runs_with("as_printed");
    let (p_t2t, p_eff) = (
        method_mean(&printed, Method::T2t),
        method_mean(&printed, Method::Eff),
    );
    assert!(p_eff > 0.5 * p_t2t, "as_printed: EFF {p_eff}, T2T {p_t2t}");
}
