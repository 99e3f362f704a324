//! Linear / extended Kalman filter with a fixed-size state: prediction, Joseph-form
//! update, gated update and sequential scalar updates. No heap allocation on the
//! fixed-size path (errors aside).

use crate::{
    EstimatorError, MeasurementNoise, ProcessNoise,
    error::{check_finite, check_finite_entries},
    gating::{Gate, GateThreshold, UpdateInfo},
    lanes::Isa,
    linalg,
    noise::check_process_noise,
    simd,
};
use fathom_core::{
    Gaussian, Time,
    gaussian::{check_covariance, symmetrize},
};
use nalgebra::{Matrix1, RowSVector, SMatrix, SVector};

/// One scalar measurement for [`KalmanFilter::update_sequential_scalar_with`]:
/// innovation `nu = z - h(x)`, Jacobian row `h` and noise variance `r`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalarMeasurement<const N: usize> {
    /// Innovation `z - h(x)` at the current (partially updated) state.
    pub innovation: f64,
    /// Measurement row `H_i` (Jacobian of `h` for an EKF).
    pub h_row: RowSVector<f64, N>,
    /// Measurement noise variance `r_i > 0`.
    pub variance: f64,
}

/// Outcome of one scalar step of a sequential update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalarOutcome {
    /// Innovation `nu_i`.
    pub innovation: f64,
    /// Innovation variance `S_i = H_i P H_i^T + r_i` (with `P` after the previous scalars).
    pub innovation_var: f64,
    /// `nu_i^2 / S_i`.
    pub nis: f64,
    /// Whether the scalar passed the gate and was applied.
    pub accepted: bool,
}

/// Report of a sequential scalar update, one outcome per measurement in order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SequentialReport {
    /// Outcomes in the order the scalars were processed.
    pub outcomes: Vec<ScalarOutcome>,
}

impl SequentialReport {
    /// Indices of the rejected scalars.
    pub fn rejected(&self) -> impl Iterator<Item = usize> + '_ {
        self.outcomes
            .iter()
            .enumerate()
            .filter(|(_, o)| !o.accepted)
            .map(|(i, _)| i)
    }

    /// Number of applied scalars.
    pub fn num_accepted(&self) -> usize {
        self.outcomes.iter().filter(|o| o.accepted).count()
    }
}

/// A Kalman filter with an `N`-dimensional state `x`, covariance `P` and the time
/// stamp `time` (s) the estimate refers to.
///
/// Invariants kept by every method: `x` finite, `P` finite, exactly symmetric and
/// positive definite (Cholesky succeeds). A failing step returns an error and leaves
/// `x`, `P` and `time` unchanged.
///
/// Equations (Bar-Shalom et al., Joseph form):
/// - predict: `x = F x (+ B u)`, `P = F P F^T + (Q + Q^T) / 2` (exactly symmetric);
/// - update: `S = H P H^T + R`, `K = P H^T S^-1` (`S^-1 = adj(S) / det S` for up to 3
///   measurements, else `S = L D L^T` and triangular solves), `nis = nu^T S^-1 nu`, `x = x + K nu`, `P = (I - K H) P (I - K H)^T + K R K^T`
///   (expanded Joseph form, exactly symmetric; see `linalg::joseph_update`).
///
/// Checks: a step computes first and then makes ONE validity test of all it needs
/// (`Q`'s diagonal and symmetry, `R` valid, `S` positive definite, the NIS and the
/// new `x` finite, the new `P` positive definite). A non-finite input entry always
/// reaches one of the tested quantities (see the kernel docs in `linalg`), so the
/// fast test fails for it; then the inputs are checked one by one in the documented
/// order, which returns the same error (variant, `what`, index, time) as checking
/// up front would, and the filter is not modified. String formatting happens only
/// on that path.
///
/// Cost: both covariance steps form one triangle and mirror it; the Joseph update is
/// `O(N^2 M)` instead of `O(N^3)`; the positive-definiteness tests are a `2 x 2`-block
/// `L D L^T` (`N^3 / 6`, one division per two columns); the triangular kernels are
/// unrolled for `N <= 16`; the kernels run with AVX2 when the CPU has it
/// ([`crate::simd`], bit-identical results). A constant `R` or `Q` can be checked once
/// with [`MeasurementNoise`] ([`KalmanFilter::update_with_noise`]) or [`ProcessNoise`]
/// ([`KalmanFilter::predict_with_noise`]). See `docs/performance.md`.
#[derive(Clone)]
pub struct KalmanFilter<const N: usize> {
    x: SVector<f64, N>,
    /// Two covariance buffers: `p[active]` is `P`; a step writes the new `P` into
    /// the other one and flips `active` only when it succeeds, so nothing is copied
    /// and a failing step leaves `P` as it was.
    p: [SMatrix<f64, N, N>; 2],
    active: usize,
    time: Time,
}

impl<const N: usize> PartialEq for KalmanFilter<N> {
    /// Equal state, covariance and time (the spare covariance buffer is not compared).
    fn eq(&self, other: &Self) -> bool {
        self.x == other.x && self.covariance() == other.covariance() && self.time == other.time
    }
}

impl<const N: usize> std::fmt::Debug for KalmanFilter<N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KalmanFilter")
            .field("x", &self.x)
            .field("p", self.covariance())
            .field("time", &self.time)
            .finish()
    }
}

/// Everything computed before the gate decision (shared by all update flavours).
struct Prepared<const N: usize, const M: usize> {
    pht: SMatrix<f64, N, M>,
    s: SMatrix<f64, M, M>,
    solver: linalg::SpdSolver<M>,
    nis: f64,
}

impl<const N: usize> KalmanFilter<N> {
    /// A filter starting from the prior `prior` at time `time`.
    ///
    /// # Errors
    /// [`EstimatorError::NonFinite`] for a non-finite time or mean, or a covariance
    /// error naming "initial covariance P0" (the Gaussian is re-checked, it may have
    /// been built unchecked).
    pub fn new(prior: Gaussian<N>, time: Time) -> Result<Self, EstimatorError> {
        check_time("initial time", time, time)?;
        let (x, p) = prior.into_parts();
        check_finite("initial state x0", x.as_slice(), N, 1, time)?;
        check_covariance("initial covariance P0", &p)
            .map_err(|e| EstimatorError::from_core_at(e, time))?;
        let p = symmetrize(&p);
        Ok(Self {
            x,
            p: [p, p],
            active: 0,
            time,
        })
    }

    /// `(P, the spare buffer)`.
    #[inline(always)]
    fn covariance_and_spare(&mut self) -> (&SMatrix<f64, N, N>, &mut SMatrix<f64, N, N>) {
        let [p0, p1] = &mut self.p;
        if self.active == 0 { (p0, p1) } else { (p1, p0) }
    }

    /// Makes the spare buffer `P` (after it was written and checked).
    #[inline(always)]
    fn flip(&mut self) {
        self.active ^= 1;
    }

    /// The state estimate `x`.
    pub fn state(&self) -> &SVector<f64, N> {
        &self.x
    }

    /// The covariance `P`.
    pub fn covariance(&self) -> &SMatrix<f64, N, N> {
        &self.p[self.active]
    }

    /// The time stamp (s) of the estimate.
    pub fn time(&self) -> Time {
        self.time
    }

    /// The estimate as a Gaussian (the filter keeps the covariance invariants).
    pub fn estimate(&self) -> Gaussian<N> {
        Gaussian::new_unchecked(self.x, *self.covariance())
    }

    /// Replaces the state `x`, keeping `P` and the time (e.g. the equalized state of
    /// the EFF structure, paper A step 2, or an external reset).
    ///
    /// # Errors
    /// [`EstimatorError::NonFinite`] naming "state x"; the filter is unchanged.
    pub fn set_state(&mut self, x: SVector<f64, N>) -> Result<(), EstimatorError> {
        check_finite("state x", x.as_slice(), N, 1, self.time)?;
        self.x = x;
        Ok(())
    }

    /// Replaces state and covariance, keeping the time.
    ///
    /// # Errors
    /// As [`KalmanFilter::new`], naming "state x" / "covariance P"; the filter is unchanged.
    pub fn set_estimate(&mut self, estimate: Gaussian<N>) -> Result<(), EstimatorError> {
        let (x, p) = estimate.into_parts();
        check_finite("state x", x.as_slice(), N, 1, self.time)?;
        check_covariance("covariance P", &p)
            .map_err(|e| EstimatorError::from_core_at(e, self.time))?;
        self.x = x;
        self.p[self.active] = symmetrize(&p);
        Ok(())
    }

    /// Predicts to `new_time`: `x = F x`, `P = F P F^T + Q` (symmetrized).
    ///
    /// `F` and `Q` are the discrete model for the step `new_time - time()` (see
    /// [`crate::models`]); `Q` must be symmetric with a non-negative diagonal
    /// (positive semi-definite is enough, the result must be positive definite).
    ///
    /// # Errors
    /// [`EstimatorError::TimeBackwards`] if `new_time < time()`, non-finite or
    /// non-symmetric inputs, or [`EstimatorError::NotPositiveDefinite`] for
    /// "predicted covariance P"; errors carry `new_time` and leave the filter unchanged.
    pub fn predict(
        &mut self,
        f: &SMatrix<f64, N, N>,
        q: &SMatrix<f64, N, N>,
        new_time: Time,
    ) -> Result<(), EstimatorError> {
        self.predict_linear(f, q, true, new_time)
    }

