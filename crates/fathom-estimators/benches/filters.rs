//! Per-step cost of the estimators (criterion): KF predict+update (6/3 and 9/3;
//! 6/3 also with `R` checked once and as sequential scalar updates with a diagonal `R`),
//! one EKF range update, one AS / SC / SI epoch of the beacons filter, one 15-state
//! error-state prediction. Run with `cargo xtask bench` (or `cargo bench -p
//! fathom-estimators`); see `docs/performance.md`.
//!
//! Instruction counts (repeatable on a loaded machine): with `FATHOM_CALLGRIND=<n>`
//! the binary skips criterion and runs `n` steps of each Kalman benchmark in its own
//! `#[inline(never)]` function, e.g.
//! `FATHOM_CALLGRIND=10000 valgrind --tool=callgrind --toggle-collect='*callgrind_*'
//! target/release/deps/filters-<hash>`, then instructions per step = `Ir / n`.

use std::hint::black_box;

use criterion::{BatchSize, Criterion, criterion_group};
use fathom_core::Gaussian;
use fathom_estimators::{
    GateThreshold, KalmanFilter, MeasurementNoise, ProcessNoise,
    beacon_ekf::{BeaconMeasurement, DvlAhrsInput, DvlAhrsMotion, DvlAhrsMotionParams},
    ekf::{Ekf, GroupItem},
    error_state::{ErrorCovariance, ErrorStateFilter},
    models,
    schemes::{Event, Observation, SchemeFilter, SchemeParams, UpdateScheme},
};
use nalgebra::{DMatrix, Matrix3, Matrix4, RowSVector, SMatrix, SVector, Vector3, Vector4};

const DT: f64 = 0.1;

/// One benchmark problem: `x` is `N`-dimensional, `M` measurements.
struct Problem<const N: usize, const M: usize> {
    f: SMatrix<f64, N, N>,
    q: SMatrix<f64, N, N>,
    h: SMatrix<f64, M, N>,
    r: SMatrix<f64, M, M>,
    z: SVector<f64, M>,
}

impl<const N: usize, const M: usize> Problem<N, M> {
    fn filter(&self) -> KalmanFilter<N> {
        let prior =
            Gaussian::new(SVector::<f64, N>::zeros(), SMatrix::<f64, N, N>::identity()).unwrap();
        KalmanFilter::new(prior, 0.0).unwrap()
    }

    /// One `predict(F, Q)` + `update(z, H, R)`, every input unchecked before the call
    /// (black-boxed, so nothing is hoisted out of the loop).
    #[inline(always)]
    fn step(&self, kf: &mut KalmanFilter<N>, t: &mut f64) {
        *t += DT;
        kf.predict(black_box(&self.f), black_box(&self.q), *t)
            .unwrap();
        black_box(
            kf.update(black_box(&self.z), black_box(&self.h), black_box(&self.r))
                .unwrap(),
        );
    }

    /// [`Problem::step`] with `R` checked once ([`MeasurementNoise`]).
    #[inline(always)]
    fn step_checked_r(&self, kf: &mut KalmanFilter<N>, t: &mut f64, noise: &MeasurementNoise<M>) {
        *t += DT;
        kf.predict(black_box(&self.f), black_box(&self.q), *t)
            .unwrap();
        black_box(
            kf.update_with_noise(black_box(&self.z), black_box(&self.h), black_box(noise))
                .unwrap(),
        );
    }

    /// [`Problem::step`] with `Q` and `R` checked once ([`ProcessNoise`],
    /// [`MeasurementNoise`]): the step of a filter with constant noise.
    #[inline(always)]
    fn step_checked_noise(
        &self,
        kf: &mut KalmanFilter<N>,
        t: &mut f64,
        (q, r): (&ProcessNoise<N>, &MeasurementNoise<M>),
    ) {
        *t += DT;
        kf.predict_with_noise(black_box(&self.f), black_box(q), *t)
            .unwrap();
        black_box(
            kf.update_with_noise(black_box(&self.z), black_box(&self.h), black_box(r))
                .unwrap(),
        );
    }

