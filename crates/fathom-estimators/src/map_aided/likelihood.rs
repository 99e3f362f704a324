//! The range likelihood of candidate values of the nonlinear states (grid points of
//! the MGPMF, particles of the particle filter), by batch ray casting.
//!
//! For a candidate `n = (dp_N, dp_E, psi_D)` the linear pose states take their
//! conditional mean `(dp_D, psi_N, psi_E) = E[. | n]` ([`super::marginal`]); the
//! candidate pose is the nominal corrected by that error (`p = p_hat - dp`,
//! `C = exp(-[psi x]) C_hat`) and each beam is cast from it. A beam's likelihood is
//! robust (the outlier probability `eps` of the settings, for returns the map does
//! not explain: glass, clutter):
//!
//! ```text
//! L = (1 - eps) N(z - r_hat; 0, s^2) + eps / max_range,   s^2 = sigma^2 + g P_pose|n g^T
//! ```
//!
//! where `g` is the beam's row with respect to the linear pose states at that hit
//! (eq. 16's `H^j`: the uncertainty of `l` given `n` widens each beam) and
//! `P_pose|n` their conditional covariance. A grid point stands for its cell: the
//! MGPMF adds `h_n Lambda h_n^T` to `s^2`, with `h_n` the beam's row for `n` and
//! `Lambda = diag(spacing^2 / 6)` the covariance of the point's hat function (the
//! interpolation kernel of eq. 17-18), the Gaussian approximation of the likelihood
//! averaged over that kernel. Without it a grid coarser than the range noise (0.45 m
//! cells against 5 cm ranges) weights points by how close they happen to fall to the
//! truth and can prefer a far point of another mode. Particles have no cells
//! (`Lambda = 0`: the standard bootstrap likelihood). A beam without a predicted hit has
//! `L = max(eps, 1e-9) / max_range` (only an outlier explains it). The barometer,
//! which sees only `dp_D`, adds a Gaussian factor with `s^2 = sigma_b^2 + P_DD|n`.
//! Far beams: where `x = nu^2 / (2 s^2)` is so large that the Gaussian term is below
//! half an ulp of the tail, `term + eps / max_range` rounds to the tail itself, so
//! the exp and the sqrt are skipped and the tail taken; the value is the same bit for
//! bit (the bound is in `evaluate_on`, tested).
//! Beams are treated as independent given `n` (the common linear states make them
//! slightly correlated; the per-beam robust tail needs the factorization).
//!
//! Rays go through [`RayCaster::cast_coherent`] in chunks of [`CHUNK_POINTS`]
//! candidates (buffers reused across updates), beam by beam: one beam from
//! consecutive candidates of the evaluation order, which the filters choose so that
//! consecutive candidates are neighbours (the MGPMF: one yaw slice at a time, the
//! horizontal grid row by row in alternating directions; the particle filter: sorted
//! along a space-filling curve). The hits, and so the values, are those of single
//! casts. With more than one thread
//! ([`super::Mgpmf::set_threads`], [`super::ParticleFilter::set_threads`]) the
//! chunks are split into contiguous ranges, one per scoped thread; each candidate's
//! value is computed by the same code whatever thread computes it and the totals are
//! integer counts, so the result is bit-identical for every thread count.

use fathom_core::{Ray, RayCaster, RayHit};
use nalgebra::{Matrix3, Rotation3, Vector3};

use super::MapAidedError;
use super::ins12::NominalNav;
use super::range_model::{BaroHeight, RangeBeam};

/// Candidates per batch of ray casts.
pub const CHUNK_POINTS: usize = 256;

/// The most threads one likelihood evaluation may use.
pub const MAX_THREADS: usize = 256;

/// Beams whose far threshold is precomputed per evaluation (more beams compute it
/// never and take every exp).
const FAR_BEAMS: usize = 16;

/// Smallest `|o . u|` used in a likelihood row (a grazing hit's row is large, not
/// infinite).
const MIN_COS: f64 = 1e-3;