    /// [`KalmanFilter::predict`] with a process noise checked once
    /// ([`ProcessNoise`]): the same numbers, without re-checking `Q` every step.
    ///
    /// # Errors
    /// As [`KalmanFilter::predict`], except that `Q` is not re-checked.
    pub fn predict_with_noise(
        &mut self,
        f: &SMatrix<f64, N, N>,
        noise: &ProcessNoise<N>,
        new_time: Time,
    ) -> Result<(), EstimatorError> {
        self.predict_linear(f, noise.matrix(), false, new_time)
    }

    /// `x = F x`, then [`KalmanFilter::predict_core`]: [`KalmanFilter::predict`]
    /// (`check_q`) and [`KalmanFilter::predict_with_noise`] (`Q` checked already).
    #[inline(always)]
    fn predict_linear(
        &mut self,
        f: &SMatrix<f64, N, N>,
        q: &SMatrix<f64, N, N>,
        check_q: bool,
        new_time: Time,
    ) -> Result<(), EstimatorError> {
        check_time("predict", new_time, self.time)?;
        let x_pred = linalg::mat_vec(f, &self.x);
        self.predict_core(x_pred, f, q, check_q, new_time, || {
            check_finite("transition matrix F", f.as_slice(), N, N, new_time)
        })
    }

    /// Predicts with a control input: `x = F x + B u`, `P = F P F^T + Q`.
    ///
    /// # Errors
    /// As [`KalmanFilter::predict`], plus non-finite `B` ("control matrix B") or
    /// `u` ("control input u").
    pub fn predict_with_control<const U: usize>(
        &mut self,
        f: &SMatrix<f64, N, N>,
        b: &SMatrix<f64, N, U>,
        u: &SVector<f64, U>,
        q: &SMatrix<f64, N, N>,
        new_time: Time,
    ) -> Result<(), EstimatorError> {
        check_time("predict", new_time, self.time)?;
        let x_pred = f * self.x + b * u;
        self.predict_core(x_pred, f, q, true, new_time, || {
            check_finite("transition matrix F", f.as_slice(), N, N, new_time)?;
            check_finite("control matrix B", b.as_slice(), N, U, new_time)?;
            check_finite("control input u", u.as_slice(), U, 1, new_time)
        })
    }

    /// EKF prediction: the caller propagates the state through its nonlinear model,
    /// `x_pred = f(x, u)`, and gives the Jacobian `F = df/dx`; `P = F P F^T + Q`.
    ///
    /// # Errors
    /// As [`KalmanFilter::predict`], plus non-finite "predicted state x".
    pub fn predict_nonlinear(
        &mut self,
        x_pred: &SVector<f64, N>,
        f_jacobian: &SMatrix<f64, N, N>,
        q: &SMatrix<f64, N, N>,
        new_time: Time,
    ) -> Result<(), EstimatorError> {
        check_time("predict", new_time, self.time)?;
        self.predict_core(*x_pred, f_jacobian, q, true, new_time, || {
            check_finite(
                "transition Jacobian F",
                f_jacobian.as_slice(),
                N,
                N,
                new_time,
            )
        })
    }

    /// The shared prediction: computes `P = F P F^T + Q`, then ONE validity test of
    /// everything (`Q`'s diagonal and symmetry, `x_pred` finite, `P` positive
    /// definite, which also rejects a non-finite `F` or `Q`, see
    /// [`linalg::propagate_covariance`]); only when it fails are the checks run one by
    /// one in the documented order (`input_checks` first: `F`, `B`, `u`), to return
    /// the same error as checking each input up front.
    #[inline(always)]
    fn predict_core(
        &mut self,
        x_pred: SVector<f64, N>,
        f: &SMatrix<f64, N, N>,
        q: &SMatrix<f64, N, N>,
        check_q: bool,
        new_time: Time,
        input_checks: impl FnOnce() -> Result<(), EstimatorError>,
    ) -> Result<(), EstimatorError> {
        simd::dispatch(
            #[inline(always)]
            |isa| {
                let (p, p_pred) = self.covariance_and_spare();
                let q_ok = linalg::propagate_covariance(isa, f, p, q, check_q, p_pred);
                if !(q_ok
                    && linalg::all_finite(x_pred.as_slice())
                    && linalg::is_positive_definite(p_pred))
                {
                    return Err(prediction_error(input_checks, &x_pred, q, p_pred, new_time));
                }
                self.x = x_pred;
                self.flip();
                self.time = new_time;
                Ok(())
            },
        )
    }

    /// Linear update with measurement `z = H x + v`, `v ~ N(0, R)`, at the filter time
    /// (Joseph form, see the type docs).
    ///
    /// # Errors
    /// Non-finite `z` ("measurement z"), `H` ("measurement matrix H") or `R`;
    /// `R` not symmetric / not positive definite ("measurement noise R");
    /// "innovation covariance S" or "updated covariance P" not positive definite.
    /// Errors carry `time()` and leave the filter unchanged.
    pub fn update<const M: usize>(
        &mut self,
        z: &SVector<f64, M>,
        h: &SMatrix<f64, M, N>,
        r: &SMatrix<f64, M, M>,
    ) -> Result<UpdateInfo<M>, EstimatorError> {
        simd::dispatch(
            #[inline(always)]
            |isa| {
                let nu = linalg::innovation_of(z, h, &self.x);
                let prep =
                    self.prepare(isa, &nu, h, r, true, || measurement_checks(z, h, self.time))?;
                self.apply(isa, &nu, prep)
            },
        )
    }

    /// Update with a given innovation `nu` (EKF: `nu = z - h(x)`, `H = dh/dx` at `x`);
    /// same code path as [`KalmanFilter::update`].
    ///
    /// # Errors
    /// As [`KalmanFilter::update`], naming "innovation nu" instead of "measurement z".
    pub fn update_with_innovation<const M: usize>(
        &mut self,
        nu: &SVector<f64, M>,
        h: &SMatrix<f64, M, N>,
        r: &SMatrix<f64, M, M>,
    ) -> Result<UpdateInfo<M>, EstimatorError> {
        simd::dispatch(
            #[inline(always)]
            |isa| {
                let prep =
                    self.prepare(isa, nu, h, r, true, || innovation_checks(nu, h, self.time))?;
                self.apply(isa, nu, prep)
            },
        )
    }

    /// [`KalmanFilter::update`] with a measurement noise checked once at construction
    /// ([`MeasurementNoise`]): the same numbers, without re-validating `R` every step.
    ///
    /// # Errors
    /// As [`KalmanFilter::update`], except that `R` is not re-checked.
    pub fn update_with_noise<const M: usize>(
        &mut self,
        z: &SVector<f64, M>,
        h: &SMatrix<f64, M, N>,
        noise: &MeasurementNoise<M>,
    ) -> Result<UpdateInfo<M>, EstimatorError> {
        simd::dispatch(
            #[inline(always)]
            |isa| {
                let nu = linalg::innovation_of(z, h, &self.x);
                let prep = self.prepare(isa, &nu, h, noise.matrix(), false, || {
                    measurement_checks(z, h, self.time)
                })?;
                self.apply(isa, &nu, prep)
            },
        )
    }

    /// Update with a given innovation and a checked noise, optionally gated: the
    /// [`MeasurementNoise`] flavour of [`KalmanFilter::update_with_innovation`] (`gate =
    /// None`, always [`Gate::Accepted`]) and [`KalmanFilter::update_with_innovation_gated`].
    ///
    /// # Errors
    /// As [`KalmanFilter::update_with_innovation`], except that `R` is not re-checked.
    pub fn update_with_innovation_and_noise<const M: usize>(
        &mut self,
        nu: &SVector<f64, M>,
        h: &SMatrix<f64, M, N>,
        noise: &MeasurementNoise<M>,
        gate: Option<GateThreshold>,
    ) -> Result<Gate<M>, EstimatorError> {
        simd::dispatch(
            #[inline(always)]
            |isa| {
                let prep = self.prepare(isa, nu, h, noise.matrix(), false, || {
                    innovation_checks(nu, h, self.time)
                })?;
                if let Some(g) = gate
                    && !g.accepts(prep.nis)
                {
                    return Ok(Gate::Rejected { nis: prep.nis });
                }
                self.apply(isa, nu, prep).map(Gate::Accepted)
            },
        )
    }

