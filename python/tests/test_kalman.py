"""fathom.KalmanFilter against FilterPy's KalmanFilter, and its checks."""

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter as FilterPyKF

import fathom


def cv_problem(dim=3, dt=0.1, q=0.5):
    """Constant velocity in `dim` axes: 2*dim states, dim position measurements."""
    n = 2 * dim
    F = np.eye(n)
    Q = np.zeros((n, n))
    for i in range(dim):
        F[i, i + dim] = dt
        Q[i, i] = q * dt**4 / 4
        Q[i, i + dim] = Q[i + dim, i] = q * dt**3 / 2
        Q[i + dim, i + dim] = q * dt**2
    H = np.zeros((dim, n))
    H[:, :dim] = np.eye(dim)
    R = 0.25 * np.eye(dim) + 0.05 * (np.ones((dim, dim)) - np.eye(dim))
    return F, Q, H, R


def pair(dim_x, dim_z, F, Q, H, R, x0, P0):
    a = fathom.KalmanFilter(dim_x, dim_z)
    b = FilterPyKF(dim_x, dim_z)
    for kf in (a, b):
        kf.F, kf.Q, kf.H, kf.R = F.copy(), Q.copy(), H.copy(), R.copy()
        kf.x = x0.copy()
        kf.P = P0.copy()
    return a, b


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape, (a.shape, b.shape)
    return float(np.max(np.abs(a - b) / np.maximum(1.0, np.abs(b))))


def follow(a, b, zs, check_gain=True):
    worst = 0.0
    for z in zs:
        a.predict()
        b.predict()
        worst = max(worst, rel(a.x, b.x), rel(a.P, b.P))
        a.update(z)
        b.update(z)
        worst = max(worst, rel(a.x, b.x), rel(a.P, b.P), rel(a.y, b.y), rel(a.S, b.S))
        worst = max(worst, rel(a.nis, b.mahalanobis**2))
        if check_gain:
            worst = max(worst, rel(a.K, b.K), rel(a.SI, b.SI))
    return worst


def test_matches_filterpy_on_6_3_constant_velocity_for_1000_steps():
    F, Q, H, R = cv_problem()
    x0 = np.array([[1.0], [-2.0], [3.0], [0.5], [0.1], [-0.2]])
    a, b = pair(6, 3, F, Q, H, R, x0, 4.0 * np.eye(6))
    assert a.core == "fixed<6>"
    rng = np.random.default_rng(7)
    truth = x0.copy()
    zs = []
    for _ in range(1000):
        truth = F @ truth + rng.multivariate_normal(np.zeros(6), Q).reshape(6, 1)
        zs.append(H @ truth + rng.multivariate_normal(np.zeros(3), R).reshape(3, 1))
    worst = follow(a, b, zs)
    assert worst <= 1e-12, worst
    assert a.x.shape == (6, 1) and a.y.shape == (3, 1)
    assert np.allclose(a.x_post, b.x_post, rtol=1e-12, atol=1e-12)
    assert np.allclose(a.P_prior, b.P_prior, rtol=1e-12, atol=1e-12)
    assert a.log_likelihood == pytest.approx(b.log_likelihood, rel=1e-10)
    # negative control: FilterPy with another R drifts far beyond the tolerance
    c, d = pair(6, 3, F, Q, H, R, x0, 4.0 * np.eye(6))
    d.R = 2.0 * R
    assert follow(c, d, zs[:50], check_gain=False) > 1e-6


@pytest.mark.parametrize("dim_x,dim_z", [(2, 1), (4, 8), (16, 4), (20, 10)])
def test_other_sizes_and_cores_match_filterpy(dim_x, dim_z):
    rng = np.random.default_rng(dim_x * 100 + dim_z)
    F = np.eye(dim_x) + 0.01 * rng.standard_normal((dim_x, dim_x))
    A = rng.standard_normal((dim_x, dim_x))
    Q = 0.01 * (A @ A.T) + 0.01 * np.eye(dim_x)
    H = rng.standard_normal((dim_z, dim_x))
    B = rng.standard_normal((dim_z, dim_z))
    R = 0.1 * (B @ B.T) + 0.5 * np.eye(dim_z)
    x0 = rng.standard_normal((dim_x, 1))
    a, b = pair(dim_x, dim_z, F, Q, H, R, x0, np.eye(dim_x))
    expected_core = "dynamic" if dim_x > fathom.MAX_FIXED_DIM_X else f"fixed<{dim_x}>"
    assert a.core == expected_core
    zs = [rng.standard_normal((dim_z, 1)) for _ in range(200)]
    assert follow(a, b, zs) <= 1e-11


