//! The map-aware sensors against geometry built with `fathom-map` (a dev-dependency:
//! the sensors themselves see maps only through `fathom_core::RayCaster`):
//! lidar ranges in a box room equal the analytic ones (noise off); a satellite behind
//! a building is NLOS and one above its roofline LOS; range noise std and detection
//! rates match their design within chi-square and binomial bounds (each with a
//! negative control); single-point positioning from noise-free LOS pseudoranges
//! returns the truth and the geometry's DOP.

use fathom_core::{
    Material,
    frames::{Euler, nav_from_body},
    units::deg_to_rad,
};
use fathom_map::primitives::{FaceMaterials, aabb_box, ground_plane};
use fathom_map::{BvhCaster, MeshBuilder, TriMesh};
use fathom_sensors::gnss::{Dop, GnssParams, SatState, solve_spp};
use fathom_sensors::map_range::{DetectionParams, LidarParams, RangeSensorParams};
use nalgebra::{Matrix4, Vector3, Vector4};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use statrs::distribution::{Binomial, ChiSquared, ContinuousCDF, DiscreteCDF};

fn mesh(f: impl FnOnce(&mut MeshBuilder)) -> TriMesh {
    let mut b = MeshBuilder::new();
    f(&mut b);
    b.build().unwrap().0
}

#[test]
fn lidar_scan_of_a_box_room_gives_the_analytic_ranges() {
    // room: north [-8, 12], east [-5, 15], 10 m high; lidar at (1, 2) 1 m up, yaw 30 deg
    let room = mesh(|b| {
        aabb_box(
            b,
            Vector3::new(-8.0, -5.0, -10.0),
            Vector3::new(12.0, 15.0, 0.0),
            &FaceMaterials::default(),
        )
        .unwrap()
    });
    let map = BvhCaster::new(&room);
    let lidar = LidarParams {
        sigma_m: 0.0,
        glass_extra_sigma_m: 0.0,
        opaque_detection: DetectionParams::ALWAYS,
        ..LidarParams::default()
    }
    .check()
    .unwrap();
    let pos = Vector3::new(1.0, 2.0, -1.0);
    let yaw = deg_to_rad(30.0);
    let rot = nav_from_body(&Euler::new(0.0, 0.0, yaw));
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let scan = lidar.scan(&map, &pos, &rot, &mut rng);
    assert_eq!(scan.len(), 109);
    let azimuths = LidarParams::default().azimuths_rad().unwrap();
    for (r, az) in scan.iter().zip(&azimuths) {
        let phi = yaw + az;
        let (c, s) = (phi.cos(), phi.sin());
        let mut expected = f64::INFINITY;
        if c > 0.0 {
            expected = expected.min((12.0 - pos.x) / c);
        }
        if c < 0.0 {
            expected = expected.min((-8.0 - pos.x) / c);
        }
        if s > 0.0 {
            expected = expected.min((15.0 - pos.y) / s);
        }
        if s < 0.0 {
            expected = expected.min((-5.0 - pos.y) / s);
        }
        let got = r.range_m.unwrap();
        assert!(
            (got - expected).abs() < 1e-9,
            "beam {}: {got} vs {expected}",
            r.beam
        );
        assert_eq!(r.hit.unwrap().material, Material::Opaque);
    }
}

/// A 50 m tall building north of the receiver (north 20..40 m, east -20..20 m).
fn building() -> BvhCaster {
    BvhCaster::new(&mesh(|b| {
        ground_plane(b, [-500.0, 500.0], [-500.0, 500.0], 0.0, Material::Opaque).unwrap();
        aabb_box(
            b,
            Vector3::new(20.0, -20.0, -50.0),
            Vector3::new(40.0, 20.0, 0.0),
            &FaceMaterials::default(),
        )
        .unwrap();
    }))
}

/// A satellite 20,200 km away from the receiver at the given azimuth and elevation.
fn satellite(p: &GnssParams, rx_in_nav: &Vector3<f64>, az_deg: f64, el_deg: f64) -> SatState {
    let frame = p.frame.check().unwrap();
    let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
    let dir = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), -el.sin());
    SatState {
        pos_ecef: frame.ecef_from_ned(rx_in_nav) + frame.ecef_vector(&dir) * 20_200e3,
        vel_ecef: Vector3::zeros(),
    }
}

