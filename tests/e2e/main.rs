//! e2e

mod fusion;
