//! Verdicts against a paper's value by equivalence: the reproduced interval is read
//! against a tolerance band around the paper's number.
//!
//! With the interval `[lo, hi]` of the reproduced mean and the band
//! `[paper - tol, paper + tol]`:
//! - **agrees** when the whole interval lies inside the band;
//! - **differs** when the whole interval lies outside it;
//! - **inconclusive** otherwise (the interval straddles an edge of the band).
//!
//! A wider interval (more runs diverging, fewer runs) can only move a verdict towards
//! inconclusive: an interval that contains an interval that agrees can itself agree
//! only if it also lies inside the band, never because it grew.

use crate::error::StatsError;

/// The outcome of an equivalence test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// The interval lies inside the band.
    Agrees,
    /// The interval lies outside the band.
    Differs,
    /// The interval straddles an edge of the band.
    Inconclusive,
}

impl Verdict {
    /// `"agrees"`, `"differs"` or `"inconclusive"`, as written in `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Agrees => "agrees",
            Self::Differs => "differs",
            Self::Inconclusive => "inconclusive",
        }
    }
}

/// An equivalence test of a reproduced interval against a paper's value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Equivalence {
    /// The paper's value.
    pub paper: f64,
    /// The tolerance band `[paper - tol, paper + tol]`.
    pub band: [f64; 2],
    /// The reproduced interval.
    pub interval: [f64; 2],
    /// The verdict.
    pub verdict: Verdict,
}

/// Reads `interval` against the band of half-width `tolerance` around `paper`.
///
/// # Errors
/// [`StatsError::NonFinite`] for a non-finite number, [`StatsError::OutOfRange`] for a
/// negative tolerance or an interval with `lo > hi`.
pub fn equivalence(
    interval: [f64; 2],
    paper: f64,
    tolerance: f64,
) -> Result<Equivalence, StatsError> {
    for (i, v) in [interval[0], interval[1], paper, tolerance]
        .into_iter()
        .enumerate()
    {
        if !v.is_finite() {
            return Err(StatsError::NonFinite {
                what: "equivalence input (interval lo, hi, paper, tolerance)".into(),
                index: i,
                value: v,
            });
        }
    }
    if tolerance < 0.0 {
        return Err(StatsError::OutOfRange {
            what: "equivalence tolerance".into(),
            value: tolerance,
            expected: ">= 0",
        });
    }
    let [lo, hi] = interval;
    if lo > hi {
        return Err(StatsError::OutOfRange {
            what: format!("equivalence interval [{lo}, {hi}]"),
            value: lo,
            expected: "a lower end at most the upper end",
        });
    }
    let band = [paper - tolerance, paper + tolerance];
    let verdict = if lo >= band[0] && hi <= band[1] {
        Verdict::Agrees
    } else if hi < band[0] || lo > band[1] {
        Verdict::Differs
    } else {
        Verdict::Inconclusive
    };
    Ok(Equivalence {
        paper,
        band,
        interval,
        verdict,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_verdicts() {
        let v = |lo, hi| equivalence([lo, hi], 1.0, 0.25).unwrap().verdict;
        assert_eq!(v(0.9, 1.1), Verdict::Agrees);
        assert_eq!(v(0.75, 1.25), Verdict::Agrees);
        assert_eq!(v(1.3, 2.0), Verdict::Differs);
        assert_eq!(v(0.1, 0.7), Verdict::Differs);
        assert_eq!(v(0.9, 1.4), Verdict::Inconclusive);
        assert_eq!(v(0.1, 3.0), Verdict::Inconclusive);
        assert_eq!(Verdict::Inconclusive.name(), "inconclusive");
        assert!(equivalence([1.0, 0.0], 1.0, 0.1).is_err());
        assert!(equivalence([0.0, 1.0], f64::NAN, 0.1).is_err());
        assert!(equivalence([0.0, 1.0], 1.0, -0.1).is_err());
    }

    /// Widening an interval never turns a verdict into "agrees": over a grid of
    /// intervals and widenings, a widened interval agrees only if the band holds it.
    #[test]
    fn widening_never_creates_agreement() {
        for i in 0..40 {
            for w in 0..40 {
                let lo = 0.5 + 0.02 * f64::from(i);
                let hi = lo + 0.01 * f64::from(w);
                let base = equivalence([lo, hi], 1.0, 0.25).unwrap().verdict;
                for grow in [0.01, 0.1, 1.0] {
                    let wide = equivalence([lo - grow, hi + grow], 1.0, 0.25).unwrap();
                    if wide.verdict == Verdict::Agrees {
                        assert_eq!(base, Verdict::Agrees);
                    }
                    if base == Verdict::Inconclusive {
                        assert_eq!(wide.verdict, Verdict::Inconclusive);
                    }
                }
            }
        }
    }
}