    /// [`Problem::step`] with a diagonal `R` (the diagonal of `self.r`) as `M` scalar
    /// Joseph updates (`update_sequential_scalar`, `O(N^2)` each).
    #[inline(always)]
    fn step_sequential(&self, kf: &mut KalmanFilter<N>, t: &mut f64, rows: &[RowSVector<f64, N>]) {
        *t += DT;
        kf.predict(black_box(&self.f), black_box(&self.q), *t)
            .unwrap();
        let r_diag: [f64; M] = std::array::from_fn(|i| self.r[(i, i)]);
        black_box(
            kf.update_sequential_scalar(
                black_box(self.z.as_slice()),
                black_box(rows),
                black_box(&r_diag),
                None,
            )
            .unwrap(),
        );
    }

    /// The textbook step in plain nalgebra, no checks, standard Joseph product form
    /// (what "a fixed-size nalgebra filter" costs).
    #[inline(always)]
    fn reference_step(&self, x: &mut SVector<f64, N>, p: &mut SMatrix<f64, N, N>) {
        let (f, q, h, r, z) = (
            black_box(&self.f),
            black_box(&self.q),
            black_box(&self.h),
            black_box(&self.r),
            black_box(&self.z),
        );
        *x = f * *x;
        *p = f * *p * f.transpose() + q;
        let pht = *p * h.transpose();
        let s = h * pht + r;
        let k = pht * s.try_inverse().unwrap();
        *x += k * (z - h * *x);
        let a = SMatrix::<f64, N, N>::identity() - k * h;
        *p = a * *p * a.transpose() + k * r * k.transpose();
        black_box(&*p);
    }
}

/// 3-D constant velocity: x = [p, v], z = p + noise (6 states, 3 measurements), a
/// dense correlated `R`.
fn cv_6_3() -> Problem<6, 3> {
    Problem {
        f: models::cv_transition_3d(DT).unwrap(),
        q: models::cv_white_accel_q_3d(DT, [0.1, 0.1, 0.05]).unwrap(),
        h: models::cv_position_h_3d(),
        r: Matrix3::new(0.25, 0.02, 0.0, 0.02, 0.25, 0.01, 0.0, 0.01, 0.5),
        z: Vector3::new(1.0, -2.0, 0.5),
    }
}

/// 3-D constant acceleration: x = [p, v, a], z = p + noise (9 states, 3
/// measurements), diagonal `R`.
fn ca_9_3() -> Problem<9, 3> {
    let mut f = SMatrix::<f64, 9, 9>::identity();
    let mut q = SMatrix::<f64, 9, 9>::zeros();
    let s = 0.05; // jerk PSD
    for i in 0..3 {
        f[(i, 3 + i)] = DT;
        f[(i, 6 + i)] = 0.5 * DT * DT;
        f[(3 + i, 6 + i)] = DT;
        let (d5, d4, d3, d2) = (DT.powi(5), DT.powi(4), DT.powi(3), DT * DT);
        let blk = [
            [d5 / 20.0, d4 / 8.0, d3 / 6.0],
            [d4 / 8.0, d3 / 3.0, d2 / 2.0],
            [d3 / 6.0, d2 / 2.0, DT],
        ];
        for a in 0..3 {
            for bb in 0..3 {
                q[(3 * a + i, 3 * bb + i)] = s * blk[a][bb];
            }
        }
    }
    let mut h = SMatrix::<f64, 3, 9>::zeros();
    h.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&Matrix3::identity());
    Problem {
        f,
        q,
        h,
        r: Matrix3::from_diagonal(&Vector3::new(0.25, 0.25, 0.5)),
        z: Vector3::new(1.0, -2.0, 0.5),
    }
}