    /// Gated linear update: computes the NIS first and applies the update only when
    /// `gate.accepts(nis)`; otherwise returns [`Gate::Rejected`] and the filter is unchanged.
    ///
    /// # Errors
    /// As [`KalmanFilter::update`].
    pub fn update_gated<const M: usize>(
        &mut self,
        z: &SVector<f64, M>,
        h: &SMatrix<f64, M, N>,
        r: &SMatrix<f64, M, M>,
        gate: GateThreshold,
    ) -> Result<Gate<M>, EstimatorError> {
        simd::dispatch(
            #[inline(always)]
            |isa| {
                let nu = linalg::innovation_of(z, h, &self.x);
                let prep =
                    self.prepare(isa, &nu, h, r, true, || measurement_checks(z, h, self.time))?;
                self.gated_apply(isa, &nu, prep, gate)
            },
        )
    }

    /// Gated update with a given innovation (EKF flavour of [`KalmanFilter::update_gated`]).
    ///
    /// # Errors
    /// As [`KalmanFilter::update_with_innovation`].
    pub fn update_with_innovation_gated<const M: usize>(
        &mut self,
        nu: &SVector<f64, M>,
        h: &SMatrix<f64, M, N>,
        r: &SMatrix<f64, M, M>,
        gate: GateThreshold,
    ) -> Result<Gate<M>, EstimatorError> {
        simd::dispatch(
            #[inline(always)]
            |isa| {
                let prep =
                    self.prepare(isa, nu, h, r, true, || innovation_checks(nu, h, self.time))?;
                self.gated_apply(isa, nu, prep, gate)
            },
        )
    }

    #[inline(always)]
    fn gated_apply<const M: usize>(
        &mut self,
        isa: Isa,
        nu: &SVector<f64, M>,
        prep: Prepared<N, M>,
        gate: GateThreshold,
    ) -> Result<Gate<M>, EstimatorError> {
        if !gate.accepts(prep.nis) {
            return Ok(Gate::Rejected { nis: prep.nis });
        }
        self.apply(isa, nu, prep).map(Gate::Accepted)
    }

    /// Forms `U = P H^T` and `S = H P H^T + R`, prepares the solves with `S`
    /// ([`linalg::SpdSolver`]) and computes
    /// the NIS, then ONE validity test: `R` valid (when `check_r`; a
    /// [`MeasurementNoise`] is checked already), `S` positive definite and the NIS
    /// finite. A non-finite `H` or `R` makes `S` fail its factorization, a non-finite
    /// `z` / `nu` makes the NIS non-finite (see [`linalg::innovation`]). Only when the
    /// test fails are the inputs checked one by one in the documented order
    /// (`input_checks`: `z` or `nu`, then `H`; then `R`; then `S`), so the error is the
    /// same as when checking up front; nothing is modified here.
    #[inline(always)]
    fn prepare<const M: usize>(
        &self,
        isa: Isa,
        nu: &SVector<f64, M>,
        h: &SMatrix<f64, M, N>,
        r: &SMatrix<f64, M, M>,
        check_r: bool,
        input_checks: impl FnOnce() -> Result<(), EstimatorError>,
    ) -> Result<Prepared<N, M>, EstimatorError> {
        // R's test first (independent of P): it overlaps with the products below
        let r_ok = !check_r || linalg::covariance_surely_valid(r);
        let (pht, s) = linalg::innovation(isa, self.covariance(), h, r);
        let solver = linalg::SpdSolver::new(&s);
        let nis = solver.as_ref().map_or(f64::NAN, |l| l.quad_form(nu));
        if !(r_ok && nis.is_finite()) {
            input_error(input_checks, r, check_r, self.time)?;
        }
        let Some(solver) = solver else {
            return Err(EstimatorError::NotPositiveDefinite {
                what: "innovation covariance S".into(),
                time: self.time,
            });
        };
        Ok(Prepared {
            pht,
            s,
            solver,
            nis,
        })
    }

    /// Gain `K = U S^-1` ([`linalg::SpdSolver::solve_right`]), state, Joseph
    /// covariance, one validity test (`x` finite, `P` positive definite), commit.
    #[inline(always)]
    fn apply<const M: usize>(
        &mut self,
        isa: Isa,
        nu: &SVector<f64, M>,
        prep: Prepared<N, M>,
    ) -> Result<UpdateInfo<M>, EstimatorError> {
        let k = prep.solver.solve_right(isa, &prep.pht);
        let x_new = self.x + linalg::mat_vec(&k, nu);
        let time = self.time;
        let (p, p_new) = self.covariance_and_spare();
        linalg::joseph_update(isa, p, &prep.pht, &k, &prep.s, p_new);
        if !(linalg::all_finite(x_new.as_slice()) && linalg::is_positive_definite(p_new)) {
            return Err(updated_error(&x_new, p_new, time));
        }
        self.x = x_new;
        self.flip();
        Ok(UpdateInfo {
            innovation: *nu,
            innovation_cov: prep.s,
            nis: prep.nis,
        })
    }

    /// Sequential scalar updates (valid when `R` is diagonal): for each `i` in order,
    /// `nu_i = z_i - H_i x`, `S_i = H_i P H_i^T + r_i`, optional gate on `nu_i^2 / S_i`,
    /// then a scalar Joseph update. Rejected scalars are skipped and reported.
    ///
    /// All-or-nothing: on error the filter is unchanged.
    ///
    /// # Errors
    /// [`EstimatorError::DimensionMismatch`] if the slice lengths differ; non-finite
    /// `"measurement z"` / `"measurement row H[i]"`; [`EstimatorError::NotPositiveDefinite`]
    /// for `"measurement variance r_diag[i]"` `<= 0`, `"innovation variance S[i]"` or
    /// "updated covariance P".
    pub fn update_sequential_scalar(
        &mut self,
        z: &[f64],
        h_rows: &[RowSVector<f64, N>],
        r_diag: &[f64],
        gate: Option<GateThreshold>,
    ) -> Result<SequentialReport, EstimatorError> {
        for (what, got) in [
            ("measurement rows H", h_rows.len()),
            ("r_diag", r_diag.len()),
        ] {
            if got != z.len() {
                return Err(EstimatorError::DimensionMismatch {
                    what: what.into(),
                    expected: z.len(),
                    got,
                });
            }
        }
        check_finite_entries("measurement z", z.len(), 1, |i, _| z[i], self.time)?;
        self.update_sequential_scalar_with(z.len(), gate, |i, x| ScalarMeasurement {
            innovation: z[i] - (h_rows[i] * x)[0],
            h_row: h_rows[i],
            variance: r_diag[i],
        })
    }

    /// Sequential scalar updates where `measurement(i, x)` gives the `i`-th scalar
    /// (innovation, Jacobian row, variance) at the current, already partially updated
    /// state `x` (an EKF relinearizes there; paper B's SI scheme). `count` scalars are
    /// processed in order; gating and errors as in
    /// [`KalmanFilter::update_sequential_scalar`].
    ///
    /// # Errors
    /// As [`KalmanFilter::update_sequential_scalar`]; the filter is unchanged on error.
    pub fn update_sequential_scalar_with<F>(
        &mut self,
        count: usize,
        gate: Option<GateThreshold>,
        mut measurement: F,
    ) -> Result<SequentialReport, EstimatorError>
    where
        F: FnMut(usize, &SVector<f64, N>) -> ScalarMeasurement<N>,
    {
        simd::dispatch(
            #[inline(always)]
            |isa| {
                let t = self.time;
                let mut x = self.x;
                let mut p = *self.covariance();
                let mut outcomes = Vec::with_capacity(count);
                for i in 0..count {
                    let m = measurement(i, &x);
                    if !m.innovation.is_finite() {
                        return Err(EstimatorError::NonFinite {
                            what: "innovation nu".into(),
                            index: i,
                            value: m.innovation,
                            time: t,
                        });
                    }
                    if let Some(c) = (0..N).find(|&c| !m.h_row[c].is_finite()) {
                        return Err(EstimatorError::NonFinite {
                            what: format!("measurement row H[{i}]"),
                            index: c,
                            value: m.h_row[c],
                            time: t,
                        });
                    }
                    if !(m.variance.is_finite() && m.variance > 0.0) {
                        return Err(EstimatorError::NotPositiveDefinite {
                            what: format!("measurement variance r_diag[{i}] = {}", m.variance),
                            time: t,
                        });
                    }
                    let pht: SVector<f64, N> = p * m.h_row.transpose();
                    let s = (m.h_row * pht)[0] + m.variance;
                    if !(s.is_finite() && s > 0.0) {
                        return Err(EstimatorError::NotPositiveDefinite {
                            what: format!("innovation variance S[{i}]"),
                            time: t,
                        });
                    }
                    let nis = m.innovation * m.innovation / s;
                    let accepted = gate.is_none_or(|g| g.accepts(nis));
                    outcomes.push(ScalarOutcome {
                        innovation: m.innovation,
                        innovation_var: s,
                        nis,
                        accepted,
                    });
                    if !accepted {
                        continue;
                    }
                    let k = pht / s;
                    x += k * m.innovation;
                    let mut p_next = p;
                    linalg::joseph_update(isa, &p, &pht, &k, &Matrix1::new(s), &mut p_next);
                    p = p_next;
                }
                if !(linalg::all_finite(x.as_slice()) && linalg::is_positive_definite(&p)) {
                    return Err(updated_error(&x, &p, t));
                }
                self.x = x;
                self.p[self.active] = p;
                Ok(SequentialReport { outcomes })
            },
        )
    }

