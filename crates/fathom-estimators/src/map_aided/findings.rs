//! What implementing seed 004's estimator equations found in the paper (misprints,
//! sign conventions, readings of garbled equations), as a list a report can print.
//! Each entry names the equation and says what the code does instead.

/// One finding about the paper's equations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PaperFinding {
    /// Short stable id, e.g. `eq14_p_inverse`.
    pub id: &'static str,
    /// The equation(s) concerned.
    pub equation: &'static str,
    /// What the paper prints, what is right, and what the code implements.
    pub text: &'static str,
}

/// The findings (see the docs of [`super::range_model`], [`super::ins12`],
/// [`super::error_model`] and [`super::mgpmf`]).
pub const PAPER_FINDINGS: &[PaperFinding] = &[
    PaperFinding {
        id: "eq7_eq9_sign",
        equation: "(7), (9)",
        text: "eq. (7) gives dr/dp = o / (o . C d) and eq. (9) gives dr/dp = -o / (o . C d) \
               for the same quantity. With r = o.(T - p) / o.(C d), -o / (o . C d) is the \
               derivative with respect to the true position p (eq. 9); the paper's error state \
               is dx = x_hat - x (eq. 6: r = h(x_hat - dx)), for which the row is +o / (o . C d) \
               (eq. 7). The code uses eq. 7's sign in H (innovation z - h(x_hat) = H dx), tested \
               against finite differences.",
    },
    PaperFinding {
        id: "eq10_denominator",
        equation: "(10)",
        text: "eq. (10) as extracted, dr/dpsi = -(o.(T - p) / o.(C d)) o^T [x C d], has o.(C d) \
               to the first power; differentiating r = o.(T - p) / o.(C d) gives the square, \
               dr/dpsi = -(o.(T - p) / (o.(C d))^2) o^T [(C d) x] = -(r / o.(C d)) (o x C d)^T \
               for C = exp(-[psi x]) C_hat. The printed form agrees only at normal incidence \
               (where both vanish). The code implements the derivative.",
    },
    PaperFinding {
        id: "eq12_13_baro_convention",
        equation: "(12), (13)",
        text: "eq. (13) stacks z = -h_baro with H_baro = +e_3 (eq. 12): a derivative with respect \
               to the true down position, the convention of eq. (9), not of eq. (7). In the error \
               convention the code uses z = h_baro (height up) and H = +e_3 on dp_D \
               (h = -(p_hat_D - dp_D)), so range and baro rows share one convention.",
    },
    PaperFinding {
        id: "eq14_p_inverse",
        equation: "(14)",
        text: "eq. (14) prints the covariance update P_k = P_k^- - K_k H P_k^{-1}; the last factor is \
               the prior covariance P_k^- (a superscript minus read as an inverse). The code uses \
               the Joseph form (I - K H) P^- (I - K H)^T + K R K^T, equal to P^- - K H P^- for the \
               optimal gain.",
    },
    PaperFinding {
        id: "eq14_double_gain",
        equation: "(14)",
        text: "eq. (14) prints x_k = x_k^- + K_k K_k (z_k - h(x_k^-)); one gain: x_k = x_k^- + \
               K_k (z_k - h(x_k^-)).",
    },
    PaperFinding {
        id: "eq3_bias_sign",
        equation: "(1), (3)",
        text: "eq. (3) couples the accelerometer-bias state into the velocity error with +C_b^n: \
               db_a is the residual accelerometer error (measured minus true after the estimate \
               is subtracted), while dp, dv, psi are estimated minus true. The code keeps the \
               paper's sign; feedback adds db_a to the bias estimate.",
    },
    PaperFinding {
        id: "eq4_noise_blocks",
        equation: "(3), (4)",
        text: "eq. (4)'s G has no input into the bias row (a constant bias). The code adds an \
               optional bias random walk as a third noise block (zero by default, which is the \
               paper's model).",
    },
    PaperFinding {
        id: "eq17_18_interpolation",
        equation: "(17), (18)",
        text: "eq. (17)-(18) are the point-mass moments; the text adds a linear interpolation \
               between the points against sparsity. Read as the moments of the piecewise-linear \
               (tensor-product hat) interpolant of the weights on the regular grid: the mean is \
               eq. (17) and the covariance is eq. (18) plus diag(spacing^2 / 6) per axis (the \
               variance of a hat function), which keeps the covariance positive definite when \
               the weight sits on one point.",
    },
    PaperFinding {
        id: "eq16_linear_part",
        equation: "(15), (16), (19)",
        text: "eq. (16) splits each range into a nonlinear part in the grid states (horizontal \
               position and yaw errors) and a linear part H^j in the rest. The code evaluates the \
               nonlinear part by ray casting at each grid point (with the linear states at their \
               mean conditioned on the point), folds the linear part's uncertainty into each \
               beam's variance, and updates the linear states with a Kalman filter conditioned on \
               the grid states (eq. 15/19), linearized at the posterior mean.",
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn findings_have_unique_ids_and_text() {
        let mut ids: Vec<_> = PAPER_FINDINGS.iter().map(|f| f.id).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), PAPER_FINDINGS.len());
        assert!(PAPER_FINDINGS.iter().all(|f| f.text.len() > 40));
        assert!(ids.contains(&"eq14_p_inverse") && ids.contains(&"eq7_eq9_sign"));
    }
}
