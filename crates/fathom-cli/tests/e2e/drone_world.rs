//! End-to-end test of the map-aided filters on a drone log with a user's world
//! (`fathom replay gnss-ins DIR --world world.obj`): a simulated `urban` flight under
//! the bridge, written by fathom as a `gnss-ins` log with its lidar beams, barometer
//! and truth, and its world as an OBJ file; GNSS dropped by an outage window while
//! the vehicle is under the deck. The map-aided methods run, stay finite and within
//! the GPS/INS filter's error there; without `--world` they are absent; `--world`
//! on a log without range rows is one line with exit code 2. With a world the replay
//! writes its scene page.

use std::path::Path;

use fathom_data::layout::{LogKind, Manifest, write_log};
use fathom_experiments::urban::export_log::simulated_flight;
use fathom_report::output::{Summary, read_summary_json};
use fathom_sim::experiment::Environment;

use crate::support::{fathom, repo_root, scratch, usage_error};

fn value(s: &Summary, method: &str, metric: &str) -> f64 {
    s.row(method, metric)
        .unwrap_or_else(|| panic!("no row {method} / {metric}"))
        .value
}

/// The `urban` preset's bridge flight with a 100 m deck, its gyro's turn-on bias
/// taken as calibrated (the replay's 12-state filters have no gyro-bias state and no
/// calibration at rest, as the `urban` methods do), written into `root/flight` with
/// `root/world.obj`; returns the outage window (s from the replay's start) that
/// covers the flight under the deck, and the flight's geodetic origin.
fn write_flight(root: &Path) -> ((f64, f64), [f64; 3]) {
    let text = std::fs::read_to_string(repo_root().join("scenarios/urban.toml"))
        .unwrap()
        .replace(
            "gyro_turn_on_bias_deg_per_hr = 200.0",
            "gyro_turn_on_bias_deg_per_hr = 0.0",
        )
        .replace("deck_length_m = 200.0", "deck_length_m = 100.0");
    let env = Environment::new(root);
    let f = simulated_flight(&text, "urban.toml", 0, 11, &env).expect("the urban flight");
    let files = f.log.to_files();
    let manifest = Manifest::new(LogKind::GnssIns, "simulated urban bridge flight (seed 11)");
    std::fs::create_dir_all(root.join("flight")).unwrap();
    write_log(&root.join("flight"), &manifest, &files).unwrap();
    std::fs::write(root.join("world.obj"), &f.world_obj).unwrap();
    // under the deck: the truth's north between 0 and the deck's length (100 m)
    let truth = f.log.truth.as_ref().unwrap();
    let t0 = f.log.imu[0].time;
    let lat0 = f.origin[0].to_radians();
    let north = |r: &fathom_data::layout::gnss_ins::TrackRow| (r.lat_lon[0] - lat0) * 6_371_000.0;
    let under: Vec<f64> = truth
        .iter()
        .filter(|r| (0.0..=100.0).contains(&north(r)))
        .map(|r| r.time)
        .collect();
    let (a, b) = (under[0], under[under.len() - 1]);
    assert!(b - a > 20.0, "the flight spends {} s under the deck", b - a);
    // the replay starts at the reference row after the first IMU row
    let start = truth.iter().find(|r| r.time >= t0).unwrap().time;
    ((a - start, b - start), f.origin)
}

