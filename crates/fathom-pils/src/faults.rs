//! Link faults as settings: datagram loss, latency with jitter, reordering,
//! duplicates, corrupted bytes, and junk datagrams (random bytes, truncated frames,
//! frames with a bad CRC, valid frames of unexpected or unknown message types) sent
//! from the sender's own address. Every draw comes from the caller's seeded RNG, so a
//! seed gives the same faults (the wall clock only decides *when* a delayed datagram
//! leaves, not *whether*).

use rand::Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::PilsError;

/// Fault settings of one direction of the link (applied by the sender).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FaultParams {
    /// Probability that a datagram is lost, in `[0, 1)`.
    pub loss: f64,
    /// Mean one-way latency added to each datagram, s.
    pub latency_s: f64,
    /// Standard deviation of the latency (normal, truncated at zero), s.
    pub jitter_s: f64,
    /// Probability that a datagram is held back and sent after the next one (or
    /// when its sender next waits for input).
    pub reorder: f64,
    /// Probability that a datagram is sent twice.
    pub duplicate: f64,
    /// Probability that one byte of a datagram is flipped.
    pub corrupt: f64,
    /// Junk datagrams per sent datagram (probability), each of a random [`JunkKind`].
    pub junk: f64,
}

impl Default for FaultParams {
    fn default() -> Self {
        Self::NONE
    }
}

impl FaultParams {
    /// A clean link.
    pub const NONE: FaultParams = FaultParams {
        loss: 0.0,
        latency_s: 0.0,
        jitter_s: 0.0,
        reorder: 0.0,
        duplicate: 0.0,
        corrupt: 0.0,
        junk: 0.0,
    };

    /// Checks every probability is in `[0, 1)` and the times are finite and `>= 0`
    /// (latency below 10 s).
    ///
    /// # Errors
    /// [`PilsError::Setting`] naming the field.
    pub fn check(&self) -> Result<FaultParams, PilsError> {
        for (name, p) in [
            ("loss", self.loss),
            ("reorder", self.reorder),
            ("duplicate", self.duplicate),
            ("corrupt", self.corrupt),
            ("junk", self.junk),
        ] {
            if !(0.0..1.0).contains(&p) {
                return Err(PilsError::setting(
                    format!("link.faults.{name}"),
                    p,
                    "must be in [0, 1)",
                ));
            }
        }
        for (name, s) in [("latency_s", self.latency_s), ("jitter_s", self.jitter_s)] {
            if !(0.0..10.0).contains(&s) {
                return Err(PilsError::setting(
                    format!("link.faults.{name}"),
                    s,
                    "must be in [0, 10) s",
                ));
            }
        }
        Ok(*self)
    }

    /// Whether any fault is active.
    pub fn any(&self) -> bool {
        *self != FaultParams::NONE
    }
}

/// What a junk datagram holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum JunkKind {
    /// Uniform random bytes (1 to 300).
    RandomBytes,
    /// A valid frame cut short.
    Truncated,
    /// A valid frame with its checksum broken.
    BadCrc,
    /// A valid frame of a common-dialect message the receiver does not expect.
    UnexpectedType,
    /// A frame with a message id outside the common dialect.
    UnknownId,
}

impl JunkKind {
    /// Every kind.
    pub const ALL: [JunkKind; 5] = [
        JunkKind::RandomBytes,
        JunkKind::Truncated,
        JunkKind::BadCrc,
        JunkKind::UnexpectedType,
        JunkKind::UnknownId,
    ];
}

/// What the injector decided for one datagram.
#[derive(Debug, Clone, PartialEq)]
pub struct Decision {
    /// Copies to send (0: lost, 2: duplicated), each with its delay (s) and bytes.
    pub copies: Vec<(f64, Vec<u8>)>,
    /// Hold this datagram until after the next one.
    pub hold_back: bool,
    /// A junk datagram to send as well.
    pub junk: Option<JunkKind>,
}

/// The fault injector of one sender.
#[derive(Debug, Clone)]
pub struct FaultInjector {
    params: FaultParams,
    jitter: Option<Normal<f64>>,
}

impl FaultInjector {
    /// An injector for checked `params`.
    ///
    /// # Errors
    /// [`PilsError::Setting`] as [`FaultParams::check`].
    pub fn new(params: FaultParams) -> Result<Self, PilsError> {
        let params = params.check()?;
        let jitter = (params.jitter_s > 0.0)
            .then(|| Normal::new(0.0, params.jitter_s).ok())
            .flatten();
        Ok(Self { params, jitter })
    }

    /// The settings.
    pub fn params(&self) -> &FaultParams {
        &self.params
    }

