//! One simulated `urban` flight written as a `gnss-ins` log with its world as an OBJ
//! file: what a drone with a lidar or range finders would log, from the same truth,
//! sensors and world as run 0 of an `urban` scenario, so that `fathom replay
//! gnss-ins DIR --world world.obj` can be tested against the truth.
//!
//! What the log holds, each from the run's own numbers:
//!
//! - `imu.csv`: the simulated IMU's increments over each step as mean rates;
//! - `gnss.csv`: a single-point fix of every received satellite (NLOS reflections
//!   included, as a receiver without the map would compute it) at each GNSS epoch with
//!   four or more, `h_acc = σ_ρ HDOP / √2`, `v_acc = σ_ρ VDOP`, fix type 3, the
//!   satellites it used; the simulated receiver gives no velocity: the velocity
//!   columns are 0 with `speed_acc` 100 m/s (replay with `use_velocity = false`);
//! - `baro.csv`: the barometer as the `urban` filters convert it (height above the
//!   NED origin, plus the origin's altitude);
//! - `range.csv`: every returned beam, its body direction in `beam_*`, orientation
//!   100 (PX4's custom rotation);
//! - `reference.csv` and `truth.csv`: the truth at the evaluation rate (the simulation
//!   has no autopilot estimate: the reference is the truth, with its attitude).
//!
//! Geodetic coordinates are PX4's projection ([`fathom_data::ulog::projection`]) of
//! the scenario's NED frame about the GNSS origin (`gnss.lat_deg`, `gnss.lon_deg`,
//! `gnss.height_m`); the OBJ is the world's mesh in that frame (ENU axes, z up), so
//! its origin is that geodetic point (`[world] origin_lat_lon_alt`).

use std::fmt::Write as _;

use fathom_data::layout::gnss_ins::{GnssInsLog, GnssRow, ImuRow, RangeRow, TrackRow};
use fathom_data::ulog::projection::reproject;
use fathom_map::TriMesh;
use fathom_sensors::gnss::solve_spp;
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::run::fly_and_sense;
use super::runner::sensor_of;
use super::scenario::UrbanScenario;
use super::sense::Streams;
use super::world::prepare;
use fathom_sim::SimError;
use fathom_sim::experiment::Environment;

/// A simulated flight as a `gnss-ins` log.
#[derive(Debug, Clone)]
pub struct SimulatedFlight {
    /// The log.
    pub log: GnssInsLog,
    /// The world as a Wavefront OBJ text (ENU axes, metres, origin at `origin`).
    pub world_obj: String,
    /// The geodetic origin of the NED frame and the OBJ: latitude, longitude (deg),
    /// altitude (m).
    pub origin: [f64; 3],
    /// Where the vehicle flies out of its rest, s (the truth's time).
    pub rest_s: f64,
}