fn kf_6_3(c: &mut Criterion) {
    let pb = cv_6_3();
    let (mut kf, mut t) = (pb.filter(), 0.0);
    c.bench_function("kf_6x3_predict_update", |b| {
        b.iter(|| pb.step(&mut kf, &mut t))
    });
    let (mut x, mut p) = (SVector::<f64, 6>::zeros(), SMatrix::<f64, 6, 6>::identity());
    c.bench_function("nalgebra_reference_6x3_predict_update", |b| {
        b.iter(|| pb.reference_step(&mut x, &mut p))
    });
    let noise = MeasurementNoise::new(pb.r).unwrap();
    let (mut kf, mut t) = (pb.filter(), 0.0);
    c.bench_function("kf_6x3_predict_update_checked_r", |b| {
        b.iter(|| pb.step_checked_r(&mut kf, &mut t, &noise))
    });
    let q_checked = ProcessNoise::new(pb.q).unwrap();
    let (mut kf, mut t) = (pb.filter(), 0.0);
    c.bench_function("kf_6x3_predict_update_checked_noise", |b| {
        b.iter(|| pb.step_checked_noise(&mut kf, &mut t, (&q_checked, &noise)))
    });
    let rows: Vec<RowSVector<f64, 6>> = (0..3).map(|i| pb.h.row(i).into_owned()).collect();
    let (mut kf, mut t) = (pb.filter(), 0.0);
    c.bench_function("kf_6x3_predict_update_sequential_diag_r", |b| {
        b.iter(|| pb.step_sequential(&mut kf, &mut t, &rows))
    });
}

fn kf_9_3(c: &mut Criterion) {
    let pb = ca_9_3();
    let (mut kf, mut t) = (pb.filter(), 0.0);
    c.bench_function("kf_9x3_predict_update", |b| {
        b.iter(|| pb.step(&mut kf, &mut t))
    });
}

#[inline(never)]
fn callgrind_kf_6x3(pb: &Problem<6, 3>, n: usize) {
    let (mut kf, mut t) = (pb.filter(), 0.0);
    for _ in 0..n {
        pb.step(&mut kf, &mut t);
    }
}

#[inline(never)]
fn callgrind_kf_6x3_checked_r(pb: &Problem<6, 3>, n: usize) {
    let (mut kf, mut t) = (pb.filter(), 0.0);
    let noise = MeasurementNoise::new(pb.r).unwrap();
    for _ in 0..n {
        pb.step_checked_r(&mut kf, &mut t, &noise);
    }
}

#[inline(never)]
fn callgrind_kf_6x3_checked_noise(pb: &Problem<6, 3>, n: usize) {
    let (mut kf, mut t) = (pb.filter(), 0.0);
    let noise = (
        ProcessNoise::new(pb.q).unwrap(),
        MeasurementNoise::new(pb.r).unwrap(),
    );
    for _ in 0..n {
        pb.step_checked_noise(&mut kf, &mut t, (&noise.0, &noise.1));
    }
}

#[inline(never)]
fn callgrind_kf_6x3_sequential(pb: &Problem<6, 3>, n: usize) {
    let (mut kf, mut t) = (pb.filter(), 0.0);
    let rows: Vec<RowSVector<f64, 6>> = (0..3).map(|i| pb.h.row(i).into_owned()).collect();
    for _ in 0..n {
        pb.step_sequential(&mut kf, &mut t, &rows);
    }
}

#[inline(never)]
fn callgrind_reference_6x3(pb: &Problem<6, 3>, n: usize) {
    let (mut x, mut p) = (SVector::<f64, 6>::zeros(), SMatrix::<f64, 6, 6>::identity());
    for _ in 0..n {
        pb.reference_step(&mut x, &mut p);
    }
}

#[inline(never)]
fn callgrind_kf_9x3(pb: &Problem<9, 3>, n: usize) {
    let (mut kf, mut t) = (pb.filter(), 0.0);
    for _ in 0..n {
        pb.step(&mut kf, &mut t);
    }
}

const BEACONS: [[f64; 3]; 4] = [
    [15.0, 15.0, 0.0],
    [-15.0, 15.0, 40.0],
    [-15.0, -15.0, 0.0],
    [15.0, -15.0, 40.0],
];

fn motion() -> DvlAhrsMotion {
    DvlAhrsMotionParams {
        vel_sigma: [0.14, 0.05, 0.18],
        vel_hold: 0.1,
        yaw_rate_sigma: 0.14,
        yaw_rate_hold: 0.1,
    }
    .check()
    .unwrap()
}