/// The fixed inputs of one likelihood evaluation.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LikelihoodModel<'a> {
    pub pos_hat: Vector3<f64>,
    pub c_hat: Matrix3<f64>,
    pub unit_dirs: &'a [Vector3<f64>],
    pub beams: &'a [RangeBeam],
    pub baro: Option<&'a BaroHeight>,
    pub max_range: f64,
    pub outlier_probability: f64,
    /// `mu_n`, and `(dp_D, psi_N, psi_E)` at `n` = `pose_base + pose_slope (n - mu_n)`.
    pub mu_n: Vector3<f64>,
    pub pose_base: Vector3<f64>,
    pub pose_slope: Matrix3<f64>,
    /// Conditional covariance of `(dp_D, psi_N, psi_E)` given `n`.
    pub pose_cov: Matrix3<f64>,
    /// Diagonal covariance of the kernel each candidate stands for on `n` (the MGPMF's
    /// hat function, `spacing^2 / 6` per axis; zero for particles).
    pub kernel_var: Vector3<f64>,
}

/// Ray buffers of the likelihood (reused).
#[derive(Debug, Clone, Default)]
pub(crate) struct RayBuffers {
    rays: Vec<Ray>,
    hits: Vec<Option<RayHit>>,
}

/// The threads of the likelihood evaluations of one filter and their ray buffers
/// (reused across updates; one set of buffers per thread).
#[derive(Debug, Clone)]
pub(crate) struct LikelihoodWorkers {
    threads: usize,
    buffers: Vec<RayBuffers>,
    /// The candidates and their values in the evaluation order (reused).
    ordered_points: Vec<Vector3<f64>>,
    ordered_out: Vec<f64>,
}

impl Default for LikelihoodWorkers {
    fn default() -> Self {
        Self {
            threads: 1,
            buffers: vec![RayBuffers::default()],
            ordered_points: Vec::new(),
            ordered_out: Vec::new(),
        }
    }
}

impl LikelihoodWorkers {
    /// The number of threads an evaluation may use.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Sets the number of threads, `1..=MAX_THREADS` (`field` names it in the error).
    pub fn set_threads(&mut self, field: &str, threads: usize) -> Result<(), MapAidedError> {
        if !(1..=MAX_THREADS).contains(&threads) {
            return Err(MapAidedError::InvalidParameter {
                field: field.to_string(),
                value: threads as f64,
                expected: "1 ..= 256 threads",
            });
        }
        self.threads = threads;
        Ok(())
    }
}

/// Totals of one evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct LikelihoodStats {
    pub rays: usize,
    pub hits: usize,
}

impl LikelihoodStats {
    fn add(self, other: Self) -> Self {
        Self {
            rays: self.rays + other.rays,
            hits: self.hits + other.hits,
        }
    }
}