/// The mesh as OBJ text in ENU axes (`usemtl opaque` / `glass`).
pub fn obj_text(mesh: &TriMesh) -> String {
    let mut s = String::from("# fathom: a world mesh, x east, y north, z up, metres\n");
    for v in mesh.vertices() {
        let _ = writeln!(s, "v {} {} {}", v.y, v.x, -v.z);
    }
    let mut current = None;
    for (t, m) in mesh.triangles().iter().zip(mesh.materials()) {
        let name = if m.is_glass() { "glass" } else { "opaque" };
        if current != Some(name) {
            let _ = writeln!(s, "usemtl {name}");
            current = Some(name);
        }
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

/// Flies scenario `scene` of the `urban` settings `text` (labelled `file`) once with
/// the seed `seed` (run 0's streams of that seed) and writes it as a `gnss-ins` log
/// (module docs).
///
/// # Errors
/// The settings' [`SimError`]s, or a flight the models refuse.
pub fn simulated_flight(
    text: &str,
    file: &str,
    scene: usize,
    seed: u64,
    env: &Environment,
) -> Result<SimulatedFlight, SimError> {
    let scenario: UrbanScenario = fathom_sim::scenario::parse_toml(text, file)?;
    let checked = scenario.check(file)?;
    let prep = prepare(checked, env)?;
    let (Some(spec), Some(world)) = (prep.checked.scenes.get(scene), prep.scenes.get(scene)) else {
        return Err(SimError::invalid_argument(
            "scenario index",
            format!("{scene} is beyond the {} scenarios", prep.scenes.len()),
        ));
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let streams = Streams::from_run(&mut rng);
    let sensor = sensor_of(&prep, spec.ranging);
    let flown = fly_and_sense(&prep, world, spec.ranging, sensor, &streams)?;
    let g = &prep.checked.gnss.params;
    let origin = [g.frame.lat_deg, g.frame.lon_deg, g.frame.height_m];
    let ll0 = [origin[0].to_radians(), origin[1].to_radians()];
    let geo = |p: &Vector3<f64>| (reproject(ll0, p.x, p.y), origin[2] - p.z);
    let frame = prep.receiver.frame();
    let sigma_rho = g.pseudorange_sigma_m;
    let mut log = GnssInsLog {
        imu: Vec::with_capacity(flown.epochs.len()),
        gnss: Vec::new(),
        baro: Some(Vec::new()),
        mag: None,
        range: Some(Vec::new()),
        reference: Some(Vec::new()),
        truth: Some(Vec::new()),
    };
    for (truth, e) in flown.truth.iter().skip(1).zip(&flown.epochs) {
        let t = truth.time;
        let dt = e.imu.dt;
        log.imu.push(ImuRow {
            time: t,
            gyro_in_body: (e.imu.delta_theta / dt).into(),
            accel_in_body: (e.imu.delta_v / dt).into(),
        });
        if let Some(epoch) = &e.gnss {
            let pairs: Vec<(Vector3<f64>, f64)> = epoch
                .sats
                .iter()
                .filter_map(|s| s.pseudorange_m.map(|rho| (s.pos_ecef, rho)))
                .collect();
            if pairs.len() >= 4
                && let Ok(sol) = solve_spp(frame, &pairs)
                && sol.pos_in_nav.iter().all(|c| c.is_finite())
            {
                let (ll, alt) = geo(&sol.pos_in_nav);
                log.gnss.push(GnssRow {
                    time: t,
                    lat_lon: ll,
                    altitude: alt,
                    h_acc: sigma_rho * sol.dop.hdop / 2f64.sqrt(),
                    v_acc: sigma_rho * sol.dop.vdop,
                    vel_in_nav: [0.0; 3],
                    speed_acc: 100.0,
                    fix_type: 3,
                    satellites: pairs.len() as u32,
                });
            }
        }
        if let Some(r) = &e.ranges {
            if let Some(b) = log.baro.as_mut() {
                b.push((t, origin[2] + r.baro.height_m));
            }
            if let Some(rows) = log.range.as_mut() {
                rows.extend(r.returns.iter().map(|b| RangeRow {
                    time: t,
                    distance: b.reading.range_m,
                    orientation: 100,
                    beam_in_body: Some(b.reading.dir_in_body.into()),
                }));
            }
        }
    }
    let every = prep.checked.steps.eval.max(1);
    for truth in flown.truth.iter().step_by(every) {
        let (ll, alt) = geo(&truth.pos_in_nav);
        let (roll, pitch, yaw) = truth.nav_from_body.euler_angles();
        let row = TrackRow {
            time: truth.time,
            lat_lon: ll,
            altitude: alt,
            vel_in_nav: truth.vel_in_nav.into(),
            euler: Some([roll, pitch, yaw]),
        };
        if let Some(r) = log.reference.as_mut() {
            r.push(row);
        }
        if let Some(r) = log.truth.as_mut() {
            r.push(TrackRow { euler: None, ..row });
        }
    }
    if log.range.as_ref().is_some_and(Vec::is_empty) {
        log.range = None;
    }
    Ok(SimulatedFlight {
        log,
        world_obj: obj_text(&world.mesh),
        origin,
        rest_s: prep.checked.rest_s,
    })
}