fn beacon_ekf() -> Ekf<4, DvlAhrsMotion> {
    let prior = Gaussian::new(
        Vector4::new(1.0, -0.5, 3.0, 0.3),
        Matrix4::from_diagonal(&Vector4::new(0.04, 0.05, 0.03, 0.01)),
    )
    .unwrap();
    let input = DvlAhrsInput {
        vel_in_body: Vector3::new(0.5, 0.0, 0.2),
        yaw_rate: 0.05,
    };
    Ekf::new(prior, 0.0, motion(), input).unwrap()
}

fn model(c: usize) -> BeaconMeasurement {
    if c < 4 {
        BeaconMeasurement::Range {
            beacon_in_nav: Vector3::from(BEACONS[c]),
        }
    } else {
        BeaconMeasurement::Depth
    }
}

/// One gated scalar range update of the 4-state beacon EKF.
fn ekf_range(c: &mut Criterion) {
    let ekf = beacon_ekf();
    let m = model(0);
    let z = 21.0;
    let gate = Some(GateThreshold::from_sigma_distance(2.5).unwrap());
    c.bench_function("ekf_range_update", |b| {
        b.iter_batched_ref(
            || ekf.clone(),
            |f| {
                let item = GroupItem {
                    value: black_box(z),
                    model: &m,
                    variance: 0.01,
                    gate,
                };
                black_box(f.update_sequential(&[item]).unwrap());
            },
            BatchSize::SmallInput,
        )
    });
}

/// One epoch of the beacons filter: 4 ranges and a depth (stamped 3 ms before the
/// epoch), then advance to the epoch (DVL/AHRS dead reckoning).
fn beacon_epochs(c: &mut Criterion) {
    let truth = Vector4::new(1.0, -0.5, 3.0, 0.3);
    let z: [f64; 5] = std::array::from_fn(|ch| {
        use fathom_estimators::ekf::ScalarModel;
        model(ch).evaluate(&truth).unwrap().0 + 0.05
    });
    let gate = Some(GateThreshold::from_sigma_distance(2.5).unwrap());
    let sigma_c2 = 0.05_f64.powi(2);
    let cov = DMatrix::from_fn(5, 5, |i, j| match (i, j) {
        (4, 4) => 0.04,
        (4, _) | (_, 4) => 0.0,
        _ if i == j => 0.01 + sigma_c2,
        _ => sigma_c2,
    });
    for (scheme, name) in [
        (UpdateScheme::Asynchronous, "beacons_epoch_as"),
        (UpdateScheme::SynchronousCollective, "beacons_epoch_sc"),
        (UpdateScheme::SynchronousIndividual, "beacons_epoch_si"),
    ] {
        let config = SchemeParams {
            scheme,
            epoch_period: 0.1,
            stale_tolerance: 0.0,
            channel_cov: cov.clone(),
            gates: vec![gate, gate, gate, gate, None],
        }
        .check()
        .unwrap();
        let filter: SchemeFilter<4, DvlAhrsMotion, BeaconMeasurement> =
            SchemeFilter::new(beacon_ekf(), config);
        c.bench_function(name, |b| {
            b.iter_batched_ref(
                || filter.clone(),
                |f| {
                    for (ch, &value) in z.iter().enumerate() {
                        f.process(Event::Measurement(Observation {
                            channel: ch,
                            stamp: 0.097,
                            value: black_box(value),
                            model: model(ch),
                            tag: ch,
                        }))
                        .unwrap();
                    }
                    f.advance_to(0.1).unwrap();
                },
                BatchSize::SmallInput,
            )
        });
    }
}

/// One 15-state error-state covariance prediction `P = Phi P Phi^T + Q_d` with a
/// dense, realistic `Phi` (second-order) and `Q_d`.
fn eskf_predict(c: &mut Criterion) {
    let p0 = ErrorStateFilter::diagonal_covariance([3.0, 0.1, 1e-3, 1e-3, 1e-6]);
    let mut f = ErrorCovariance::zeros();
    for i in 0..15 {
        for j in 0..15 {
            f[(i, j)] = 1e-3 * (((i * 7 + j * 3) % 11) as f64 - 5.0);
        }
    }
    let fdt = f * 0.2;
    let phi = ErrorCovariance::identity() + fdt + fdt * fdt * 0.5;
    let qd = ErrorCovariance::from_diagonal(&SVector::<f64, 15>::from_fn(|i, _| {
        1e-8 * (1.0 + i as f64)
    }));
    let filter = ErrorStateFilter::new(&p0, 0.0).unwrap();
    c.bench_function("eskf_15_predict", |b| {
        b.iter_batched_ref(
            || filter.clone(),
            |f| f.predict(black_box(&phi), black_box(&qd), 0.2).unwrap(),
            BatchSize::SmallInput,
        )
    });
}

