//! The `urban` report notes.

use super::record::KeptRun;
use super::world::Prepared;
use crate::experiment::Analysis;

/// Writes the notes.
pub(super) fn write(_prep: &Prepared, _main: &[KeptRun], _out: &mut Analysis) {}