#[test]
fn satellite_behind_a_building_is_nlos_and_above_the_roofline_los() {
    let map = building();
    let rx = Vector3::new(0.0, 0.0, -2.0);
    // roofline seen from the receiver: atan(48 / 20) = 67.4 deg
    for (p_nlos, received) in [(1.0, true), (0.0, false)] {
        let p = GnssParams {
            nlos_reception_probability: p_nlos,
            ..GnssParams::default()
        };
        let sats = [
            satellite(&p, &rx, 0.0, 30.0),   // behind the building
            satellite(&p, &rx, 0.0, 80.0),   // above the roofline
            satellite(&p, &rx, 180.0, 30.0), // the open side
            satellite(&p, &rx, 10.0, 66.0),  // just below the roofline
        ];
        let rec = p.check().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let obs = rec.observe_satellites(&map, 0.0, &sats, &rx, &Vector3::zeros(), &mut rng);
        assert_eq!(
            obs.iter().map(|o| o.los).collect::<Vec<_>>(),
            [false, true, true, false]
        );
        for o in &obs {
            assert!((o.elevation_rad.to_degrees() - [30.0, 80.0, 30.0, 66.0][o.sat]).abs() < 1e-6);
            assert_eq!(o.received, o.los || received);
            if !o.los && received {
                assert!((5.0..=60.0).contains(&o.excess_delay_m));
                let rho = o.pseudorange_m.unwrap();
                let expected = o.true_range_m + rec.clock_bias_m(0.0) + o.excess_delay_m;
                assert!((rho - expected).abs() < 30.0); // 10 sigma of 3 m
            }
        }
    }
}

/// Range readings of beam 0 looking at a wall `dist` m ahead (opaque or glass) at
/// incidence `inc_deg` (the vehicle yawed by it), and the true range.
fn wall_readings(
    material: Material,
    inc_deg: f64,
    dist: f64,
    n: usize,
    seed: u64,
) -> (Vec<Option<f64>>, f64) {
    let faces = FaceMaterials {
        south: material,
        ..FaceMaterials::default()
    };
    let map = BvhCaster::new(&mesh(|b| {
        aabb_box(
            b,
            Vector3::new(dist, -500.0, -100.0),
            Vector3::new(dist + 10.0, 500.0, 0.0),
            &faces,
        )
        .unwrap()
    }));
    let sensor = RangeSensorParams::paper_rangefinders().check().unwrap();
    let rot = nav_from_body(&Euler::new(0.0, 0.0, deg_to_rad(inc_deg)));
    let pos = Vector3::new(0.0, 0.0, -10.0);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let readings = (0..n)
        .map(|_| {
            let scan = sensor.scan(&map, &pos, &rot, &mut rng);
            let hit = scan[0].hit.unwrap();
            assert!((hit.incidence_rad.to_degrees() - inc_deg).abs() < 1e-9);
            assert_eq!(hit.material, material);
            scan[0].range_m
        })
        .collect();
    (readings, dist / deg_to_rad(inc_deg).cos())
}

/// Whether `(n - 1) s^2 / sigma^2` lies in the central 99.9 % of chi-square(n - 1).
fn std_within_chi_square(samples: &[f64], mean: f64, sigma: f64) -> bool {
    let n = samples.len() as f64;
    // the true range is known: n degrees of freedom about it
    let ss: f64 = samples.iter().map(|x| (x - mean).powi(2)).sum();
    let chi = ChiSquared::new(n).unwrap();
    let stat = ss / (sigma * sigma);
    stat > chi.inverse_cdf(0.0005) && stat < chi.inverse_cdf(0.9995)
}

#[test]
fn range_noise_std_matches_the_design_within_chi_square_bounds() {
    let sensor = RangeSensorParams::paper_rangefinders().check().unwrap();
    for (material, seed) in [(Material::Opaque, 11), (Material::Glass, 12)] {
        let (readings, r) = wall_readings(material, 0.0, 20.0, 3000, seed);
        let ranges: Vec<f64> = readings.into_iter().flatten().collect();
        assert!(ranges.len() > 2500);
        let sigma = sensor.sigma(r, material);
        let expected = 0.02 + 0.01 * 20.0 + if material.is_glass() { 0.1 } else { 0.0 };
        assert!((sigma - expected).abs() < 1e-12);
        assert!(std_within_chi_square(&ranges, r, sigma), "{material}");
        // negative control: a 10 % different design std is rejected
        assert!(
            !std_within_chi_square(&ranges, r, 1.1 * sigma),
            "{material}"
        );
        assert!(
            !std_within_chi_square(&ranges, r, 0.9 * sigma),
            "{material}"
        );
    }
}

/// Whether `k` detections of `n` lie in the central 99.9 % of Binomial(n, p).
fn count_within_binomial(k: u64, n: u64, p: f64) -> bool {
    let b = Binomial::new(p, n).unwrap();
    k >= b.inverse_cdf(0.0005) && k <= b.inverse_cdf(0.9995)
}