criterion_group!(
    benches,
    kf_6_3,
    kf_9_3,
    ekf_range,
    beacon_epochs,
    eskf_predict
);

/// Fastest and median time per step over many short batches (500 steps, ~0.1-1 ms):
/// on a loaded machine most batches run without being preempted, so the fastest
/// batch is close to the unloaded cost (`FATHOM_MIN_BATCH=1`; development aid, the
/// reported numbers are criterion's).
fn min_batch_times() {
    fn report(name: &str, mut batch: impl FnMut()) {
        let mut times: Vec<f64> = (0..3000)
            .map(|_| {
                let start = std::time::Instant::now();
                batch();
                start.elapsed().as_secs_f64() * 1e9 / 500.0
            })
            .collect();
        times.sort_by(f64::total_cmp);
        println!(
            "{name:<40} fastest {:8.1} ns  p10 {:8.1} ns  median {:8.1} ns",
            times[0],
            times[times.len() / 10],
            times[times.len() / 2]
        );
    }
    let pb = cv_6_3();
    let (mut kf, mut t) = (pb.filter(), 0.0);
    report("kf_6x3_predict_update", || {
        for _ in 0..500 {
            pb.step(&mut kf, &mut t);
        }
    });
    let (mut kf, mut t) = (pb.filter(), 0.0);
    report("  of which predict", || {
        for _ in 0..500 {
            t += DT;
            kf.predict(black_box(&pb.f), black_box(&pb.q), t).unwrap();
        }
    });
    let mut kf = pb.filter();
    report("  of which update", || {
        for _ in 0..500 {
            black_box(
                kf.update(black_box(&pb.z), black_box(&pb.h), black_box(&pb.r))
                    .unwrap(),
            );
        }
    });
    let (mut x, mut p) = (SVector::<f64, 6>::zeros(), SMatrix::<f64, 6, 6>::identity());
    report("nalgebra_reference_6x3_predict_update", || {
        for _ in 0..500 {
            pb.reference_step(&mut x, &mut p);
        }
    });
    let noise = MeasurementNoise::new(pb.r).unwrap();
    let (mut kf, mut t) = (pb.filter(), 0.0);
    report("kf_6x3_predict_update_checked_r", || {
        for _ in 0..500 {
            pb.step_checked_r(&mut kf, &mut t, &noise);
        }
    });
    let q_checked = ProcessNoise::new(pb.q).unwrap();
    let (mut kf, mut t) = (pb.filter(), 0.0);
    report("kf_6x3_predict_update_checked_noise", || {
        for _ in 0..500 {
            pb.step_checked_noise(&mut kf, &mut t, (&q_checked, &noise));
        }
    });
    let pb = ca_9_3();
    let (mut kf, mut t) = (pb.filter(), 0.0);
    report("kf_9x3_predict_update", || {
        for _ in 0..500 {
            pb.step(&mut kf, &mut t);
        }
    });
}

fn main() {
    if let Some(n) = std::env::var("FATHOM_CALLGRIND")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        // Fixed work for instruction counting (see the module docs); no criterion.
        callgrind_kf_6x3(&cv_6_3(), n);
        callgrind_kf_6x3_checked_r(&cv_6_3(), n);
        callgrind_kf_6x3_checked_noise(&cv_6_3(), n);
        callgrind_kf_6x3_sequential(&cv_6_3(), n);
        callgrind_reference_6x3(&cv_6_3(), n);
        callgrind_kf_9x3(&ca_9_3(), n);
        return;
    }
    if std::env::var_os("FATHOM_MIN_BATCH").is_some() {
        min_batch_times();
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
