//! What a scenario will cost before it runs: simulated samples, peak memory and run
//! time (orders of magnitude), each part attributed to the scenario keys that drive
//! it, and the [`Limits`] a scenario must fit (checked by `fathom check` and, before
//! anything is allocated, by `fathom run`).
//!
//! An experiment describes its cost as a list of [`CostTerm`]s
//! ([`crate::Experiment::cost`]): the samples one run simulates, the memory a run
//! holds while it runs (one per worker thread), what the analysis keeps per run, and
//! what is built once. Every count is a float computed from the checked scenario
//! values, so an absurd value gives an absurd estimate, never an overflow or an
//! allocation. The time constants are the measured throughput of the presets on one
//! core, good to a factor of a few: the estimate is for refusing a scenario that
//! needs days or terabytes, not for planning to the minute.

use serde::Serialize;

use crate::SimError;

/// Bytes in a GiB.
pub const GIB: f64 = 1024.0 * 1024.0 * 1024.0;

/// Limits a scenario must fit. The defaults fit a laptop: 4 GiB of memory, 24 h.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Limits {
    /// Peak memory, bytes.
    pub memory_bytes: f64,
    /// Wall-clock run time on the worker threads, s.
    pub seconds: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            memory_bytes: 4.0 * GIB,
            seconds: 24.0 * 3600.0,
        }
    }
}

impl Limits {
    /// Limits from the `--max-memory-gb` and `--max-hours` options (`None`: default).
    ///
    /// # Errors
    /// [`SimError::InvalidArgument`] naming the option for a value that is not a
    /// positive finite number.
    pub fn from_options(memory_gb: Option<f64>, hours: Option<f64>) -> Result<Self, SimError> {
        let d = Limits::default();
        let pos = |what: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(SimError::invalid_argument(
                    what,
                    format!("must be a positive number, got {v}"),
                ))
            }
        };
        Ok(Limits {
            memory_bytes: match memory_gb {
                Some(v) => pos("--max-memory-gb", v)? * GIB,
                None => d.memory_bytes,
            },
            seconds: match hours {
                Some(v) => pos("--max-hours", v)? * 3600.0,
                None => d.seconds,
            },
        })
    }
}

/// How a term's memory scales with the execution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Held {
    /// Built once (shared truth, tables of the analysis).
    Once,
    /// Held by each run while it runs: once per worker thread.
    PerThread,
}

/// A scenario key that drives a [`CostTerm`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CostKey {
    /// The key as written in the scenario (e.g. `motion.step_s`).
    pub key: String,
    /// Its value, in the key's unit.
    pub value: f64,
    /// By how much it raises the cost over the preset (e.g. 10 for a step ten times
    /// smaller than the preset's): the key with the largest factor is the one a
    /// refusal names.
    pub factor: f64,
}

/// One part of a scenario's cost.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CostTerm {
    /// What it is (e.g. "motion steps of a run").
    pub what: String,
    /// The keys that drive it, with their values and their factors over the preset.
    pub keys: Vec<CostKey>,
    /// Samples simulated or processed in total (all runs of all batches).
    pub samples: f64,
    /// Single-core time per sample, s.
    pub seconds_per_sample: f64,
    /// Memory, bytes.
    pub bytes: f64,
    /// How the memory is held.
    pub held: Held,
}

impl CostTerm {
    /// A term of `samples` samples at `seconds_per_sample` and `bytes` of memory.
    pub fn new(
        what: impl Into<String>,
        samples: f64,
        seconds_per_sample: f64,
        bytes: f64,
        held: Held,
    ) -> Self {
        CostTerm {
            what: what.into(),
            keys: Vec::new(),
            samples,
            seconds_per_sample,
            bytes,
            held,
        }
    }

    /// Adds a driving key and its value; the cost grows with the value (`preset`
    /// is the preset's value of the key).
    pub fn up(self, key: impl Into<String>, value: f64, preset: f64) -> Self {
        self.with_key(key, value, value / preset)
    }

    /// Adds a driving key whose cost grows as the value shrinks (a step, a period).
    pub fn down(self, key: impl Into<String>, value: f64, preset: f64) -> Self {
        self.with_key(key, value, preset / value)
    }

    fn with_key(mut self, key: impl Into<String>, value: f64, factor: f64) -> Self {
        let factor = if factor.is_nan() { 0.0 } else { factor };
        self.keys.push(CostKey {
            key: key.into(),
            value,
            factor,
        });
        self
    }