    /// Decides the fate of one datagram. The number of draws per datagram is fixed
    /// (seven), whatever is decided, so one fault setting does not shift the draws of
    /// the others.
    pub fn decide(&self, datagram: &[u8], rng: &mut impl Rng) -> Decision {
        let p = &self.params;
        let u_loss: f64 = rng.random();
        let u_dup: f64 = rng.random();
        let u_reorder: f64 = rng.random();
        let u_corrupt: f64 = rng.random();
        let corrupt_at: u64 = rng.random();
        let u_junk: f64 = rng.random();
        let junk_kind: u64 = rng.random();
        let mut copies = Vec::new();
        if u_loss >= p.loss {
            let n = if u_dup < p.duplicate { 2 } else { 1 };
            for _ in 0..n {
                let mut bytes = datagram.to_vec();
                if u_corrupt < p.corrupt && !bytes.is_empty() {
                    let i = (corrupt_at % bytes.len() as u64) as usize;
                    // A nonzero mask from the draw's high bits: the byte always changes.
                    let mask = ((corrupt_at >> 32) as u8).max(1);
                    bytes[i] ^= mask;
                }
                copies.push((self.delay(rng), bytes));
            }
        }
        Decision {
            copies,
            hold_back: u_reorder < p.reorder,
            junk: (u_junk < p.junk)
                .then(|| JunkKind::ALL[(junk_kind % JunkKind::ALL.len() as u64) as usize]),
        }
    }

    /// One latency draw (latency + jitter, at least zero), s.
    fn delay(&self, rng: &mut impl Rng) -> f64 {
        let j = self.jitter.map_or(0.0, |n| n.sample(rng));
        (self.params.latency_s + j).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use statrs_free::binomial_ok;

    /// A two-sided binomial check without statrs: |k - np| <= 5 sqrt(np(1-p)).
    mod statrs_free {
        pub fn binomial_ok(k: usize, n: usize, p: f64) -> bool {
            let mean = n as f64 * p;
            let sd = (n as f64 * p * (1.0 - p)).sqrt();
            (k as f64 - mean).abs() <= 5.0 * sd
        }
    }

    #[test]
    fn bad_settings_are_refused() {
        for f in [
            FaultParams {
                loss: 1.0,
                ..FaultParams::NONE
            },
            FaultParams {
                corrupt: f64::NAN,
                ..FaultParams::NONE
            },
            FaultParams {
                latency_s: -0.1,
                ..FaultParams::NONE
            },
            FaultParams {
                jitter_s: f64::INFINITY,
                ..FaultParams::NONE
            },
        ] {
            assert!(FaultInjector::new(f).is_err(), "{f:?}");
        }
    }

    #[test]
    fn clean_link_passes_everything_unchanged() {
        let inj = FaultInjector::new(FaultParams::NONE).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for i in 0..100u8 {
            let d = inj.decide(&[i, 1, 2], &mut rng);
            assert_eq!(d.copies, vec![(0.0, vec![i, 1, 2])]);
            assert!(!d.hold_back && d.junk.is_none());
        }
    }

    #[test]
    fn rates_match_the_settings_and_the_seed_repeats() {
        let params = FaultParams {
            loss: 0.05,
            latency_s: 0.02,
            jitter_s: 0.01,
            reorder: 0.1,
            duplicate: 0.02,
            corrupt: 0.03,
            junk: 0.04,
        };
        let inj = FaultInjector::new(params).unwrap();
        let run = |seed| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            (0..20_000)
                .map(|_| inj.decide(&[0u8; 40], &mut rng))
                .collect::<Vec<_>>()
        };
        let a = run(7);
        assert_eq!(a, run(7));
        assert_ne!(a, run(8));
        let n = a.len();
        let lost = a.iter().filter(|d| d.copies.is_empty()).count();
        let dup = a.iter().filter(|d| d.copies.len() == 2).count();
        let held = a.iter().filter(|d| d.hold_back).count();
        let junk = a.iter().filter(|d| d.junk.is_some()).count();
        let corrupt = a
            .iter()
            .filter(|d| d.copies.first().is_some_and(|c| c.1 != [0u8; 40]))
            .count();
        assert!(binomial_ok(lost, n, 0.05), "lost {lost}");
        assert!(binomial_ok(dup, n - lost, 0.02), "dup {dup}");
        assert!(binomial_ok(held, n, 0.1), "held {held}");
        assert!(binomial_ok(junk, n, 0.04), "junk {junk}");
        assert!(binomial_ok(corrupt, n - lost, 0.03), "corrupt {corrupt}");
        // Negative control: the check rejects a count from another rate.
        assert!(!binomial_ok(lost, n, 0.08));
        let delays: Vec<f64> = a
            .iter()
            .flat_map(|d| d.copies.iter().map(|c| c.0))
            .collect();
        let mean = delays.iter().sum::<f64>() / delays.len() as f64;
        assert!((mean - 0.02).abs() < 5.0 * 0.01 / (delays.len() as f64).sqrt() + 1e-4);
        assert!(delays.iter().all(|d| *d >= 0.0));
    }
}
