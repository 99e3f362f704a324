//! Parallel, reproducible Monte Carlo runs.
//!
//! # Seeding
//! Run `i` of a batch with base seed `s` draws from
//! `ChaCha8Rng::seed_from_u64(s)` switched to stream `i` (`set_stream(i)`), see
//! [`run_rng`]. ChaCha's 64-bit stream id gives each run an independent
//! 2^64-block keystream from the same key, so runs never overlap, and run `i` can be
//! reproduced alone with [`run_rng`]. Results depend only on `(base_seed, i)`, never on
//! the number of threads or the scheduling: the same inputs give bit-identical output
//! with 1 or many threads.
//!
//! The `*_with_progress` variants also report the batch and every finished run to a
//! [`Progress`] hook (see [`crate::progress`]); the hook cannot change the results.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::progress::{Progress, ProgressEvent};

/// The RNG of run `run_index` in a batch with `base_seed`:
/// `ChaCha8Rng::seed_from_u64(base_seed)` with `set_stream(run_index)`.
pub fn run_rng(base_seed: u64, run_index: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(base_seed);
    rng.set_stream(run_index as u64);
    rng
}

/// Run `f(run_index, rng)` for `run_index in 0..runs`, in parallel, and return the
/// results in run order.
///
/// `threads`: `None` uses rayon's global pool (all cores, or `RAYON_NUM_THREADS`);
/// `Some(n)` builds a local pool with `n` threads (`Some(0)` = rayon's default count).
/// If the local pool cannot be built, the runs execute on the global pool instead,
/// which changes nothing in the results (see the module docs on seeding).
pub fn run_monte_carlo<T, F>(runs: usize, base_seed: u64, threads: Option<usize>, f: F) -> Vec<T>
where
    T: Send,
    F: Fn(usize, &mut ChaCha8Rng) -> T + Sync,
{
    run_monte_carlo_with_progress(runs, base_seed, threads, None, "", f)
}

/// [`run_monte_carlo`] reporting to `progress` (if any): the batch `label` and its size
/// first, then every finished run (from the worker thread that ran it), then the end of
/// the batch (see [`crate::progress`]). The hook only observes: results are the same
/// with or without it.
pub fn run_monte_carlo_with_progress<T, F>(
    runs: usize,
    base_seed: u64,
    threads: Option<usize>,
    progress: Option<&Progress>,
    label: &str,
    f: F,
) -> Vec<T>
where
    T: Send,
    F: Fn(usize, &mut ChaCha8Rng) -> T + Sync,
{
    if let Some(p) = progress {
        p.report(ProgressEvent::BatchStarted {
            label: label.to_string(),
            total: runs,
        });
    }
    let work = || {
        (0..runs)
            .into_par_iter()
            .map(|i| {
                let mut rng = run_rng(base_seed, i);
                let out = f(i, &mut rng);
                if let Some(p) = progress {
                    p.report(ProgressEvent::RunFinished { index: i });
                }
                out
            })
            .collect::<Vec<T>>()
    };
    let results = in_pool(threads, work);
    if let Some(p) = progress {
        p.report(ProgressEvent::BatchFinished {
            label: label.to_string(),
        });
    }
    results
}

/// Like [`run_monte_carlo`] for a fallible run function: all runs are executed, and the
/// error of the lowest failing run index is returned (deterministic whatever the
/// thread count); otherwise all results in run order.
///
/// # Errors
/// The error of the first (by run index) failing run.
pub fn try_run_monte_carlo<T, E, F>(
    runs: usize,
    base_seed: u64,
    threads: Option<usize>,
    f: F,
) -> Result<Vec<T>, E>
where
    T: Send,
    E: Send,
    F: Fn(usize, &mut ChaCha8Rng) -> Result<T, E> + Sync,
{
    try_run_monte_carlo_with_progress(runs, base_seed, threads, None, "", f)
}

/// [`try_run_monte_carlo`] reporting to `progress` as
/// [`run_monte_carlo_with_progress`] (a failed run counts as finished).
///
/// # Errors
/// The error of the first (by run index) failing run.
pub fn try_run_monte_carlo_with_progress<T, E, F>(
    runs: usize,
    base_seed: u64,
    threads: Option<usize>,
    progress: Option<&Progress>,
    label: &str,
    f: F,
) -> Result<Vec<T>, E>
where
    T: Send,
    E: Send,
    F: Fn(usize, &mut ChaCha8Rng) -> Result<T, E> + Sync,
{
    run_monte_carlo_with_progress(runs, base_seed, threads, progress, label, f)
        .into_iter()
        .collect()
}

/// Runs `f(i, rng)` for the run indices `indices` in parallel (run `i` draws from
/// [`run_rng`]`(base_seed, i)`) and returns the results in index order, reporting every
/// finished run to `progress` (the caller reports the batch's start and end). The
/// driver calls it chunk by chunk, so that a batch's records need not all be in memory
/// at once; the results do not depend on how the indices are chunked.
///
/// # Errors
/// The error of the first (by run index) failing run.
pub fn try_run_indices<T, E, F>(
    indices: std::ops::Range<usize>,
    base_seed: u64,
    threads: Option<usize>,
    progress: Option<&Progress>,
    f: F,
) -> Result<Vec<T>, E>
where
    T: Send,
    E: Send,
    F: Fn(usize, &mut ChaCha8Rng) -> Result<T, E> + Sync,
{
    let work = || {
        indices
            .into_par_iter()
            .map(|i| {
                let mut rng = run_rng(base_seed, i);
                let out = f(i, &mut rng);
                if let Some(p) = progress {
                    p.report(ProgressEvent::RunFinished { index: i });
                }
                out
            })
            .collect::<Vec<Result<T, E>>>()
    };
    in_pool(threads, work).into_iter().collect()
}