    /// The term's single-core time, s (0 for a term that costs memory only, even with
    /// an infinite sample count).
    pub fn seconds(&self) -> f64 {
        if self.seconds_per_sample == 0.0 {
            0.0
        } else {
            self.samples * self.seconds_per_sample
        }
    }

    fn memory(&self, threads: f64) -> f64 {
        match self.held {
            Held::Once => self.bytes,
            Held::PerThread => self.bytes * threads,
        }
    }

    /// The main key (the largest factor over the preset) and the term described with
    /// every key's value, the main key first.
    fn describe(&self) -> (String, String) {
        let mut keys: Vec<&CostKey> = self.keys.iter().collect();
        keys.sort_by(|a, b| b.factor.total_cmp(&a.factor));
        let main = keys
            .first()
            .map_or_else(|| "runs".to_string(), |k| k.key.clone());
        let keys = keys
            .iter()
            .map(|k| format!("`{}` = {}", k.key, short(k.value)))
            .collect::<Vec<_>>()
            .join(", ");
        let from = if keys.is_empty() {
            String::new()
        } else {
            format!(" from {keys}")
        };
        (main, format!("{}{from}", self.what))
    }
}

/// A scenario's estimated cost.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cost {
    /// The parts; empty for an experiment that gives no estimate.
    pub terms: Vec<CostTerm>,
    /// Worker threads the estimate is for.
    pub threads: usize,
}

impl Cost {
    /// A cost from its terms, for `threads` worker threads.
    pub fn new(terms: Vec<CostTerm>, threads: usize) -> Self {
        Cost {
            terms,
            threads: threads.max(1),
        }
    }

    /// Whether the experiment gave an estimate.
    pub fn is_known(&self) -> bool {
        !self.terms.is_empty()
    }

    /// Samples in total.
    pub fn samples(&self) -> f64 {
        self.terms.iter().map(|t| t.samples).sum()
    }

    /// Peak memory, bytes.
    pub fn memory_bytes(&self) -> f64 {
        let threads = self.threads as f64;
        self.terms.iter().map(|t| t.memory(threads)).sum()
    }

    /// Wall-clock time on the worker threads, s.
    pub fn seconds(&self) -> f64 {
        self.terms.iter().map(CostTerm::seconds).sum::<f64>() / self.threads as f64
    }

    /// One line: samples, memory, time (orders of magnitude).
    pub fn summary(&self) -> String {
        if !self.is_known() {
            return "cost not estimated for this experiment".into();
        }
        format!(
            "about {} samples, {} of memory, {} on {} thread{}",
            short(self.samples()),
            bytes(self.memory_bytes()),
            duration(self.seconds()),
            self.threads,
            if self.threads == 1 { "" } else { "s" }
        )
    }

    /// Checks the cost against `limits`; the refusal names the key of the largest
    /// part (`file` labels it).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the key, the estimate and the limit.
    pub fn check(&self, limits: &Limits, file: &str) -> Result<(), SimError> {
        let threads = self.threads as f64;
        let memory = self.memory_bytes();
        // NaN compares false: a NaN estimate (never expected) is refused too.
        if memory.is_nan() || memory > limits.memory_bytes {
            let worst = self
                .terms
                .iter()
                .max_by(|a, b| a.memory(threads).total_cmp(&b.memory(threads)));
            let (key, what) =
                worst.map_or_else(|| ("runs".into(), String::new()), CostTerm::describe);
            return Err(SimError::invalid(
                file,
                key,
                format!(
                    "the run would need about {} of memory (mostly {what}), more than the \
                     limit of {} (--max-memory-gb); lower the value",
                    bytes(memory),
                    bytes(limits.memory_bytes)
                ),
            ));
        }
        let seconds = self.seconds();
        if seconds.is_nan() || seconds > limits.seconds {
            let worst = self
                .terms
                .iter()
                .max_by(|a, b| a.seconds().total_cmp(&b.seconds()));
            let (key, what) =
                worst.map_or_else(|| ("runs".into(), String::new()), CostTerm::describe);
            return Err(SimError::invalid(
                file,
                key,
                format!(
                    "the run would take about {} on {} thread{} (mostly {what}), more than the \
                     limit of {} (--max-hours); lower the value",
                    duration(seconds),
                    self.threads,
                    if self.threads == 1 { "" } else { "s" },
                    duration(limits.seconds)
                ),
            ));
        }
        Ok(())
    }
}

