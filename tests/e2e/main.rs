//! e2e
mod beacons;
