//! GNSS against the map (spec D): satellite orbits ([`orbit`]: Keplerian elements,
//! the nominal 24-slot GPS constellation), the local frame of the scenario origin
//! ([`geodesy`]), a fixed nine-satellite sky for a line-of-sight count ([`sky`]), the receiver's per-satellite line of sight, pseudoranges and
//! Doppler ([`receiver`]), least-squares single-point positioning with DOP
//! ([`spp`]), and the paper's BESTPOS model ([`bestpos`]).

pub mod bestpos;
pub mod geodesy;
pub mod orbit;
pub mod receiver;
pub mod sky;
pub mod spp;

pub use bestpos::{Bestpos, BestposParams};
pub use geodesy::{LocalFrame, LocalFrameParams};
pub use orbit::{KeplerElements, Orbit, SatState, nominal_gps24};
pub use receiver::{GnssParams, GnssReceiver, SatObservation};
pub use sky::{fixed_sky_directions, los_count};
pub use spp::{Dop, SppSolution, solve_spp};