fn in_pool<R: Send>(threads: Option<usize>, work: impl FnOnce() -> R + Send) -> R {
    match threads {
        Some(n) => match rayon::ThreadPoolBuilder::new().num_threads(n).build() {
            Ok(pool) => pool.install(work),
            Err(_) => work(),
        },
        None => work(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;
    use std::sync::{Arc, Mutex};

    fn draw(i: usize, rng: &mut ChaCha8Rng) -> (usize, Vec<u64>, f64) {
        let v: Vec<u64> = (0..50).map(|_| rng.random::<u64>()).collect();
        let x: f64 = rng.random::<f64>();
        (i, v, x)
    }

    #[test]
    fn same_results_for_one_and_many_threads() {
        let one = run_monte_carlo(64, 7, Some(1), draw);
        let four = run_monte_carlo(64, 7, Some(4), draw);
        let global = run_monte_carlo(64, 7, None, draw);
        assert_eq!(one.len(), 64);
        for k in 0..64 {
            assert_eq!(one[k].0, k);
            assert_eq!(one[k].1, four[k].1);
            assert_eq!(one[k].2.to_bits(), four[k].2.to_bits());
            assert_eq!(one[k].2.to_bits(), global[k].2.to_bits());
        }
    }

    #[test]
    fn runs_are_distinct_and_depend_on_base_seed() {
        let a = run_monte_carlo(8, 1, Some(2), draw);
        let b = run_monte_carlo(8, 2, Some(2), draw);
        for i in 0..8 {
            assert_ne!(a[i].1, b[i].1);
            for j in 0..i {
                assert_ne!(a[i].1, a[j].1);
            }
        }
        // Run i alone reproduces run i of the batch.
        let mut rng = run_rng(1, 5);
        assert_eq!(draw(5, &mut rng), a[5]);
    }

    #[test]
    fn zero_runs_give_empty_vec() {
        let v: Vec<u64> = run_monte_carlo(0, 1, Some(3), |_, r| r.random());
        assert!(v.is_empty());
    }

    #[test]
    fn try_variant_returns_first_error_by_index() {
        let r: Result<Vec<usize>, String> = try_run_monte_carlo(100, 3, Some(4), |i, _| {
            if i % 17 == 5 && i > 20 {
                Err(format!("run {i}"))
            } else {
                Ok(i)
            }
        });
        assert_eq!(r.unwrap_err(), "run 22");
        let ok: Result<Vec<usize>, String> = try_run_monte_carlo(10, 3, None, |i, _| Ok(i * 2));
        assert_eq!(ok.unwrap(), (0..10).map(|i| i * 2).collect::<Vec<_>>());
    }

    /// A hook recording every event (thread-safe).
    fn recorder() -> (Progress, Arc<Mutex<Vec<ProgressEvent>>>) {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&seen);
        (Progress::new(move |e| sink.lock().unwrap().push(e)), seen)
    }

    #[test]
    fn progress_counts_every_run_exactly_once_and_changes_nothing() {
        for threads in [Some(1), Some(3), None] {
            let (hook, seen) = recorder();
            let with = run_monte_carlo_with_progress(57, 9, threads, Some(&hook), "batch", draw);
            let without = run_monte_carlo(57, 9, threads, draw);
            assert_eq!(with, without, "{threads:?}");
            let ev = seen.lock().unwrap().clone();
            assert_eq!(ev.len(), 57 + 2, "{threads:?}");
            assert_eq!(
                ev[0],
                ProgressEvent::BatchStarted {
                    label: "batch".into(),
                    total: 57
                }
            );
            assert_eq!(
                ev[58],
                ProgressEvent::BatchFinished {
                    label: "batch".into()
                }
            );
            let mut indices: Vec<usize> = ev[1..58]
                .iter()
                .map(|e| match e {
                    ProgressEvent::RunFinished { index } => *index,
                    other => panic!("unexpected {other:?}"),
                })
                .collect();
            indices.sort_unstable();
            assert_eq!(indices, (0..57).collect::<Vec<_>>());
        }
    }

    #[test]
    fn progress_counts_failed_runs_and_keeps_the_first_error() {
        let (hook, seen) = recorder();
        let f = |i: usize, _: &mut ChaCha8Rng| {
            if i == 4 || i == 7 { Err(i) } else { Ok(i) }
        };
        let r: Result<Vec<usize>, usize> =
            try_run_monte_carlo_with_progress(12, 1, Some(2), Some(&hook), "x", f);
        assert_eq!(r, Err(4));
        assert_eq!(r, try_run_monte_carlo(12, 1, Some(2), f));
        let finished = seen
            .lock()
            .unwrap()
            .iter()
            .filter(|e| matches!(e, ProgressEvent::RunFinished { .. }))
            .count();
        assert_eq!(finished, 12);
    }
}
