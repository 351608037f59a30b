//! Placeholder while the bdf integrator is written.

use super::{Dae, DynamicStats, IntegratorSettings, Outcome, Output, Start};
use crate::error::Error;

/// Integrate from `start` to the output's end time.
pub fn run(_dae: &mut Dae<'_>, _out: &mut Output, _settings: &IntegratorSettings, start: Start) -> Outcome {
    let cause = "bdf is not available yet".into();
    (DynamicStats::default(), Err(Error::Integration { time: start.t, step: 0.0, cause, rows: vec![] }))
}
