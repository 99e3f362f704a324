//! Per-step cost of the INS (criterion): one strapdown step (100 Hz, moving and
//! turning at 35 deg latitude) and one 15-state error-model discretization (`F`,
//! second-order `Phi`, `G Q_c G^T` as the `vkf` ESKF does it). Run with `cargo xtask
//! bench`; see `docs/performance.md`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use fathom_ins::earth::Geodetic;
use fathom_ins::error_model::{self as em, BiasModel, Discretization, ImuErrorParams};
use fathom_ins::{ImuIncrement, InsState, Strapdown};
use nalgebra::{UnitQuaternion, Vector3};

fn state() -> InsState {
    InsState::new(
        Geodetic::new(35f64.to_radians(), 129f64.to_radians(), -50.0),
        Vector3::new(4.0, 2.5, 0.1),
        UnitQuaternion::from_euler_angles(0.02, -0.01, 0.5),
    )
}

fn strapdown_step(c: &mut Criterion) {
    let dt = 0.01;
    // 3 deg/s turn, level, ~1 g up (specific force), small accelerations.
    let inc = ImuIncrement::new(
        dt,
        Vector3::new(1e-6, -2e-6, 3f64.to_radians() * dt),
        Vector3::new(0.01 * dt, 0.15 * dt, -9.80 * dt),
    );
    let mut ins = Strapdown::new(state()).unwrap();
    ins.step(&inc).unwrap();
    let start = ins.clone();
    let mut n = 0u32;
    c.bench_function("strapdown_step", |b| {
        b.iter(|| {
            // restart every 100 000 steps (1000 s) to stay near the start point
            n += 1;
            if n == 100_000 {
                n = 0;
                ins = start.clone();
            }
            ins.step(black_box(&inc)).unwrap();
        })
    });
}

fn error_model_15(c: &mut Criterion) {
    let model = ImuErrorParams {
        accel_vrw: 3.3e-5,
        gyro_arw: 3.6e-6,
        accel_bias: BiasModel::RandomWalk { sigma_rate: 1e-7 },
        gyro_bias: BiasModel::RandomWalk { sigma_rate: 1e-10 },
    }
    .check()
    .unwrap();
    let q_c = model.noise_psd();
    let s = state();
    let f_body = Vector3::new(0.01, 0.15, -9.80);
    let dt = 0.2;
    c.bench_function("eskf_15_discretize", |b| {
        b.iter(|| {
            let st = black_box(&s);
            let f = em::error_dynamics(st, black_box(&f_body), &model);
            let phi = em::transition_matrix(&f, dt, Discretization::SecondOrder);
            let g = em::noise_input(st);
            let gqg = g * q_c * g.transpose();
            let qd = (gqg + gqg.transpose()) * (0.5 * dt);
            black_box((phi, qd))
        })
    });
}

criterion_group!(benches, strapdown_step, error_model_15);
criterion_main!(benches);