#[test]
fn detection_rates_match_their_probabilities_within_binomial_bounds() {
    let sensor = RangeSensorParams::paper_rangefinders().check().unwrap();
    let n = 4000;
    for (material, inc, seed) in [
        (Material::Opaque, 72.5, 21), // opaque: 0.99 up to 60 deg, 0 from 85 deg
        (Material::Opaque, 30.0, 22),
        (Material::Glass, 10.0, 23), // glass: 0.9 up to 5 deg, 0 from 15 deg
        (Material::Glass, 2.0, 24),
    ] {
        let (readings, _) = wall_readings(material, inc, 5.0, n, seed);
        let k = readings.iter().filter(|r| r.is_some()).count() as u64;
        let p = sensor.detection_probability(deg_to_rad(inc), material);
        assert!(
            count_within_binomial(k, n as u64, p),
            "{material} {inc}: {k} of {n}, p {p}"
        );
        // negative control: 5 points of probability off is rejected
        let off = if p > 0.5 { p - 0.05 } else { p + 0.05 };
        assert!(!count_within_binomial(k, n as u64, off), "{material} {inc}");
    }
    // glass beyond 15 deg: never a return, though the beam hits it
    let (readings, _) = wall_readings(Material::Glass, 30.0, 5.0, 500, 25);
    assert!(readings.iter().all(Option::is_none));
}

#[test]
fn spp_from_noise_free_los_pseudoranges_returns_the_truth_and_the_geometry_dop() {
    let p = GnssParams {
        pseudorange_sigma_m: 0.0,
        range_rate_sigma_mps: 0.0,
        epoch_offset_s: 7200.0,
        ..GnssParams::default()
    };
    let rec = p.check().unwrap();
    let open = BvhCaster::new(&TriMesh::empty());
    let truth = Vector3::new(35.0, -12.0, -20.0);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for t in [0.0, 600.0, 3000.0] {
        let obs = rec.observe(&open, t, &truth, &Vector3::new(1.0, 2.0, 0.0), &mut rng);
        assert!(obs.len() >= 5 && obs.iter().all(|o| o.los && o.received));
        let pairs: Vec<_> = obs
            .iter()
            .map(|o| (o.state.pos_ecef, o.pseudorange_m.unwrap()))
            .collect();
        let fix = solve_spp(rec.frame(), &pairs).unwrap();
        assert!(
            (fix.pos_in_nav - truth).norm() < 1e-6,
            "{:?}",
            fix.pos_in_nav - truth
        );
        assert!((fix.clock_bias_m - rec.clock_bias_m(t)).abs() < 1e-6);
        // DOP from azimuth / elevation in east-north-up, computed independently
        let mut g = Matrix4::zeros();
        for o in &obs {
            let (az, el) = (o.azimuth_rad, o.elevation_rad);
            let row = Vector4::new(el.cos() * az.sin(), el.cos() * az.cos(), el.sin(), 1.0);
            g += row * row.transpose();
        }
        let q = g.try_inverse().unwrap();
        let expected = Dop {
            gdop: q.trace().sqrt(),
            pdop: (q[(0, 0)] + q[(1, 1)] + q[(2, 2)]).sqrt(),
            hdop: (q[(0, 0)] + q[(1, 1)]).sqrt(),
            vdop: q[(2, 2)].sqrt(),
            tdop: q[(3, 3)].sqrt(),
        };
        for (a, b) in [
            (fix.dop.gdop, expected.gdop),
            (fix.dop.pdop, expected.pdop),
            (fix.dop.hdop, expected.hdop),
            (fix.dop.vdop, expected.vdop),
            (fix.dop.tdop, expected.tdop),
        ] {
            assert!((a - b).abs() < 1e-6 * b, "{a} vs {b}");
        }
        // Doppler: the range rate of a noise-free observation
        let o = &obs[0];
        let v_rx = rec.frame().ecef_vector(&Vector3::new(1.0, 2.0, 0.0));
        let u = (o.state.pos_ecef - rec.frame().ecef_from_ned(&truth)).normalize();
        let rate = u.dot(&(o.state.vel_ecef - v_rx)) + 0.5;
        assert!((o.range_rate_mps.unwrap() - rate).abs() < 1e-9);
        assert!(o.doppler_hz().unwrap().abs() < 6000.0);
    }
    // three satellites are not enough
    let few = [(Vector3::new(2e7, 0.0, 0.0), 2e7); 3];
    assert!(solve_spp(rec.frame(), &few).is_err());
}
