//! Tests of the `urban` flight on the link: the wire form navigates exactly as the
//! offline run (the lockstep session over a faulty link: `session.rs`).

use std::collections::BTreeMap;

use super::*;
use crate::report::offline_with;

const PRESET: &str = include_str!("../../../scenarios/urban.toml");

/// The preset with a short bridge (40 m deck, 16 m of open sky each side) and 2 s of
/// rest: about 4,000 steps.
pub(crate) fn short_bridge() -> String {
    let text = PRESET
        .replace("rest_s = 10.0 ", "rest_s = 2.0 ")
        .replace("deck_length_m = 200.0", "deck_length_m = 40.0")
        .replace(
            "ground_margin_m = 100.0\npath_height_m = 5.0",
            "ground_margin_m = 20.0\npath_height_m = 5.0",
        );
    assert!(text.contains("deck_length_m = 40.0") && text.contains("rest_s = 2.0 "));
    assert!(
        text.contains("ground_margin_m = 20.0"),
        "the preset's bridge lines moved"
    );
    text
}

fn flight(method: &str) -> UrbanFlight {
    UrbanFlight::load(
        &short_bridge(),
        "urban.toml",
        Path::new("."),
        Some("bridge"),
        Some(method),
        1,
    )
    .unwrap()
}

/// The solutions of the `urban` navigation fed the offline run's own epochs, started
/// from the truth and the run's initial error (what `fathom run` does).
fn offline_urban(fl: &UrbanFlight, run: &UrbanRun) -> BTreeMap<u64, Solution> {
    let env = fl.env();
    let mut streams = fl.streams();
    let dx0 = initial_error(&fl.prep, &mut streams.init).unwrap();
    let mut nav = Navigation::new(
        &env,
        fl.method,
        fl.schedule.start as usize,
        &streams.particle,
    );
    let mut out = BTreeMap::new();
    for (i, e) in run.sensed().iter().enumerate() {
        let k = i + 1;
        let truth = SensorSource::truth(run, k as u64);
        let init = (k == fl.schedule.start as usize).then(|| NavStart::from_truth(truth, &dx0));
        let fed = nav.feed(k, truth.time, e, init.as_ref()).unwrap();
        if let (Fed::Stepped { .. }, Some(n)) = (fed, nav.nav()) {
            let s = n.nominal();
            out.insert(
                k as u64,
                (s.pos_in_nav, s.vel_in_nav, s.nav_from_body, n.map_aided()),
            );
        }
    }
    out.into_iter()
        .map(|(k, (p, v, q, m))| {
            (
                k,
                Solution {
                    step: k,
                    time: 0.0,
                    pos_in_nav: p,
                    vel_in_nav: v,
                    nav_from_body: q,
                    omega_body: Default::default(),
                    pos_cov: Default::default(),
                    att_cov: Default::default(),
                    pos_att_cov: Default::default(),
                    vel_cov: Default::default(),
                    map_aided: m,
                },
            )
        })
        .collect()
}

fn states(s: &BTreeMap<u64, Solution>) -> Vec<(u64, [f64; 10], bool)> {
    s.iter()
        .map(|(k, x)| {
            let q = x.nav_from_body.coords;
            (
                *k,
                [
                    x.pos_in_nav.x,
                    x.pos_in_nav.y,
                    x.pos_in_nav.z,
                    x.vel_in_nav.x,
                    x.vel_in_nav.y,
                    x.vel_in_nav.z,
                    q.w,
                    q.x,
                    q.y,
                    q.z,
                ],
                x.map_aided,
            )
        })
        .collect()
}

/// The wire form rebuilt with the sensor model navigates bit for bit as the `urban`
/// run on its own epochs, for a switching method that does switch; the quantized
/// form differs (negative control: the comparison sees the quantization).
#[test]
fn the_wire_form_navigates_exactly_as_the_urban_run() {
    for method in ["GREKF", "MGPMF"] {
        let fl = flight(method);
        let run = UrbanRun::new(&fl).unwrap();
        let reference = offline_urban(&fl, &run);
        let env = fl.env();
        let mut nav = UrbanNav::new(&fl, &env);
        let wire = offline_with(
            &fl.schedule,
            run.epochs(),
            SensorSource::initial(&run),
            &mut nav,
            false,
        )
        .unwrap();
        assert!(reference.len() > 1000, "{method}: {}", reference.len());
        assert_eq!(states(&wire), states(&reference), "{method}");
        assert!(
            reference.values().any(|s| s.map_aided) && reference.values().any(|s| !s.map_aided),
            "{method} never switched on the short bridge"
        );
        let mut nav = UrbanNav::new(&fl, &env);
        let quantized = offline_with(
            &fl.schedule,
            run.epochs(),
            SensorSource::initial(&run),
            &mut nav,
            true,
        )
        .unwrap();
        assert_ne!(states(&quantized), states(&reference), "{method}");
    }
}

/// Every epoch carries the magnetometer: the site's dipole field (38,710 nT at
/// 37.5 N 127 E) turned into the body frame by the true attitude, and the
/// `HIL_SENSOR` round trip keeps it to `f32` precision.
#[test]
fn epochs_carry_the_site_field_in_the_body_frame() {
    let fl = flight("GREKF");
    let run = UrbanRun::new(&fl).unwrap();
    let field = site_field_gauss(&fl.schedule.frame);
    assert!((field.norm() - 0.387_1).abs() < 1e-3, "{field}");
    for k in [1u64, 500, 2000] {
        let e = SensorSource::epoch(&run, k);
        let truth = SensorSource::truth(&run, k);
        let mag = e.mag_body_gauss.unwrap();
        assert!(
            (truth.nav_from_body * mag - field).norm() < 1e-12,
            "step {k}"
        );
        let msgs = crate::codec::encode_epoch(e, &fl.schedule.frame, &fl.schedule.wire);
        let Some(mavlink::dialects::common::MavMessage::HIL_SENSOR(d)) = msgs.last() else {
            panic!("HIL_SENSOR closes the step")
        };
        let back = crate::codec::decode_imu(d).mag_body_gauss.unwrap();
        assert!((back - mag).norm() < 1e-7, "step {k}: {back} {mag}");
    }
}
