//! End-to-end tests of fathom: whole experiments run through the same driver as
//! `cargo xtask paper`, on reduced scenarios, checking the output contract,
//! determinism across thread counts and the handling of malformed scenario files.
//!
//! One test binary for the whole workspace; each experiment has its own module.

mod support;

mod beacons;
mod bounded_errors;
mod campaign;
mod cli;
mod default_outputs;
mod determinism;
mod drone_world;
mod every_key;
mod fusion;
mod fuzz_corpus;
mod hardening;
mod imu_allan;
mod limits;
mod map_aided;
mod noise;
mod outputs;
mod own_logs;
mod pils;
mod plaza;
mod quadrotor_ins;
mod report_text;
mod scene_page;
mod smoother;
mod statistics;
mod ulog;
mod urban;
mod user_scenarios;
mod vkf;