    /// Commits an externally computed `(x, P)` after checking it (used by the
    /// dynamic-size stacked update).
    pub(crate) fn commit_checked(
        &mut self,
        x: SVector<f64, N>,
        p: SMatrix<f64, N, N>,
    ) -> Result<(), EstimatorError> {
        let p = symmetrize(&p);
        check_finite("updated state x", x.as_slice(), N, 1, self.time)?;
        check_pd("updated covariance P", &p, self.time)?;
        self.x = x;
        self.p[self.active] = p;
        Ok(())
    }
}

#[inline]
pub(crate) fn check_time(what: &str, new_time: Time, current: Time) -> Result<(), EstimatorError> {
    if new_time.is_finite() && new_time >= current {
        return Ok(());
    }
    time_error(what, new_time, current)
}

#[cold]
#[inline(never)]
fn time_error(what: &str, new_time: Time, current: Time) -> Result<(), EstimatorError> {
    if !new_time.is_finite() {
        return Err(EstimatorError::NonFinite {
            what: format!("{what}: time"),
            index: 0,
            value: new_time,
            time: current,
        });
    }
    if new_time < current {
        return Err(EstimatorError::TimeBackwards {
            what: what.to_owned(),
            prev: current,
            next: new_time,
        });
    }
    Ok(())
}

/// The error of a failed prediction test: the checks in their documented order.
#[cold]
#[inline(never)]
fn prediction_error<const N: usize>(
    input_checks: impl FnOnce() -> Result<(), EstimatorError>,
    x_pred: &SVector<f64, N>,
    q: &SMatrix<f64, N, N>,
    p_pred: &SMatrix<f64, N, N>,
    time: Time,
) -> EstimatorError {
    input_checks()
        .and_then(|()| check_finite("predicted state x", x_pred.as_slice(), N, 1, time))
        .and_then(|()| check_process_noise(q, time))
        .and_then(|()| check_pd("predicted covariance P", p_pred, time))
        .err()
        // unreachable: the fast test fails only if one of the checks does
        .unwrap_or_else(|| EstimatorError::NotPositiveDefinite {
            what: "predicted covariance P".into(),
            time,
        })
}

/// `z` (named "measurement z") and `H` finite.
fn measurement_checks<const N: usize, const M: usize>(
    z: &SVector<f64, M>,
    h: &SMatrix<f64, M, N>,
    time: Time,
) -> Result<(), EstimatorError> {
    check_finite("measurement z", z.as_slice(), M, 1, time)?;
    check_finite("measurement matrix H", h.as_slice(), M, N, time)
}

/// `nu` (named "innovation nu") and `H` finite.
fn innovation_checks<const N: usize, const M: usize>(
    nu: &SVector<f64, M>,
    h: &SMatrix<f64, M, N>,
    time: Time,
) -> Result<(), EstimatorError> {
    check_finite("innovation nu", nu.as_slice(), M, 1, time)?;
    check_finite("measurement matrix H", h.as_slice(), M, N, time)
}

/// The input checks of an update in their documented order (`z` / `nu`, `H`, then
/// `R` when `check_r`); `Ok` when they all pass.
#[cold]
#[inline(never)]
fn input_error<const M: usize>(
    input_checks: impl FnOnce() -> Result<(), EstimatorError>,
    r: &SMatrix<f64, M, M>,
    check_r: bool,
    time: Time,
) -> Result<(), EstimatorError> {
    input_checks()?;
    if check_r {
        check_covariance("measurement noise R", r)
            .map_err(|e| EstimatorError::from_core_at(e, time))?;
    }
    Ok(())
}

/// The error of a failed test of an updated estimate.
#[cold]
#[inline(never)]
fn updated_error<const N: usize>(
    x: &SVector<f64, N>,
    p: &SMatrix<f64, N, N>,
    time: Time,
) -> EstimatorError {
    check_finite("updated state x", x.as_slice(), N, 1, time)
        .and_then(|()| check_pd("updated covariance P", p, time))
        .err()
        // unreachable: the fast test fails only if one of the checks does
        .unwrap_or_else(|| EstimatorError::NotPositiveDefinite {
            what: "updated covariance P".into(),
            time,
        })
}