impl LikelihoodModel<'_> {
    /// The candidate pose (position, attitude matrix) and the pose-moving linear
    /// states at `n`.
    #[inline]
    fn pose(&self, n: &Vector3<f64>) -> (Vector3<f64>, Matrix3<f64>, Vector3<f64>) {
        let lin = self.pose_base + self.pose_slope * (n - self.mu_n);
        let pos = self.pos_hat - Vector3::new(n.x, n.y, lin.x);
        let psi = Vector3::new(lin.y, lin.z, n.z);
        let c = Rotation3::from_scaled_axis(-psi).into_inner() * self.c_hat;
        (pos, c, lin)
    }

    /// Writes the log-likelihood of every candidate of `points` into `out`
    /// (`out.len() == points.len()`), on the workers' threads (module docs). The
    /// candidates are evaluated in the order `order` (a permutation of the indices of
    /// `points`, or empty for their own order): neighbouring candidates in that order
    /// make coherent ray groups ([`RayCaster::cast_coherent`]). Each value is the same
    /// whatever the order.
    pub fn evaluate(
        &self,
        points: &[Vector3<f64>],
        order: &[u32],
        out: &mut [f64],
        workers: &mut LikelihoodWorkers,
        caster: &dyn RayCaster,
    ) -> LikelihoodStats {
        if order.is_empty() {
            return self.evaluate_in_order(points, out, workers, caster);
        }
        debug_assert_eq!(order.len(), points.len());
        let mut ordered = std::mem::take(&mut workers.ordered_points);
        let mut ordered_out = std::mem::take(&mut workers.ordered_out);
        ordered.clear();
        ordered.extend(order.iter().map(|&i| points[i as usize]));
        ordered_out.clear();
        ordered_out.resize(ordered.len(), 0.0);
        let stats = self.evaluate_in_order(&ordered, &mut ordered_out, workers, caster);
        for (&i, v) in order.iter().zip(&ordered_out) {
            out[i as usize] = *v;
        }
        workers.ordered_points = ordered;
        workers.ordered_out = ordered_out;
        stats
    }

    /// [`Self::evaluate`] in the order of `points`.
    fn evaluate_in_order(
        &self,
        points: &[Vector3<f64>],
        out: &mut [f64],
        workers: &mut LikelihoodWorkers,
        caster: &dyn RayCaster,
    ) -> LikelihoodStats {
        let chunks = points.len().div_ceil(CHUNK_POINTS);
        let threads = workers.threads.min(chunks).max(1);
        if workers.buffers.len() < threads {
            workers.buffers.resize_with(threads, RayBuffers::default);
        }
        if threads == 1 {
            return self.evaluate_on(points, out, &mut workers.buffers[0], caster);
        }
        let per_thread = chunks.div_ceil(threads) * CHUNK_POINTS;
        std::thread::scope(|scope| {
            let mut parts = points
                .chunks(per_thread)
                .zip(out.chunks_mut(per_thread))
                .zip(workers.buffers.iter_mut());
            let first = parts.next();
            let spawned: Vec<_> = parts
                .map(|((p, o), buf)| scope.spawn(move || self.evaluate_on(p, o, buf, caster)))
                .collect();
            let mut stats = first.map_or_else(LikelihoodStats::default, |((p, o), buf)| {
                self.evaluate_on(p, o, buf, caster)
            });
            for handle in spawned {
                match handle.join() {
                    Ok(s) => stats = stats.add(s),
                    Err(panic) => std::panic::resume_unwind(panic),
                }
            }
            stats
        })
    }

    /// [`Self::evaluate`] on the calling thread.
    fn evaluate_on(
        &self,
        points: &[Vector3<f64>],
        out: &mut [f64],
        buf: &mut RayBuffers,
        caster: &dyn RayCaster,
    ) -> LikelihoodStats {
        let nb = self.beams.len();
        let eps = self.outlier_probability;
        // linear domain (one exp and one sqrt per beam, one ln per 8 beams) when the
        // tail keeps every factor >= eps / max_range; log domain without a tail
        let linear = eps > 0.0;
        let keep_norm = (1.0 - eps) / (2.0 * std::f64::consts::PI).sqrt();
        let tail = eps / self.max_range;
        let outlier = eps.max(1e-9) / self.max_range;
        let ln_outlier = outlier.ln();
        let half_ln_2pi = 0.5 * (2.0 * std::f64::consts::PI).ln();
        // A beam whose Gaussian term cannot change `term + tail` (module docs, "far
        // beams"): with `s >= sigma / 2`, the term is at most
        // `keep_norm exp(-x) / (sigma / 2)`, below `tail 2^-56` (under half an ulp of
        // `tail`, with room for the rounding of the term) once `x` exceeds this.
        let far = |sigma: f64| {
            let bound = (keep_norm / (0.5 * sigma * tail)).ln() + 56.0 * std::f64::consts::LN_2;
            if linear && tail >= f64::MIN_POSITIVE && bound.is_finite() {
                bound
            } else {
                f64::INFINITY
            }
        };
        let far_beams: [f64; FAR_BEAMS] =
            std::array::from_fn(|j| self.beams.get(j).map_or(f64::INFINITY, |b| far(b.sigma_m)));
        let mut stats = LikelihoodStats::default();
        for (chunk, out_chunk) in points
            .chunks(CHUNK_POINTS)
            .zip(out.chunks_mut(CHUNK_POINTS))
        {
            // beam-major: ray `j * len + k` is beam `j` from candidate `k`, so that
            // consecutive rays are one beam from consecutive candidates (the coherent
            // groups of `cast_coherent`)
            let len = chunk.len();
            buf.rays.clear();
            buf.rays
                .resize(len * nb, Ray::new(Vector3::zeros(), Vector3::x(), 0.0));
            for (k, n) in chunk.iter().enumerate() {
                let (pos, c, _) = self.pose(n);
                for (j, d) in self.unit_dirs.iter().enumerate() {
                    buf.rays[j * len + k] = Ray::new(pos, c * d, self.max_range);
                }
            }
            // every slot is written by the cast: no clearing
            buf.hits.resize(buf.rays.len(), None);
            let _ = caster.cast_coherent(&buf.rays, &mut buf.hits);
            stats.rays += buf.rays.len();
            for (k, (n, o)) in chunk.iter().zip(out_chunk.iter_mut()).enumerate() {
                let mut ll = 0.0;
                let mut prod: f64 = 1.0;
                for j in 0..nb {
                    if linear && j % 8 == 7 {
                        ll += prod.ln();
                        prod = 1.0;
                    }
                    let Some(hit) = &buf.hits[j * len + k] else {
                        if linear {
                            prod *= outlier;
                        } else {
                            ll += ln_outlier;
                        }
                        continue;
                    };
                    stats.hits += 1;
                    let u = &buf.rays[j * len + k].dir_in_nav;
                    let on = &hit.normal_in_nav;
                    let mut q = on.dot(u);
                    if q.abs() < MIN_COS {
                        q = -MIN_COS;
                    }
                    let oxu = on.cross(u);
                    let k = -hit.range / q;
                    // rows of the beam for the linear pose states and for n
                    let g = Vector3::new(on.z / q, k * oxu.x, k * oxu.y);
                    let h_n = Vector3::new(on.x / q, on.y / q, k * oxu.z);
                    let beam = &self.beams[j];
                    let s2 = beam.sigma_m * beam.sigma_m
                        + g.dot(&(self.pose_cov * g))
                        + h_n.component_mul(&h_n).dot(&self.kernel_var);
                    let nu = beam.range_m - hit.range;
                    if linear {
                        let a = -0.5 * nu * nu / s2;
                        let far_x = far_beams.get(j).copied().unwrap_or(f64::INFINITY);
                        // `term + tail == tail` bit for bit for a far beam: skip exp
                        prod *= if -a > far_x && s2 >= 0.25 * beam.sigma_m * beam.sigma_m {
                            tail
                        } else {
                            keep_norm * a.exp() / s2.sqrt() + tail
                        };
                    } else {
                        ll += -0.5 * nu * nu / s2 - 0.5 * s2.ln() - half_ln_2pi;
                    }
                }
                ll += prod.ln();
                if let Some(b) = self.baro {
                    let lin = self.pose_base + self.pose_slope * (n - self.mu_n);
                    let height = -(self.pos_hat.z - lin.x);
                    let s2 = b.sigma_m * b.sigma_m + self.pose_cov[(0, 0)];
                    let nu = b.height_m - height;
                    ll += -0.5 * nu * nu / s2 - 0.5 * s2.ln() - half_ln_2pi;
                }
                *o = ll;
            }
        }
        stats
    }
}