/// The replay's settings: the simulated IMU's noise (the `urban` filters'), no GNSS
/// velocity (the simulated receiver gives none), the outage; `sim.toml` also places
/// the world's origin at the flight's geodetic origin (`--world` gives the file),
/// `sim_no_world.toml` has no `[world]`.
fn settings(root: &Path, outage: (f64, f64), origin: [f64; 3]) {
    let text = std::fs::read_to_string(repo_root().join("scenarios/gnss-ins.toml"))
        .unwrap()
        .replace(
            "velocity_random_walk_mps_per_sqrt_s = 0.05",
            "velocity_random_walk_mps_per_sqrt_s = 0.0023",
        )
        .replace(
            "angle_random_walk_rad_per_sqrt_s = 0.005",
            "angle_random_walk_rad_per_sqrt_s = 0.00087",
        )
        .replace(
            "accel_bias_random_walk_mps2_per_sqrt_s = 0.003",
            "accel_bias_random_walk_mps2_per_sqrt_s = 0.00005",
        )
        .replace("use_velocity = true", "use_velocity = false")
        .replace(
            "gate_probability = 0.9999\n",
            &format!(
                "gate_probability = 0.9999\n[[gnss.outages]]\nstart_s = {}\nend_s = {}\n",
                outage.0, outage.1
            ),
        );
    std::fs::write(root.join("sim_no_world.toml"), &text).unwrap();
    let with_world = text.replace(
        "[initial]",
        &format!(
            "[world]\norigin_lat_lon_alt = [{}, {}, {}]\n\n[initial]",
            origin[0], origin[1], origin[2]
        ),
    );
    std::fs::write(root.join("sim.toml"), with_world).unwrap();
}

#[test]
fn map_aided_filters_replay_a_drone_log_with_a_user_world() {
    let root = scratch("drone-world");
    let (outage, origin) = write_flight(&root);
    settings(&root, outage, origin);
    let r = fathom(
        &root,
        &[
            "replay",
            "gnss-ins",
            "flight",
            "--world",
            "world.obj",
            "--config",
            "sim.toml",
            "--out",
            "o",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let s = read_summary_json(root.join("o/summary.json")).unwrap();
    let gps = value(&s, "GPS-INS-12", "outage0_max_h_vs_ekf2");
    let gps_rmse = value(&s, "GPS-INS-12", "rmse_h");
    for m in ["GREKF", "MGPMF"] {
        let max = value(&s, m, "outage0_max_h_vs_ekf2");
        let rmse = value(&s, m, "rmse_h");
        let updates = value(&s, m, "map_updates");
        let switches = value(&s, m, "mode_switches");
        eprintln!(
            "drone world {m}: outage max error {max:.3} m (GPS-INS-12 {gps:.3} m), rmse_h \
             {rmse:.3} m (GPS-INS-12 {gps_rmse:.3} m), {updates} map updates, {switches} \
             switches, nees {:.3}",
            value(&s, m, "nees_pos")
        );
        assert!(max.is_finite() && rmse.is_finite());
        assert!(
            updates > 0.0 && switches >= 2.0,
            "{m}: {updates} {switches}"
        );
        // the reference is the truth here: the map-aided error under the deck stays
        // within the dead-reckoning GPS/INS filter's there
        assert!(max <= gps, "{m}: {max} m vs GPS-INS-12 {gps} m");
    }
    let report = std::fs::read_to_string(root.join("o/report.md")).unwrap();
    assert!(report.contains("### World") && report.contains("world.obj"));
    // the scene page: the world, the truth and the methods with their modes
    let page = std::fs::read_to_string(root.join("o/scene.html")).unwrap();
    assert!(page.contains("gnss-ins replay with the world") && page.contains("map-aided"));
    // without --world: no map-aided methods
    let r = fathom(
        &root,
        &[
            "replay",
            "gnss-ins",
            "flight",
            "--config",
            "sim_no_world.toml",
            "--out",
            "plain",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let s = read_summary_json(root.join("plain/summary.json")).unwrap();
    assert!(s.row("GPS-INS-12", "rmse_h").is_some());
    for m in ["GREKF", "MGPMF"] {
        assert!(s.rows.iter().all(|r| r.method != m), "{m} without a world");
    }
    assert!(
        !root.join("plain/scene.html").exists(),
        "no world, no scene page"
    );
    // --world on a log without range rows: one line, exit code 2
    let sitl = repo_root().join("data/ulog/sitl_groundtruth.ulg");
    usage_error(
        &root,
        &[
            "replay",
            "ulog",
            sitl.to_str().unwrap(),
            "--world",
            "world.obj",
            "--out",
            "x",
        ],
        &["world.obj", "no range rows"],
    );
}