/// A number with 2 significant digits (`180`, `1.2e+11`).
pub fn short(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e6).contains(&a) {
        return format!("{v:.1e}");
    }
    let s = if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    };
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Bytes as KiB / MiB / GiB / TiB.
pub fn bytes(b: f64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    if !b.is_finite() {
        return format!("{b} B");
    }
    let mut v = b;
    for u in &UNITS[..4] {
        if v < 1024.0 {
            return format!("{} {u}", short(v.max(0.0)));
        }
        v /= 1024.0;
    }
    format!("{} {}", short(v), UNITS[4])
}

/// Seconds as an order of magnitude (`< 1 s`, `40 s`, `3 min`, `5 h`, `2e+06 days`).
pub fn duration(s: f64) -> String {
    if !s.is_finite() {
        return format!("{s} s");
    }
    if s < 1.0 {
        "under a second".into()
    } else if s < 120.0 {
        format!("{} s", s.round())
    } else if s < 7200.0 {
        format!("{} min", (s / 60.0).round())
    } else if s < 172_800.0 {
        format!("{} h", (s / 3600.0).round())
    } else {
        format!("{} days", short((s / 86_400.0).round()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cost() -> Cost {
        Cost::new(
            vec![
                CostTerm::new("motion steps", 1e6, 1e-7, 1e3, Held::PerThread)
                    .up("motion.duration_s", 180.0, 180.0)
                    .down("motion.step_s", 0.01, 0.01),
                CostTerm::new("kept per run", 100.0, 0.0, 1e4, Held::Once).up("runs", 100.0, 100.0),
            ],
            4,
        )
    }

    #[test]
    fn totals_follow_the_terms() {
        let c = cost();
        assert_eq!(c.samples(), 1e6 + 100.0);
        assert_eq!(c.memory_bytes(), 4e3 + 1e4);
        assert!((c.seconds() - 0.1 / 4.0).abs() < 1e-12);
        assert!(c.check(&Limits::default(), "f.toml").is_ok());
        assert!(
            c.summary().starts_with("about 1.0e6 samples"),
            "{}",
            c.summary()
        );
    }

    /// The message of a cost the default limits refuse.
    fn refusal(c: &Cost) -> String {
        c.check(&Limits::default(), "f.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn a_refusal_names_the_largest_part_and_the_limit() {
        let mut c = cost();
        c.terms[1].bytes = 1e12;
        let e = refusal(&c);
        assert!(
            e.starts_with("f.toml: key `runs`: the run would need about 931 GiB"),
            "{e}"
        );
        assert!(e.contains("limit of 4 GiB"), "{e}");
        let mut c = cost();
        c.terms[0].samples = 1e15;
        let e = refusal(&c);
        assert!(
            e.starts_with("f.toml: key `motion.duration_s`: the run would take"),
            "{e}"
        );
        assert!(e.contains("`motion.step_s` = 0.01"), "{e}");
        // The key named is the one furthest beyond the preset.
        c.terms[0].keys[1].factor = 1e9;
        let e = refusal(&c);
        assert!(e.starts_with("f.toml: key `motion.step_s`:"), "{e}");
        // NaN and infinite estimates are refused, not let through.
        c.terms[0].samples = f64::NAN;
        assert!(c.check(&Limits::default(), "f").is_err());
        c.terms[0].samples = f64::INFINITY;
        assert!(c.check(&Limits::default(), "f").is_err());
        // A memory-only term with an infinite count costs no time (not NaN).
        let t = CostTerm::new("m", f64::INFINITY, 0.0, 1.0, Held::Once);
        assert_eq!(t.seconds(), 0.0);
    }

    #[test]
    fn limits_from_options() {
        let l = Limits::from_options(Some(1.0), Some(2.0)).unwrap();
        assert_eq!((l.memory_bytes, l.seconds), (GIB, 7200.0));
        assert_eq!(Limits::from_options(None, None).unwrap(), Limits::default());
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Limits::from_options(Some(bad), None).is_err());
            assert!(Limits::from_options(None, Some(bad)).is_err());
        }
    }

    #[test]
    fn readable_magnitudes() {
        assert_eq!(short(180.0), "180");
        assert_eq!(short(0.01), "0.01");
        assert_eq!(short(1e9), "1.0e9");
        assert_eq!(bytes(4.0 * GIB), "4 GiB");
        assert_eq!(bytes(1536.0), "1.5 KiB");
        assert_eq!(duration(0.2), "under a second");
        assert_eq!(duration(3.0 * 3600.0), "3 h");
        assert_eq!(duration(1e9), "11574 days");
    }
}