/// Finite and positive definite (Cholesky succeeds).
#[inline]
fn check_pd<const N: usize>(
    what: &str,
    p: &SMatrix<f64, N, N>,
    time: Time,
) -> Result<(), EstimatorError> {
    check_finite(what, p.as_slice(), N, N, time)?;
    if !linalg::is_positive_definite(p) {
        return Err(EstimatorError::NotPositiveDefinite {
            what: what.to_owned(),
            time,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{
        DMatrix, DVector, Matrix1, Matrix2, Matrix3, RowVector2, SMatrix, Vector1, Vector2, Vector3,
    };
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn filter2(x: Vector2<f64>, p: Matrix2<f64>) -> KalmanFilter<2> {
        KalmanFilter::new(Gaussian::new(x, p).unwrap(), 0.0).unwrap()
    }

    #[test]
    fn textbook_constant_position() {
        // x0 = 0, P0 = 1, R = 1, z = 1 -> K = 1/2, x = 0.5, P = 0.5, S = 2, NIS = 1/2.
        let mut kf = KalmanFilter::new(
            Gaussian::new(Vector1::new(0.0), Matrix1::new(1.0)).unwrap(),
            0.0,
        )
        .unwrap();
        let info = kf
            .update(&Vector1::new(1.0), &Matrix1::new(1.0), &Matrix1::new(1.0))
            .unwrap();
        assert_relative_eq!(kf.state()[0], 0.5, epsilon = 1e-15);
        assert_relative_eq!(kf.covariance()[(0, 0)], 0.5, epsilon = 1e-15);
        assert_relative_eq!(info.innovation_cov[(0, 0)], 2.0);
        assert_relative_eq!(info.nis, 0.5);
    }

    #[test]
    fn textbook_two_state_by_hand() {
        // x0 = [0, 1], P0 = I, F = [1 1; 0 1], Q = 0:
        //   predicted x = [1, 1], P = [2 1; 1 1].
        // H = [1 0], R = 1, z = 3: nu = 2, S = 3, K = [2/3, 1/3],
        //   x = [7/3, 5/3], P = P - K S K^T = [2/3 1/3; 1/3 2/3], NIS = 4/3.
        let mut kf = filter2(Vector2::new(0.0, 1.0), Matrix2::identity());
        kf.predict(&Matrix2::new(1.0, 1.0, 0.0, 1.0), &Matrix2::zeros(), 1.0)
            .unwrap();
        assert_relative_eq!(*kf.state(), Vector2::new(1.0, 1.0));
        assert_relative_eq!(*kf.covariance(), Matrix2::new(2.0, 1.0, 1.0, 1.0));
        assert_eq!(kf.time(), 1.0);
        let info = kf
            .update(
                &Vector1::new(3.0),
                &SMatrix::<f64, 1, 2>::new(1.0, 0.0),
                &Matrix1::new(1.0),
            )
            .unwrap();
        assert_relative_eq!(
            *kf.state(),
            Vector2::new(7.0 / 3.0, 5.0 / 3.0),
            epsilon = 1e-14
        );
        assert_relative_eq!(
            *kf.covariance(),
            Matrix2::new(2.0, 1.0, 1.0, 2.0) / 3.0,
            epsilon = 1e-14
        );
        assert_relative_eq!(info.nis, 4.0 / 3.0, epsilon = 1e-14);
        assert_relative_eq!(info.innovation[0], 2.0);
    }

    #[test]
    fn control_and_nonlinear_predictions_share_the_covariance_path() {
        let f = Matrix2::new(1.0, 0.5, 0.0, 1.0);
        let q = Matrix2::new(0.1, 0.02, 0.02, 0.2);
        let b = Vector2::new(0.125, 0.5); // acceleration input, dt = 0.5
        let u = Vector1::new(2.0);
        let mut a = filter2(Vector2::new(1.0, -1.0), Matrix2::new(1.0, 0.2, 0.2, 0.5));
        let mut c = a.clone();
        a.predict_with_control(&f, &b, &u, &q, 0.5).unwrap();
        let x_pred = f * c.state() + b * 2.0;
        c.predict_nonlinear(&x_pred, &f, &q, 0.5).unwrap();
        assert_eq!(a, c);
        assert_relative_eq!(*a.state(), Vector2::new(0.75, 0.0), epsilon = 1e-15);
    }

    #[test]
    fn update_with_innovation_matches_update() {
        let mut a = filter2(Vector2::new(1.0, 2.0), Matrix2::new(2.0, 0.3, 0.3, 1.0));
        let mut b = a.clone();
        let h = Matrix2::new(1.0, 0.0, 0.5, 1.0);
        let r = Matrix2::new(0.5, 0.1, 0.1, 0.4);
        let z = Vector2::new(1.3, 3.1);
        let ia = a.update(&z, &h, &r).unwrap();
        let ib = b
            .update_with_innovation(&(z - h * Vector2::new(1.0, 2.0)), &h, &r)
            .unwrap();
        assert_eq!(a, b);
        assert_eq!(ia, ib);
    }

    #[test]
    fn errors_name_what_and_leave_state_unchanged() {
        let mut kf = filter2(Vector2::new(1.0, 2.0), Matrix2::identity());
        kf.predict(&Matrix2::identity(), &Matrix2::identity(), 3.0)
            .unwrap();
        let before = kf.clone();
        let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);

        let e = kf
            .update(&Vector1::new(f64::NAN), &h, &Matrix1::new(1.0))
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { what, index: 0, time, .. }
                if what == "measurement z" && *time == 3.0),
            "{e}"
        );
        assert!(e.to_string().contains("measurement z"));
        assert_eq!(kf, before);

        let e = kf
            .update(&Vector1::new(1.0), &h, &Matrix1::new(-1.0))
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { what, time }
                if what == "measurement noise R" && *time == 3.0),
            "{e}"
        );
        assert_eq!(kf, before);

        let e = kf
            .update(
                &Vector2::new(1.0, 1.0),
                &Matrix2::identity(),
                &Matrix2::new(1.0, 2.0, 2.0, 1.0),
            )
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { what, .. } if what == "measurement noise R")
        );
        let e = kf
            .update(
                &Vector2::new(1.0, 1.0),
                &Matrix2::identity(),
                &Matrix2::new(1.0, 0.5, 0.0, 1.0),
            )
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotSymmetric { what, .. } if what == "measurement noise R")
        );
        let e = kf
            .update(
                &Vector1::new(1.0),
                &SMatrix::<f64, 1, 2>::new(1.0, f64::INFINITY),
                &Matrix1::new(1.0),
            )
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { what, index: 1, .. } if what == "measurement matrix H")
        );
        let e = kf
            .update_with_innovation(&Vector1::new(f64::NAN), &h, &Matrix1::new(1.0))
            .unwrap_err();
        assert!(matches!(&e, EstimatorError::NonFinite { what, .. } if what == "innovation nu"));
        assert_eq!(kf, before);

        // prediction errors
        let e = kf
            .predict(&Matrix2::identity(), &Matrix2::identity(), 2.0)
            .unwrap_err();
        assert!(matches!(
            e,
            EstimatorError::TimeBackwards {
                prev: 3.0,
                next: 2.0,
                ..
            }
        ));
        let e = kf
            .predict(
                &Matrix2::identity(),
                &Matrix2::new(1.0, 0.0, 0.0, -1.0),
                4.0,
            )
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { what, time } if what.starts_with("process noise Q") && *time == 4.0)
        );
        let e = kf
            .predict(
                &Matrix2::new(1.0, f64::NAN, 0.0, 1.0),
                &Matrix2::identity(),
                4.0,
            )
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { what, index: 1, .. } if what == "transition matrix F")
        );
        // a singular F with Q = 0 makes the predicted P singular
        let e = kf
            .predict(&Matrix2::new(1.0, 1.0, 1.0, 1.0), &Matrix2::zeros(), 4.0)
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { what, .. } if what == "predicted covariance P")
        );
        assert!(
            kf.predict(&Matrix2::identity(), &Matrix2::zeros(), f64::NAN)
                .is_err()
        );
        assert_eq!(kf, before);

        // sequential: the bad scalar is the second one, the first must not be committed
        let e = kf
            .update_sequential_scalar(
                &[1.0, 2.0],
                &[RowVector2::new(1.0, 0.0), RowVector2::new(0.0, 1.0)],
                &[1.0, 0.0],
                None,
            )
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { what, .. } if what.contains("r_diag[1]"))
        );
        let e = kf
            .update_sequential_scalar(&[1.0], &[], &[1.0], None)
            .unwrap_err();
        assert!(matches!(
            e,
            EstimatorError::DimensionMismatch {
                expected: 1,
                got: 0,
                ..
            }
        ));
        assert_eq!(kf, before);

        // construction
        let bad = Gaussian::new_unchecked(Vector2::zeros(), Matrix2::new(1.0, 0.0, 0.0, -1.0));
        assert!(matches!(
            KalmanFilter::new(bad, 0.0),
            Err(EstimatorError::NotPositiveDefinite { .. })
        ));
        let good = Gaussian::new(Vector2::zeros(), Matrix2::identity()).unwrap();
        assert!(KalmanFilter::new(good.clone(), f64::NAN).is_err());
        assert!(kf.set_state(Vector2::new(0.0, f64::NAN)).is_err());
        assert_eq!(kf, before);
        kf.set_state(Vector2::new(5.0, 6.0)).unwrap();
        assert_eq!(kf.covariance(), before.covariance());
        kf.set_estimate(good).unwrap();
        assert_eq!(*kf.covariance(), Matrix2::identity());
    }

    #[test]
    fn gated_update_rejects_outliers_without_touching_the_state() {
        let mut kf = filter2(Vector2::new(0.0, 0.0), Matrix2::identity());
        let before = kf.clone();
        let h = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
        let r = Matrix1::new(1.0);
        let gate = GateThreshold::from_sigma_distance(2.5).unwrap();
        // S = 2; nu = 4 -> NIS = 8 > 6.25
        let g = kf.update_gated(&Vector1::new(4.0), &h, &r, gate).unwrap();
        assert!(matches!(g, Gate::Rejected { nis } if (nis - 8.0).abs() < 1e-12));
        assert!(!g.is_accepted());
        assert_eq!(kf, before);
        // nu = 3 -> NIS = 4.5, accepted and identical to an ungated update
        let g = kf.update_gated(&Vector1::new(3.0), &h, &r, gate).unwrap();
        assert!(g.is_accepted());
        assert_relative_eq!(g.nis(), 4.5);
        let mut plain = before.clone();
        plain.update(&Vector1::new(3.0), &h, &r).unwrap();
        assert_eq!(kf, plain);
        let g = kf
            .update_with_innovation_gated(&Vector1::new(100.0), &h, &r, gate)
            .unwrap();
        assert!(!g.is_accepted());
        assert_eq!(kf, plain);
    }

    fn random_spd<const K: usize>(rng: &mut ChaCha8Rng, eps: f64) -> SMatrix<f64, K, K> {
        let a = SMatrix::<f64, K, K>::from_fn(|_, _| rng.random_range(-1.0..1.0));
        a * a.transpose() + SMatrix::<f64, K, K>::identity() * eps
    }

    #[test]
    fn sequential_equals_stacked_for_diagonal_r() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..20 {
            let p = random_spd::<4>(&mut rng, 0.1);
            let x = SMatrix::<f64, 4, 1>::from_fn(|_, _| rng.random_range(-5.0..5.0));
            let h = SMatrix::<f64, 3, 4>::from_fn(|_, _| rng.random_range(-2.0..2.0));
            let r_diag = [0.3, 1.2, 0.05];
            let z = Vector3::from_fn(|_, _| rng.random_range(-5.0..5.0));
            let kf = KalmanFilter::new(Gaussian::new(x, p).unwrap(), 1.0).unwrap();

            let mut seq = kf.clone();
            let rows: Vec<_> = (0..3).map(|i| h.row(i).into_owned()).collect();
            let rep = seq
                .update_sequential_scalar(z.as_slice(), &rows, &r_diag, None)
                .unwrap();
            assert_eq!(rep.num_accepted(), 3);

            let mut stk = kf.clone();
            let hd = DMatrix::from_fn(3, 4, |i, j| h[(i, j)]);
            let rd = DMatrix::from_diagonal(&DVector::from_row_slice(&r_diag));
            stk.update_stacked(&DVector::from_row_slice(z.as_slice()), &hd, &rd)
                .unwrap();

            assert_relative_eq!(
                *seq.state(),
                *stk.state(),
                epsilon = 1e-12,
                max_relative = 1e-12
            );
            assert_relative_eq!(
                *seq.covariance(),
                *stk.covariance(),
                epsilon = 1e-12,
                max_relative = 1e-12
            );
        }
    }

    #[test]
    fn stacked_correlated_r_by_hand() {
        // N = 2, m = 2, x0 = 0, P = diag(1, 2), H = I, R = [1 0.5; 0.5 1], z = [1, 2].
        // S = [2 0.5; 0.5 3], det S = 5.75, S^-1 = [3 -0.5; -0.5 2] / 5.75.
        // K = P S^-1 = [3 -0.5; -1 4] / 5.75, x = K z = [2, 7] / 5.75,
        // P+ = (I - K) P = [2.75 1; 1 3.5] / 5.75, NIS = z^T S^-1 z = 9 / 5.75.
        let mut kf = filter2(Vector2::zeros(), Matrix2::new(1.0, 0.0, 0.0, 2.0));
        let info = kf
            .update_stacked(
                &DVector::from_row_slice(&[1.0, 2.0]),
                &DMatrix::identity(2, 2),
                &DMatrix::from_row_slice(2, 2, &[1.0, 0.5, 0.5, 1.0]),
            )
            .unwrap();
        assert_relative_eq!(*kf.state(), Vector2::new(2.0, 7.0) / 5.75, epsilon = 1e-14);
        assert_relative_eq!(
            *kf.covariance(),
            Matrix2::new(2.75, 1.0, 1.0, 3.5) / 5.75,
            epsilon = 1e-14
        );
        assert_relative_eq!(info.nis, 9.0 / 5.75, epsilon = 1e-14);
        assert_relative_eq!(
            info.innovation_cov,
            DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 3.0]),
            epsilon = 1e-15
        );
        // the fixed-size path gives the same numbers
        let mut fixed = filter2(Vector2::zeros(), Matrix2::new(1.0, 0.0, 0.0, 2.0));
        fixed
            .update(
                &Vector2::new(1.0, 2.0),
                &Matrix2::identity(),
                &Matrix2::new(1.0, 0.5, 0.5, 1.0),
            )
            .unwrap();
        assert_relative_eq!(*fixed.state(), *kf.state(), epsilon = 1e-14);
        assert_relative_eq!(*fixed.covariance(), *kf.covariance(), epsilon = 1e-14);
    }

    #[test]
    fn fixed_size_and_faer_stacked_updates_agree() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..20 {
            let p = random_spd::<6>(&mut rng, 0.05);
            let x = SMatrix::<f64, 6, 1>::from_fn(|_, _| rng.random_range(-5.0..5.0));
            let h = SMatrix::<f64, 3, 6>::from_fn(|_, _| rng.random_range(-2.0..2.0));
            let r = random_spd::<3>(&mut rng, 0.1);
            let z = Vector3::from_fn(|_, _| rng.random_range(-5.0..5.0));
            let kf = KalmanFilter::new(Gaussian::new(x, p).unwrap(), 0.0).unwrap();
            let mut a = kf.clone();
            let ia = a.update(&z, &h, &r).unwrap();
            let mut b = kf.clone();
            let ib = b
                .update_stacked(
                    &DVector::from_fn(3, |i, _| z[i]),
                    &DMatrix::from_fn(3, 6, |i, j| h[(i, j)]),
                    &DMatrix::from_fn(3, 3, |i, j| r[(i, j)]),
                )
                .unwrap();
            assert_relative_eq!(
                *a.state(),
                *b.state(),
                epsilon = 1e-10,
                max_relative = 1e-10
            );
            assert_relative_eq!(
                *a.covariance(),
                *b.covariance(),
                epsilon = 1e-10,
                max_relative = 1e-10
            );
            assert_relative_eq!(ia.nis, ib.nis, max_relative = 1e-10);
            assert_relative_eq!(
                ia.innovation_cov,
                Matrix3::from_fn(|i, j| ib.innovation_cov[(i, j)]),
                max_relative = 1e-12
            );
        }
    }

    #[test]
    fn stacked_errors_and_dimension_checks() {
        let mut kf = filter2(Vector2::zeros(), Matrix2::identity());
        let before = kf.clone();
        let z = DVector::from_row_slice(&[1.0, 2.0]);
        let e = kf
            .update_stacked(&z, &DMatrix::identity(2, 3), &DMatrix::identity(2, 2))
            .unwrap_err();
        assert!(matches!(
            e,
            EstimatorError::DimensionMismatch {
                expected: 2,
                got: 3,
                ..
            }
        ));
        let e = kf
            .update_stacked(&z, &DMatrix::identity(2, 2), &DMatrix::identity(3, 3))
            .unwrap_err();
        assert!(matches!(e, EstimatorError::DimensionMismatch { .. }));
        let e = kf
            .update_stacked(
                &DVector::from_row_slice(&[1.0, f64::NAN]),
                &DMatrix::identity(2, 2),
                &DMatrix::identity(2, 2),
            )
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NonFinite { what, index: 1, .. } if what == "measurement z")
        );
        let e = kf
            .update_stacked(
                &z,
                &DMatrix::identity(2, 2),
                &DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]),
            )
            .unwrap_err();
        assert!(
            matches!(&e, EstimatorError::NotPositiveDefinite { what, .. } if what == "measurement noise R")
        );
        assert_eq!(kf, before);
        // m = 0 is a no-op
        let info = kf
            .update_stacked(
                &DVector::zeros(0),
                &DMatrix::zeros(0, 2),
                &DMatrix::zeros(0, 0),
            )
            .unwrap();
        assert_eq!(info.nis, 0.0);
        assert_eq!(kf, before);
    }

    #[test]
    fn sequential_gating_reports_rejected_scalars() {
        let mut kf = filter2(Vector2::zeros(), Matrix2::identity());
        let gate = GateThreshold::from_sigma_distance(2.5).unwrap();
        let rows = [
            RowVector2::new(1.0, 0.0),
            RowVector2::new(0.0, 1.0),
            RowVector2::new(1.0, 1.0),
        ];
        // second scalar is an outlier (nu = 10, S = 2, NIS = 50)
        let rep = kf
            .update_sequential_scalar(&[0.5, 10.0, 0.4], &rows, &[1.0, 1.0, 1.0], Some(gate))
            .unwrap();
        assert_eq!(rep.rejected().collect::<Vec<_>>(), vec![1]);
        assert_eq!(rep.num_accepted(), 2);
        assert_relative_eq!(rep.outcomes[1].nis, 50.0);
        // same as the sequential update of the two good scalars only
        let mut other = filter2(Vector2::zeros(), Matrix2::identity());
        other
            .update_sequential_scalar(&[0.5, 0.4], &[rows[0], rows[2]], &[1.0, 1.0], None)
            .unwrap();
        assert_relative_eq!(*kf.state(), *other.state(), epsilon = 1e-15);
        assert_relative_eq!(*kf.covariance(), *other.covariance(), epsilon = 1e-15);
    }

    #[test]
    fn stacked_gating_removes_components_then_updates_the_rest() {
        let mut kf = filter2(Vector2::zeros(), Matrix2::identity());
        let gate = GateThreshold::from_sigma_distance(2.5).unwrap();
        let h = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        let r = DMatrix::from_row_slice(3, 3, &[1.0, 0.2, 0.1, 0.2, 1.0, 0.3, 0.1, 0.3, 1.0]);
        let nu = DVector::from_row_slice(&[0.5, 10.0, 0.4]);
        let rep = kf.update_stacked_gated(&nu, &h, &r, gate).unwrap();
        assert_eq!(rep.rejected().collect::<Vec<_>>(), vec![1]);
        assert_relative_eq!(rep.component_nis[1], 50.0);
        let mut other = filter2(Vector2::zeros(), Matrix2::identity());
        other
            .update_stacked_with_innovation(
                &DVector::from_row_slice(&[0.5, 0.4]),
                &DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 1.0, 1.0]),
                &DMatrix::from_row_slice(2, 2, &[1.0, 0.1, 0.1, 1.0]),
            )
            .unwrap();
        assert_eq!(kf, other);
        // all rejected: no update
        let before = kf.clone();
        let rep = kf
            .update_stacked_gated(&(nu * 100.0), &h, &r, gate)
            .unwrap();
        assert!(rep.update.is_none());
        assert_eq!(kf, before);
    }

    /// Every public step of a filter with `N` states and `M` measurements, driven by
    /// `rng` (random `F`, `Q`, `H`, `R`, `z`), recorded bit by bit: states,
    /// covariances, NIS and the innovation covariances.
    fn run_every_step<const N: usize, const M: usize>(seed: u64, tweak: f64) -> Vec<u64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let prior =
            Gaussian::new(SVector::<f64, N>::zeros(), random_spd::<N>(&mut rng, 0.5)).unwrap();
        let mut kf = KalmanFilter::new(prior, 0.0).unwrap();
        let mut bits = Vec::new();
        let mut record = |kf: &KalmanFilter<N>, extra: &[f64]| {
            let all = kf.state().iter().chain(kf.covariance().iter()).chain(extra);
            bits.extend(all.map(|v| v.to_bits()));
        };
        let gate = GateThreshold::from_sigma_distance(3.0).unwrap();
        for k in 0..40 {
            let f = SMatrix::<f64, N, N>::identity()
                + SMatrix::<f64, N, N>::from_fn(|_, _| rng.random_range(-0.1..0.1));
            let q = random_spd::<N>(&mut rng, 0.01) * 0.01;
            let h = SMatrix::<f64, M, N>::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let r = random_spd::<M>(&mut rng, 0.1);
            let z = SVector::<f64, M>::from_fn(|_, _| rng.random_range(-2.0..2.0) + tweak);
            if k % 3 == 0 {
                let noise = ProcessNoise::new(q).unwrap();
                kf.predict_with_noise(&f, &noise, f64::from(k) + 1.0)
                    .unwrap();
            } else {
                kf.predict(&f, &q, f64::from(k) + 1.0).unwrap();
            }
            record(&kf, &[]);
            let info = match k % 4 {
                0 => kf.update(&z, &h, &r).unwrap(),
                1 => kf
                    .update_with_noise(&z, &h, &MeasurementNoise::new(r).unwrap())
                    .unwrap(),
                2 => match kf.update_gated(&z, &h, &r, gate).unwrap() {
                    Gate::Accepted(info) => info,
                    Gate::Rejected { nis } => UpdateInfo {
                        innovation: z,
                        innovation_cov: r,
                        nis,
                    },
                },
                _ => {
                    let rows: Vec<_> = (0..M).map(|i| h.row(i).into_owned()).collect();
                    let r_diag: Vec<_> = (0..M).map(|i| r[(i, i)]).collect();
                    let rep = kf
                        .update_sequential_scalar(z.as_slice(), &rows, &r_diag, Some(gate))
                        .unwrap();
                    let nis = rep.outcomes.iter().map(|o| o.nis).sum();
                    UpdateInfo {
                        innovation: z,
                        innovation_cov: r,
                        nis,
                    }
                }
            };
            record(&kf, &[info.nis]);
            record(&kf, info.innovation_cov.as_slice());
        }
        bits
    }

    #[test]
    fn checked_process_noise_gives_the_same_bits_and_errors_as_the_raw_q() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let prior =
            Gaussian::new(SVector::<f64, 6>::zeros(), random_spd::<6>(&mut rng, 0.5)).unwrap();
        let (mut raw, mut checked) = (
            KalmanFilter::new(prior.clone(), 0.0).unwrap(),
            KalmanFilter::new(prior, 0.0).unwrap(),
        );
        for k in 1..30 {
            let f = SMatrix::<f64, 6, 6>::identity()
                + SMatrix::<f64, 6, 6>::from_fn(|_, _| rng.random_range(-0.1..0.1));
            let mut q = random_spd::<6>(&mut rng, 0.01) * 0.01;
            // symmetric within the tolerance, not exactly: the stored (Q + Q^T) / 2
            // must give what predict's own symmetrization gives
            q[(0, 3)] *= 1.0 + 1e-12;
            let t = f64::from(k);
            raw.predict(&f, &q, t).unwrap();
            checked
                .predict_with_noise(&f, &ProcessNoise::new(q).unwrap(), t)
                .unwrap();
            let bits = |kf: &KalmanFilter<6>| {
                let all = kf.state().iter().chain(kf.covariance().iter());
                all.map(|v| v.to_bits()).collect::<Vec<_>>()
            };
            assert_eq!(bits(&raw), bits(&checked), "step {k}");
        }
        // failures: the same error, the filter unchanged
        let noise = ProcessNoise::new(SMatrix::<f64, 6, 6>::zeros()).unwrap();
        let t = raw.time() + 1.0;
        let singular = SMatrix::<f64, 6, 6>::zeros();
        let mut bad_f = SMatrix::<f64, 6, 6>::identity();
        bad_f[(2, 4)] = f64::NAN;
        for f in [singular, bad_f] {
            let before = checked.clone();
            let e_raw = raw.clone().predict(&f, noise.matrix(), t).unwrap_err();
            let e_checked = checked.predict_with_noise(&f, &noise, t).unwrap_err();
            assert_eq!(format!("{e_raw:?}"), format!("{e_checked:?}"));
            assert_eq!(checked, before);
        }
        assert!(matches!(
            checked.predict_with_noise(&SMatrix::identity(), &noise, t - 5.0),
            Err(EstimatorError::TimeBackwards { .. })
        ));
        // what ProcessNoise refuses, predict refuses with the same error
        let mut asym = SMatrix::<f64, 6, 6>::identity();
        asym[(1, 2)] = 0.5;
        let mut neg = SMatrix::<f64, 6, 6>::identity();
        neg[(3, 3)] = -1e-9;
        let mut nan = SMatrix::<f64, 6, 6>::identity();
        nan[(5, 0)] = f64::NAN;
        for q in [asym, neg, nan] {
            let e_new = ProcessNoise::new(q).unwrap_err();
            let e_predict = raw
                .clone()
                .predict(&SMatrix::identity(), &q, 0.0 + raw.time())
                .unwrap_err();
            let time_free = |e: EstimatorError| format!("{:?}", e.at_time(0.0));
            assert_eq!(time_free(e_new), time_free(e_predict));
        }
    }

    #[test]
    fn simd_dispatch_is_bit_identical_to_the_baseline_build() {
        // On an AVX2 machine (the project's), `dispatch` really takes the AVX2 path,
        // so the comparison below is between two different compilations.
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::env::var_os("FATHOM_SIMD").is_none()
        {
            assert_eq!(simd::kernel_instruction_set(), "avx2");
        }
        fn same_bits<const N: usize, const M: usize>(seed: u64) -> bool {
            let wide = run_every_step::<N, M>(seed, 0.0);
            wide == simd::tests::with_baseline(|| run_every_step::<N, M>(seed, 0.0))
        }
        type Check = fn(u64) -> bool;
        let shapes: [(&str, Check); 4] = [
            ("6/3", same_bits::<6, 3>),
            ("9/3", same_bits::<9, 3>),
            ("4/2", same_bits::<4, 2>),
            ("15/1", same_bits::<15, 1>),
        ];
        for seed in 0..4 {
            for (shape, same) in shapes {
                assert!(same(seed), "{shape} seed {seed}: AVX2 and baseline differ");
            }
        }
        // negative control: the comparison sees a change of one ulp in the measurements
        let tweaked = run_every_step::<6, 3>(0, f64::EPSILON);
        assert!(tweaked != run_every_step::<6, 3>(0, 0.0));
    }

    #[test]
    fn sequential_with_closure_relinearizes_at_the_current_state() {
        // range-like scalar h(x) = |x| measured twice: the second innovation must use
        // the state after the first update.
        let mut kf = filter2(Vector2::new(3.0, 4.0), Matrix2::identity());
        let z = [5.5, 5.5];
        let mut seen = Vec::new();
        kf.update_sequential_scalar_with(2, None, |i, x| {
            seen.push(*x);
            let range = x.norm();
            ScalarMeasurement {
                innovation: z[i] - range,
                h_row: (x / range).transpose(),
                variance: 0.25,
            }
        })
        .unwrap();
        assert_eq!(seen[0], Vector2::new(3.0, 4.0));
        assert!(seen[1].norm() > 5.0);
        assert!(kf.state().norm() > seen[1].norm());
    }

    /// The checks of `predict` one by one in their documented order (time, `F`,
    /// `x_pred`, `Q`, predicted `P`): what the code did before they were fused into
    /// one test with a search on failure.
    fn predict_oracle(
        kf: &KalmanFilter<3>,
        f: &Matrix3<f64>,
        q: &Matrix3<f64>,
        t: Time,
    ) -> Result<(), EstimatorError> {
        check_time("predict", t, kf.time())?;
        check_finite("transition matrix F", f.as_slice(), 3, 3, t)?;
        let x_pred = f * kf.state();
        check_finite("predicted state x", x_pred.as_slice(), 3, 1, t)?;
        check_process_noise(q, t)?;
        let p = f * kf.covariance() * f.transpose() + q;
        check_pd("predicted covariance P", &symmetrize(&p), t)
    }

    /// The checks of `update` one by one in their documented order (`z`, `H`, `R`,
    /// `S`); the updated estimate cannot fail for these inputs.
    fn update_oracle(
        kf: &KalmanFilter<3>,
        z: &Vector2<f64>,
        h: &SMatrix<f64, 2, 3>,
        r: &Matrix2<f64>,
    ) -> Result<(), EstimatorError> {
        let t = kf.time();
        check_finite("measurement z", z.as_slice(), 2, 1, t)?;
        check_finite("measurement matrix H", h.as_slice(), 2, 3, t)?;
        check_covariance("measurement noise R", r)
            .map_err(|e| EstimatorError::from_core_at(e, t))?;
        let s = h * kf.covariance() * h.transpose() + r;
        if linalg::SpdSolver::new(&symmetrize(&s)).is_none() {
            return Err(EstimatorError::NotPositiveDefinite {
                what: "innovation covariance S".into(),
                time: t,
            });
        }
        Ok(())
    }

    /// Same `Ok` / same error (compared by `Debug`, so that a NaN `value` compares
    /// equal), and an unchanged filter on error.
    fn assert_same<T: std::fmt::Debug>(
        got: Result<T, EstimatorError>,
        expected: Result<(), EstimatorError>,
        after: &KalmanFilter<3>,
        before: &KalmanFilter<3>,
        case: &str,
    ) {
        match (&got, &expected) {
            (Ok(_), Ok(())) => {}
            (Err(g), Err(e)) => {
                assert_eq!(format!("{g:?}"), format!("{e:?}"), "{case}");
                assert_eq!(after, before, "{case}: the filter changed on error");
            }
            _ => panic!("{case}: got {got:?}, expected {expected:?}"),
        }
    }

    /// Every entry of every input, set to NaN, +inf or -inf, and the other invalid
    /// inputs (asymmetric or indefinite `Q` / `R`, singular `F` with `Q = 0`): the fused
    /// checks report exactly the error of checking each input up front, and leave the
    /// filter unchanged.
    #[test]
    fn fused_checks_report_the_same_errors_as_checking_up_front() {
        let p0 = Matrix3::new(2.0, 0.3, 0.1, 0.3, 1.0, 0.2, 0.1, 0.2, 0.5);
        let kf = KalmanFilter::new(
            Gaussian::new(Vector3::new(1.0, -2.0, 0.5), p0).unwrap(),
            1.0,
        )
        .unwrap();
        let f = Matrix3::new(1.0, 0.1, 0.0, 0.0, 1.0, 0.1, 0.0, 0.0, 1.0);
        let q = Matrix3::new(0.01, 0.002, 0.0, 0.002, 0.02, 0.001, 0.0, 0.001, 0.03);
        let h = SMatrix::<f64, 2, 3>::new(1.0, 0.0, 0.5, 0.0, 1.0, 0.0);
        let r = Matrix2::new(0.25, 0.05, 0.05, 0.5);
        let z = Vector2::new(1.2, -1.9);
        let bad_values = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
        let mut cases = 0;

        let mut check_predict = |f: &Matrix3<f64>, q: &Matrix3<f64>, t: Time, case: &str| {
            let mut a = kf.clone();
            assert_same(
                a.predict(f, q, t),
                predict_oracle(&kf, f, q, t),
                &a,
                &kf,
                case,
            );
            // the other prediction flavours with the same F and Q
            let mut b = kf.clone();
            let x_pred = f * kf.state();
            let expected = check_time("predict", t, kf.time())
                .and_then(|()| check_finite("transition Jacobian F", f.as_slice(), 3, 3, t))
                .and_then(|()| check_finite("predicted state x", x_pred.as_slice(), 3, 1, t))
                .and_then(|()| check_process_noise(q, t))
                .and_then(|()| predict_oracle(&kf, f, q, t));
            assert_same(
                b.predict_nonlinear(&x_pred, f, q, t),
                expected,
                &b,
                &kf,
                case,
            );
            cases += 1;
        };
        for i in 0..9 {
            for v in bad_values {
                let mut fb = f;
                fb[(i / 3, i % 3)] = v;
                check_predict(&fb, &q, 2.0, &format!("F[{i}] = {v}"));
                let mut qb = q;
                qb[(i / 3, i % 3)] = v;
                check_predict(&f, &qb, 2.0, &format!("Q[{i}] = {v}"));
                // both a bad F and a bad Q: F is named first
                check_predict(&fb, &qb, 2.0, &format!("F and Q [{i}] = {v}"));
            }
        }
        let mut q_asym = q;
        q_asym[(2, 0)] += 1e-4;
        check_predict(&f, &q_asym, 2.0, "asymmetric Q");
        let mut q_neg = q;
        q_neg[(1, 1)] = -1e-6;
        check_predict(&f, &q_neg, 2.0, "negative Q diagonal");
        let q_indef = Matrix3::new(0.0, 5.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        check_predict(&f, &q_indef, 2.0, "indefinite Q");
        check_predict(&Matrix3::zeros(), &Matrix3::zeros(), 2.0, "F = 0, Q = 0");
        check_predict(
            &Matrix3::new(1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            &Matrix3::zeros(),
            2.0,
            "singular F, Q = 0",
        );
        check_predict(&f, &q, 0.5, "time backwards");
        check_predict(&f, &q, f64::NAN, "NaN time");
        check_predict(&(f * 1e200), &q, 2.0, "overflowing F");
        check_predict(&f, &q, 2.0, "valid");

        // control input: B and u are checked after F
        for i in 0..3 {
            for v in bad_values {
                let (mut b, mut u) = (Vector3::new(0.5, 0.1, 1.0), Vector1::new(2.0));
                b[i] = v;
                let mut a = kf.clone();
                let got = a.predict_with_control(&f, &b, &u, &q, 2.0);
                let expected = check_finite("control matrix B", b.as_slice(), 3, 1, 2.0);
                assert_same(got, expected, &a, &kf, &format!("B[{i}] = {v}"));
                b[i] = 0.5;
                u[0] = v;
                let got = a.predict_with_control(&f, &b, &u, &q, 2.0);
                let expected = check_finite("control input u", u.as_slice(), 1, 1, 2.0);
                assert_same(got, expected, &a, &kf, &format!("u = {v}"));
                cases += 2;
            }
        }

        let mut check_update =
            |z: &Vector2<f64>, h: &SMatrix<f64, 2, 3>, r: &Matrix2<f64>, case: &str| {
                let expected = update_oracle(&kf, z, h, r);
                let mut a = kf.clone();
                assert_same(a.update(z, h, r), expected.clone(), &a, &kf, case);
                // gated: an error, never a rejection, for invalid inputs
                let gate = GateThreshold::from_sigma_distance(3.0).unwrap();
                let mut g = kf.clone();
                assert_same(
                    g.update_gated(z, h, r, gate),
                    expected.clone(),
                    &g,
                    &kf,
                    case,
                );
                // with a given innovation: the same checks, naming "innovation nu"
                let nu = z - h * kf.state();
                let expected_nu = check_finite("innovation nu", nu.as_slice(), 2, 1, kf.time())
                    .and_then(|()| update_oracle(&kf, &Vector2::zeros(), h, r));
                let mut b = kf.clone();
                assert_same(
                    b.update_with_innovation(&nu, h, r),
                    expected_nu,
                    &b,
                    &kf,
                    case,
                );
                // with a checked R: R is not re-checked
                if let Ok(noise) = MeasurementNoise::new(*r) {
                    let mut c = kf.clone();
                    assert_same(
                        c.update_with_noise(z, h, &noise),
                        expected.clone(),
                        &c,
                        &kf,
                        case,
                    );
                }
                cases += 1;
            };
        for i in 0..6 {
            for v in bad_values {
                let mut hb = h;
                hb[(i / 3, i % 3)] = v;
                check_update(&z, &hb, &r, &format!("H[{i}] = {v}"));
                let mut zb = z;
                zb[i % 2] = v;
                check_update(&zb, &h, &r, &format!("z[{}] = {v}", i % 2));
                check_update(&zb, &hb, &r, &format!("z and H [{i}] = {v}"));
                let mut rb = r;
                rb[(i % 4 / 2, i % 2)] = v;
                check_update(&z, &h, &rb, &format!("R[{}] = {v}", i % 4));
                check_update(&z, &hb, &rb, &format!("H and R [{i}] = {v}"));
            }
        }
        check_update(&z, &h, &Matrix2::new(0.25, 0.05, 0.06, 0.5), "asymmetric R");
        check_update(&z, &h, &Matrix2::new(0.25, 0.5, 0.5, 0.5), "indefinite R");
        check_update(&z, &h, &Matrix2::new(0.25, 0.0, 0.0, 0.0), "singular R");
        check_update(&z, &h, &Matrix2::new(-1.0, 0.0, 0.0, -1.0), "negative R");
        check_update(
            &z,
            &h,
            &Matrix2::new(1e120, 0.0, 0.0, 1e120),
            "huge R (declined by the fast test, valid)",
        );
        let c = 1.0 - 1e-12;
        check_update(
            &z,
            &h,
            &Matrix2::new(1.0, c, c, 1.0),
            "nearly singular R (declined by the fast test, valid)",
        );
        check_update(&(z * 1e300), &h, &r, "huge z (NIS overflows, not an error)");
        check_update(&z, &h, &r, "valid");
        assert!(cases >= 200, "{cases}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        #[test]
        fn covariance_stays_symmetric_positive_definite(
            a in prop::array::uniform9(-1.0f64..1.0),
            f in prop::array::uniform9(-2.0f64..2.0),
            b in prop::array::uniform9(-1.0f64..1.0),
            h in prop::array::uniform6(-2.0f64..2.0),
            c in prop::array::uniform4(-1.0f64..1.0),
            x in prop::array::uniform3(-10.0f64..10.0),
            z in prop::array::uniform2(-10.0f64..10.0),
            eps in 1e-3f64..1.0,
        ) {
            let a = Matrix3::from_row_slice(&a);
            let p0 = a * a.transpose() + Matrix3::identity() * eps;
            let f = Matrix3::from_row_slice(&f);
            let b = Matrix3::from_row_slice(&b);
            let q = b * b.transpose() + Matrix3::identity() * 1e-3;
            let h = SMatrix::<f64, 2, 3>::from_row_slice(&h);
            let c = Matrix2::from_row_slice(&c);
            let r = c * c.transpose() + Matrix2::identity() * 1e-2;
            let mut kf = KalmanFilter::new(
                Gaussian::new(Vector3::from_row_slice(&x), p0).unwrap(), 0.0).unwrap();
            for step in 1..=3 {
                kf.predict(&f, &q, step as f64).unwrap();
                let p = kf.covariance();
                prop_assert_eq!(*p, p.transpose());
                prop_assert!(p.cholesky().is_some());
                kf.update(&Vector2::from_row_slice(&z), &h, &r).unwrap();
                let p = kf.covariance();
                prop_assert_eq!(*p, p.transpose());
                prop_assert!(p.cholesky().is_some());
                prop_assert!(fathom_core::gaussian::check_covariance("P", p).is_ok());
            }
        }
    }
}
