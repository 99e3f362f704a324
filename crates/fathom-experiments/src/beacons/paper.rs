//! The numbers printed in the paper (seed 003, Tables 13-14): the reference column of
//! the `beacons` experiment, never an output.

/// Paper Table 13 (main case): `(scheme, mean, std, max, rmse)`.
pub(super) const PAPER_TABLE13: [(&str, [f64; 4]); 3] = [
    ("AS", [0.1522, 0.0869, 0.6016, 0.1332]),
    ("SC", [0.1537, 0.0795, 0.5873, 0.1730]),
    ("SI", [0.1737, 0.0885, 0.6011, 0.1950]),
];

/// Paper Table 14: detected injected outliers per scheme (of 276).
pub(super) const PAPER_TABLE14: [(&str, f64); 3] = [("AS", 276.0), ("SC", 264.0), ("SI", 276.0)];

/// Injected outliers in the paper's Table 14.
pub(super) const PAPER_INJECTED: f64 = 276.0;