def test_control_input_overrides_and_1d_state():
    F, Q, H, R = cv_problem(dim=1, dt=0.5)
    a, b = pair(2, 1, F, Q, H, R, np.array([0.0, 1.0]), np.eye(2))
    B = np.array([[0.125], [0.5]])
    for k in range(50):
        u = np.array([np.sin(0.1 * k)])
        a.predict(u=u, B=B)
        b.predict(u=u, B=B)
        a.update(0.3 * k, R=0.5)
        b.update(0.3 * k, R=0.5)
    assert a.x.shape == (2,)
    assert rel(a.x, b.x) <= 1e-12 and rel(a.P, b.P) <= 1e-12
    a.predict(Q=0.01)
    b.predict(Q=0.01)
    assert rel(a.P, b.P) <= 1e-12
    a.update(None)
    assert a.z is None and np.array_equal(a.x_post, a.x)


def test_filterpy_idioms_edit_in_place():
    kf = fathom.KalmanFilter(2, 1)
    kf.P *= 1000.0
    assert np.array_equal(kf.P, 1000.0 * np.eye(2))
    kf.F[0, 1] = 0.5
    assert kf.F[0, 1] == 0.5
    kf.H = np.array([[1.0, 0.0]])
    kf.x[1, 0] = 2.0
    kf.predict()
    assert kf.x[0, 0] == pytest.approx(1.0)
    assert kf.t == 1.0


def test_bad_covariances_raise_the_core_message_and_leave_the_filter_unchanged():
    F, Q, H, R = cv_problem()
    kf = fathom.KalmanFilter(6, 3)
    kf.F, kf.Q, kf.H, kf.R = F, Q, H, R
    kf.P = 2.0 * np.eye(6)
    x, P = kf.x.copy(), kf.P.copy()
    bad_p = np.eye(6)
    bad_p[0, 1] = bad_p[1, 0] = 2.0
    with pytest.raises(ValueError, match=r"^covariance P is not positive definite at t = 0 s$"):
        kf.P = bad_p
    nan_p = np.eye(6)
    nan_p[2, 3] = np.nan
    with pytest.raises(ValueError, match=r"^covariance P: value at index 15 is not finite \(NaN\)"):
        kf.P = nan_p
    with pytest.raises(ValueError, match="covariance P: matrix is not symmetric"):
        kf.P = np.eye(6) + np.triu(np.ones((6, 6)), 1)
    bad_r = np.diag([1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match=r"^measurement noise R is not positive definite at t = 0 s$"):
        kf.R = bad_r
    with pytest.raises(ValueError, match=r"^measurement noise R: value at index 0 is not finite"):
        kf.R = np.full((3, 3), np.nan)
    kf.predict()
    with pytest.raises(ValueError, match=r"^measurement noise R is not positive definite at t = 1 s$"):
        kf.update(np.zeros(3), R=bad_r)
    with pytest.raises(ValueError, match=r"^measurement z: value at index 1 is not finite \(NaN\) at t = 1 s$"):
        kf.update(np.array([0.0, np.nan, 0.0]))
    with pytest.raises(ValueError, match=r"process noise Q \(diagonal entry 2 = -1\) is not positive definite"):
        kf.predict(Q=np.diag([1.0, 1.0, -1.0, 1.0, 1.0, 1.0]))
    # in-place NaN in P is refused at the next step
    P_now = kf.P
    P_now[0, 0] = np.nan
    with pytest.raises(ValueError, match="covariance P: value at index 0 is not finite"):
        kf.predict()
    kf.P = np.eye(6)  # replacing P drops the pending in-place edit
    kf.predict()
    assert kf.t == 2.0
    assert np.all(np.isfinite(kf.P)) and x.shape == (6, 1) and P.shape == (6, 6)


def test_bad_shapes_raise():
    kf = fathom.KalmanFilter(4, 2)
    before = (kf.x.copy(), kf.P.copy())
    with pytest.raises(ValueError, match=r"P: expected shape \(4, 4\), got \(3, 3\)"):
        kf.P = np.eye(3)
    with pytest.raises(ValueError, match="x: expected 4 values"):
        kf.x = np.zeros(5)
    with pytest.raises(ValueError, match=r"F: expected shape \(4, 4\)"):
        kf.F = np.eye(2)
    with pytest.raises(ValueError, match=r"H: expected shape \(2, 4\)"):
        kf.H = np.ones((4, 2))
    with pytest.raises(ValueError, match="z: expected 2 values"):
        kf.update(np.zeros(3))
    with pytest.raises(ValueError):
        kf.update("not a number")
    with pytest.raises(ValueError):
        kf.F = np.zeros((4, 4, 1))
    with pytest.raises(ValueError, match="dim_x must be in"):
        fathom.KalmanFilter(0, 1)
    with pytest.raises(ValueError, match="dim_x must be in"):
        fathom.KalmanFilter(10**6, 1)
    with pytest.raises(OverflowError):
        fathom.KalmanFilter(-1, 1)
    with pytest.raises(TypeError):
        kf.alpha = 1.02
    assert np.array_equal(kf.x, before[0]) and np.array_equal(kf.P, before[1])