/// The likelihood model of one update: the nominal pose, the beams and the
/// conditional pose part of the prior.
#[allow(clippy::too_many_arguments)]
pub(crate) fn model<'a>(
    nominal: &NominalNav,
    unit_dirs: &'a [Vector3<f64>],
    beams: &'a [RangeBeam],
    baro: Option<&'a BaroHeight>,
    max_range: f64,
    outlier_probability: f64,
    part: &super::marginal::Partition,
    kernel_var: Vector3<f64>,
) -> LikelihoodModel<'a> {
    let (pose_base, pose_slope, pose_cov) = part.pose_part();
    LikelihoodModel {
        pos_hat: nominal.pos_in_nav,
        c_hat: nominal.nav_from_body.to_rotation_matrix().into_inner(),
        unit_dirs,
        beams,
        baro,
        max_range,
        outlier_probability,
        mu_n: part.mu_n,
        pose_base,
        pose_slope,
        pose_cov,
        kernel_var,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map_aided::ErrorVector12;
    use crate::map_aided::marginal::Partition;
    use crate::map_aided::test_support::Planes;
    use nalgebra::UnitQuaternion;

    /// The far-beam bound of `evaluate_on`: beyond it `term + tail` is the tail, bit
    /// for bit, for every `s^2 >= sigma^2 / 4`; 10 below it the term shows (the
    /// negative control).
    #[test]
    fn beyond_the_far_bound_the_gaussian_term_vanishes_in_the_tail() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(16);
        let mut shown = 0;
        for _ in 0..20_000 {
            let eps = [0.01, 0.05, 0.3][rng.random_range(0..3)];
            let max_range = [5.0, 40.0, 60.0, 1000.0][rng.random_range(0..4)];
            let sigma: f64 = 10f64.powf(rng.random_range(-3.0..0.5));
            let keep_norm = (1.0 - eps) / (2.0 * std::f64::consts::PI).sqrt();
            let tail = eps / max_range;
            let bound = (keep_norm / (0.5 * sigma * tail)).ln() + 56.0 * std::f64::consts::LN_2;
            let s2 = sigma * sigma * rng.random_range(0.25..100.0);
            let x = bound * (1.0 + 1e-12) + rng.random_range(0.0..5.0);
            let term = |x: f64| keep_norm * (-x).exp() / s2.sqrt() + tail;
            assert_eq!(
                term(x).to_bits(),
                tail.to_bits(),
                "{eps} {max_range} {sigma} {s2} {x}"
            );
            // the smallest s^2 the bound allows shows the term 10 below the bound
            let tight = keep_norm * (-(bound - 10.0)).exp() / (0.5 * sigma) + tail;
            shown += usize::from(tight != tail);
        }
        assert_eq!(shown, 20_000);
    }

    /// The candidate pose is the nominal corrected by the joint error `(n, E[l | n])`,
    /// and the likelihood peaks at the true offset.
    #[test]
    fn candidate_poses_and_the_peak() {
        let map = Planes::corner();
        let truth = Vector3::new(-4.0, -5.0, -3.0);
        let nominal = NominalNav {
            pos_in_nav: truth + Vector3::new(0.7, -0.4, 0.0),
            vel_in_nav: Vector3::zeros(),
            nav_from_body: UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3),
            accel_bias_in_body: Vector3::zeros(),
        };
        let mut p = crate::map_aided::Matrix12::identity() * 0.5;
        p[(0, 2)] = 0.1;
        p[(2, 0)] = 0.1;
        let part = Partition::new(&ErrorVector12::zeros(), &p).unwrap();
        let dirs: Vec<_> = (0..6)
            .map(|k| {
                let a = k as f64 * std::f64::consts::FRAC_PI_3;
                Vector3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let beams: Vec<_> = dirs
            .iter()
            .map(|d| RangeBeam {
                dir_in_body: *d,
                range_m: map
                    .cast(&truth, &(nominal.nav_from_body * d), 60.0)
                    .map_or(1.0, |h| h.range),
                sigma_m: 0.05,
            })
            .collect();
        let m = model(
            &nominal,
            &dirs,
            &beams,
            None,
            60.0,
            0.05,
            &part,
            Vector3::zeros(),
        );
        let n = Vector3::new(0.3, -0.2, 0.01);
        let (pos, c, lin) = m.pose(&n);
        let dx = Partition::join(&n, &part.linear_mean(&n));
        let t = nominal.corrected(&dx);
        assert!((t.pos_in_nav - pos).norm() < 1e-12);
        assert!((t.nav_from_body.to_rotation_matrix().into_inner() - c).amax() < 1e-12);
        assert_eq!(lin.x, dx[2]);
        let pts = [
            Vector3::new(0.7, -0.4, 0.0),
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(0.7, -0.4, 0.05),
        ];
        let mut out = [0.0; 3];
        let mut workers = LikelihoodWorkers::default();
        let st = m.evaluate(&pts, &[], &mut out, &mut workers, &map);
        assert_eq!(st.rays, 18);
        assert!(out[0] > out[1] + 10.0 && out[0] > out[2], "{out:?}");
        // any evaluation order gives each candidate the same value, bit for bit
        for order in [[2u32, 0, 1], [1, 2, 0], [0, 1, 2]] {
            let mut permuted = [0.0; 3];
            let st = m.evaluate(&pts, &order, &mut permuted, &mut workers, &map);
            assert_eq!(st.rays, 18);
            assert_eq!(
                permuted.map(f64::to_bits),
                out.map(f64::to_bits),
                "{order:?}"
            );
        }
        // the linear-domain product equals the sum of the logs of the robust terms
        let (eps, r) = (0.05, 60.0);
        let mut manual = 0.0;
        let (pos, c, _) = m.pose(&pts[1]);
        for (d, b) in dirs.iter().zip(&beams) {
            let u = c * d;
            let l = match map.cast(&pos, &u, r) {
                None => eps / r,
                Some(h) => {
                    let q = h.normal_in_nav.dot(&u);
                    let k = -h.range / q;
                    let oxu = h.normal_in_nav.cross(&u);
                    let g = Vector3::new(h.normal_in_nav.z / q, k * oxu.x, k * oxu.y);
                    let s2 = b.sigma_m.powi(2) + g.dot(&(m.pose_cov * g));
                    let nu = b.range_m - h.range;
                    (1.0 - eps) * (-0.5 * nu * nu / s2).exp()
                        / (2.0 * std::f64::consts::PI * s2).sqrt()
                        + eps / r
                }
            };
            manual += l.ln();
        }
        assert!(
            (manual - out[1]).abs() < 1e-9 * manual.abs().max(1.0),
            "{manual} {}",
            out[1]
        );
    }
}
