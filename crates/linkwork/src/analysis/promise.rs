//! What a run promised, checked after it: the constraint residuals at every output against the
//! tolerances scaled to the mechanism, and a conservative system's energy against what the
//! integrator's tolerances allow (docs/integrators.md, "What a run promises";
//! docs/kinematics.md, "The residual at every output"). A run that breaks a promise fails with
//! [`Error::Accuracy`], its results kept; an energy drift between the two thresholds is a
//! warning.

use super::dynamic::ROUNDOFF_UNITS;
use super::residual_floor;
use crate::error::{Error, RowName};
use crate::model::IntegratorSettings;

/// A dynamic run's position residual may reach this many times its tolerance at the
/// mechanism's size, `atol + rtol L` (`L` the largest body coordinate `|x|, |y|` at an output),
/// before it fails: 10. The integrators' Newton stops within a third of the tolerance, and the
/// output interpolant adds its own error: measured on the examples' dynamic analyses (double
/// pendulum, IFToMM A01 and A02, Andrews, both quick-returns, wedge, bouncing disc) with the three
/// integrators at `rtol = atol` from `1e-2` to `1e-11`, the largest was `0.38` of it (`hht`, A01).
pub const POSITION_FACTOR: f64 = 10.0;

/// The same for the velocity residual, against `atol + rtol V` (`V` the largest body speed
/// component): `1e5`. The index-3 methods (`hht`, `bdf` index 3) do not impose the velocity
/// constraints; theirs follow the positions' error divided by the step, and grow as the tolerance
/// shrinks: measured as above, at most `6.2e3` (`hht`, Andrews, `1e-11`), `2.4e3` at `1e-10`.
pub const VELOCITY_FACTOR: f64 = 1e5;

/// A velocity residual above this fraction of the largest speed fails whatever the tolerances
/// allow: `0.5`. The joints' velocity equations are then not satisfied at all: the residual is as
/// large as the motion it constrains (the double pendulum at `rtol = atol = 1e-2` reaches `0.12`).
pub const VELOCITY_SPEED_FRACTION: f64 = 0.5;

/// A conservative system's energy drift, relative to the energy of its motion, above which the
/// summary warns: `1e4` times the tolerance (`max(rtol, atol / L)`), the ratio of the global to
/// the local error that the property tests bound (tests/properties.rs, free dynamics keeps its
/// energy; the examples reach `5.3e3`, `hht` on A02 at `1e-8`); but not below
/// [`DRIFT_WARNING_FLOOR`] nor above [`DRIFT_WARNING_CEILING`].
pub const DRIFT_PER_TOLERANCE: f64 = 1e4;

/// The smallest relative drift warned about: `1e-4`. At tolerances below `1e-8` `hht`'s own
/// damping (`alpha`) no longer shrinks with the tolerance (`1.7e-6` of the double pendulum's
/// energy at `1e-10`, `3.6e-7` at `1e-11`, `1.7e4` and `3.6e4` times the tolerance), far below
/// anything a result is read for.
pub const DRIFT_WARNING_FLOOR: f64 = 1e-4;

/// The largest relative drift that passes without a warning whatever the tolerance: `1e-2`, a
/// hundredth of the energy of the motion (`1e4 rtol` would allow all of it at `rtol = 1e-2`).
pub const DRIFT_WARNING_CEILING: f64 = 1e-2;

/// The relative drift at which a conservative run fails: `0.5`, half the energy of its motion
/// gained or lost. Nothing of such a run is the motion of the system in the file (a spring of
/// 1e12 N/m under `bdf` at the default tolerances loses 99.7% in 1 ms, docs/integrators.md).
pub const DRIFT_FAILURE: f64 = 0.5;

/// A kinematic output whose residual (every row, the redundant ones too) exceeds this fraction of
/// the mechanism's size (the largest body coordinate `|x|, |y|`) and `solver.tolerance` fails:
/// `1e-6`. Newton stops at the tolerance or at the round-off of the coordinates
/// ([`residual_floor`], which counts the angles: `1.4e-14` of a metre-sized mechanism, `9e-11`
/// after 1000 turns); above a millionth of the mechanism the round-off of huge angles or times
/// has taken over (a start at `t = 1e12` s left a joint open by 5.4 cm, 4.9e-2 of residual, as
/// "converged").
pub const KINEMATIC_SIZE_FRACTION: f64 = 1e-6;

/// The smallest relative tolerance the checks hold a run to: `2.2e-12`, ten times the round-off
/// at which the integrators' Newton stops (`1000 eps` of the state, [`ROUNDOFF_UNITS`]). At
/// `rtol = 1e-16` (raised to `2.2e-14`) `hht`'s velocity residual on A01 is `1.6e-8` m/s at
/// 1.9 m/s: `3.7e5` times `rtol V`, `3.8e3` times this floor's.
pub const TOLERANCE_FLOOR: f64 = 10.0 * ROUNDOFF_UNITS * f64::EPSILON;

/// The largest value of one checked quantity over the outputs, with its time and row.
#[derive(Debug, Clone, Copy, Default)]
pub struct Worst {
    /// The value.
    pub value: f64,
    /// Its output time, s.
    pub time: f64,
    /// Its constraint row.
    pub row: usize,
}

impl Worst {
    /// Keep `(value, time, row)` if it is the largest yet.
    pub fn see(&mut self, value: f64, time: f64, row: usize) {
        if value > self.value {
            *self = Worst { value, time, row };
        }
    }
}

/// What a dynamic run's outputs showed, for its checks.
#[derive(Debug, Clone, Default)]
pub struct Audit {
    /// Largest body coordinate `|x|, |y|` at an output, m.
    pub length: f64,
    /// Largest body velocity component `|vx|, |vy|`, m/s.
    pub speed: f64,
    /// Largest round-off floor of the positions at an output ([`residual_floor`]).
    pub floor: f64,
    /// Largest position and velocity residuals.
    pub position: Worst,
    pub velocity: Worst,
    /// Energy at the first output, J.
    energy0: Option<f64>,
    /// Largest kinetic energy, least and largest potential energy, largest `|T| + |V|`, J.
    kinetic: f64,
    potential: (f64, f64),
    size: f64,
    /// Largest `|E - E0|`, J, and its time.
    drift: Worst,
}

impl Audit {
    /// Record an output at `t`: positions `q`, velocities `qdot`, energies.
    pub fn see(&mut self, t: f64, q: &[f64], qdot: &[f64], kinetic: f64, potential: f64) {
        let translations = |v: &[f64]| v.chunks(3).flat_map(|b| [b[0].abs(), b[1].abs()]).fold(0.0f64, f64::max);
        self.length = self.length.max(translations(q));
        self.speed = self.speed.max(translations(qdot));
        self.floor = self.floor.max(residual_floor(q));
        let energy = kinetic + potential;
        let e0 = *self.energy0.get_or_insert(energy);
        if self.size == 0.0 {
            self.potential = (potential, potential);
        }
        self.kinetic = self.kinetic.max(kinetic);
        self.potential = (self.potential.0.min(potential), self.potential.1.max(potential));
        self.size = self.size.max(kinetic.abs() + potential.abs()).max(f64::MIN_POSITIVE);
        self.drift.see((energy - e0).abs(), t, 0);
    }
}

/// Check a dynamic run that ended well: its position and velocity residuals, and for a
/// `conservative` system its energy. A drift between the thresholds adds a warning to
/// `warnings`. `row_name` names a constraint row.
pub fn check_dynamic(
    audit: &Audit,
    settings: &IntegratorSettings,
    conservative: bool,
    row_name: impl Fn(usize) -> RowName,
    warnings: &mut Vec<String>,
) -> Result<(), Error> {
    let (rtol, atol) = (settings.rtol, settings.atol);
    let relative = rtol.max(TOLERANCE_FLOOR);
    let asked = atol + relative * audit.length;
    let bound = (POSITION_FACTOR * asked).max(audit.floor);
    let residual = |quantity: &'static str, worst: Worst, bound: f64, detail: String| {
        if worst.value > bound {
            let rows = vec![row_name(worst.row)];
            return Err(Error::Accuracy { time: worst.time, quantity, rows, value: worst.value, bound, detail });
        }
        Ok(())
    };
    residual(
        "position residual",
        audit.position,
        bound,
        format!(
            "the joints are open by more than {POSITION_FACTOR} times what rtol {rtol:e} and atol {atol:e} ask at this \
             mechanism's size ({:.3e} m): the integrator's steps do not hold its constraints; tighten rtol/atol",
            audit.length
        ),
    )?;
    let asked = atol + relative * audit.speed;
    let bound = (VELOCITY_FACTOR * asked).min((VELOCITY_SPEED_FRACTION * audit.speed).max(POSITION_FACTOR * asked));
    residual(
        "velocity residual",
        audit.velocity,
        bound,
        format!(
            "the velocities break the joints by more than rtol {rtol:e} and atol {atol:e} allow at the largest speed \
             ({:.3e} m/s), or by half of it: tighten rtol/atol",
            audit.speed
        ),
    )?;
    if conservative {
        check_energy(audit, settings, warnings)?;
    }
    Ok(())
}

/// The energy check of a conservative run ([`check_dynamic`]).
fn check_energy(audit: &Audit, settings: &IntegratorSettings, warnings: &mut Vec<String>) -> Result<(), Error> {
    // The energy of the motion: the largest kinetic energy and the range of the potential.
    let motion = audit.kinetic.max(audit.potential.1 - audit.potential.0);
    // A mechanism that barely moves: its energies differ by round-off of their size (the
    // property test's `1e-12`).
    if motion <= 1e-12 * audit.size {
        return Ok(());
    }
    let (rtol, atol) = (settings.rtol, settings.atol);
    let tolerance = if audit.length > 0.0 { rtol.max(atol / audit.length) } else { rtol };
    let drift = audit.drift.value / motion;
    let kind = settings.kind.name();
    let what = format!(
        "the energy of this conservative system (no damping, friction, contact, drivers or applied loads) changed \
         by {:.1}% of the energy of its motion ({:.3e} J of {motion:.3e} J) by t = {} s",
        100.0 * drift,
        audit.drift.value,
        crate::error::seconds(&audit.drift.time)
    );
    let advice = format!(
        "{kind}'s steps, each within rtol {rtol:e} and atol {atol:e}, added their errors up: tighten rtol and atol \
         (atol well below the motion's amplitude){}",
        if kind == "abam" { "" } else { ", or use abam, which does not damp" }
    );
    if drift > DRIFT_FAILURE {
        return Err(Error::Accuracy {
            time: audit.drift.time,
            quantity: "energy drift",
            rows: vec![],
            value: drift,
            bound: DRIFT_FAILURE,
            detail: format!("{what}; {advice}"),
        });
    }
    let warn = (DRIFT_PER_TOLERANCE * tolerance).clamp(DRIFT_WARNING_FLOOR, DRIFT_WARNING_CEILING);
    if drift > warn {
        warnings.push(format!("{what}, more than the tolerances account for ({warn:.0e} of it); {advice}"));
    }
    Ok(())
}

/// Check a kinematic output at `t`: `residual` in the row `row` names (every row, the redundant ones too)
/// at positions `q`, velocities `qdot`, against `tolerance` and [`KINEMATIC_SIZE_FRACTION`] of
/// the mechanism's size.
pub fn check_kinematic(
    t: f64,
    q: &[f64],
    qdot: &[f64],
    residual: f64,
    row: impl FnOnce() -> RowName,
    tolerance: f64,
) -> Result<(), Error> {
    let size = q.chunks(3).flat_map(|b| [b[0].abs(), b[1].abs()]).fold(0.0f64, f64::max);
    let bound = tolerance.max(KINEMATIC_SIZE_FRACTION * size);
    if residual <= bound {
        return Ok(());
    }
    let detail = if residual_floor(q) > tolerance {
        let angle = q.chunks(3).map(|b| b[2].abs()).fold(0.0f64, f64::max);
        let rate = qdot.chunks(3).map(|b| b[2].abs()).fold(0.0f64, f64::max);
        format!(
            "the round-off of the coordinates: the angles reach {angle:.3e} rad, and a unit of round-off of t \
             ({:.3e} s) turns the bodies by {:.3e} rad, so Newton cannot close the joints to solver.tolerance \
             {tolerance:e} nor to {KINEMATIC_SIZE_FRACTION:e} of the mechanism's size ({size:.3e} m); start the \
             analysis near t = 0 (count time from the start in the drivers' functions)",
            f64::EPSILON * t.abs(),
            f64::EPSILON * t.abs() * rate
        )
    } else {
        format!(
            "Newton met solver.tolerance {tolerance:e} on the independent rows, and this row, left out as \
             redundant, does not hold: the redundant constraints disagree"
        )
    };
    Err(Error::Accuracy { time: t, quantity: "position residual", rows: vec![row()], value: residual, bound, detail })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(r: usize) -> RowName {
        RowName { element: format!("J{r}"), equation: "x".into() }
    }

    /// Outputs of a body at 2 m moving at 5 m/s, its energy `T + V` over two outputs.
    fn audit(energies: [(f64, f64); 2]) -> Audit {
        let mut a = Audit::default();
        for (k, (kinetic, potential)) in energies.into_iter().enumerate() {
            a.see(k as f64, &[2.0, 0.0, 0.1], &[5.0, 0.0, 1.0], kinetic, potential);
        }
        a
    }

    /// A position residual above `10 (atol + rtol L)` fails naming its row and time; at the
    /// bound it passes. `L = 2` m, `rtol = atol = 1e-6`: the bound is `3e-5`.
    #[test]
    fn a_position_residual_beyond_the_tolerances_fails() {
        let settings = IntegratorSettings::default();
        let mut a = audit([(10.0, 0.0), (10.0, 0.0)]);
        a.position.see(3e-5, 0.5, 2);
        check_dynamic(&a, &settings, true, row, &mut vec![]).unwrap();
        a.position.see(3.1e-5, 0.75, 4);
        let e = check_dynamic(&a, &settings, true, row, &mut vec![]).unwrap_err();
        assert!(matches!(&e, Error::Accuracy { time, rows, .. } if *time == 0.75 && rows == &[row(4)]), "{e}");
        assert!(e.to_string().starts_with("position residual 3.100e-5 at t = 0.75 s in J4.x, above 3.000e-5"), "{e}");
    }

    /// A velocity residual passes up to `1e5 (atol + rtol V)` (`0.6` m/s at `V = 5`), and never
    /// beyond half the largest speed (`2.5` m/s, at `rtol = atol = 1e-4`).
    #[test]
    fn a_velocity_residual_beyond_the_tolerances_fails() {
        let mut settings = IntegratorSettings::default();
        let mut a = audit([(10.0, 0.0), (10.0, 0.0)]);
        a.velocity.see(0.59, 0.5, 1);
        check_dynamic(&a, &settings, false, row, &mut vec![]).unwrap();
        a.velocity.see(0.61, 0.5, 1);
        let e = check_dynamic(&a, &settings, false, row, &mut vec![]).unwrap_err();
        assert!(e.to_string().starts_with("velocity residual 6.100e-1"), "{e}");
        (settings.rtol, settings.atol) = (1e-4, 1e-4);
        check_dynamic(&a, &settings, false, row, &mut vec![]).unwrap();
        a.velocity.see(2.6, 0.5, 1);
        let e = check_dynamic(&a, &settings, false, row, &mut vec![]).unwrap_err();
        assert!(e.to_string().contains("above 2.500e0"), "{e}");
    }

    /// A conservative system's energy at `rtol = atol = 1e-6`: a drift of `1e-3` of the motion's
    /// energy passes (the warning's threshold is `1e4 rtol = 1e-2`), `4.8e-2` warns, `0.7` fails.
    /// A system that is not conservative is not judged.
    #[test]
    fn the_energy_of_a_conservative_system_is_held_to_the_tolerances() {
        let settings = IntegratorSettings::default();
        let mut warnings = vec![];
        check_dynamic(&audit([(10.0, 0.0), (10.01, 0.0)]), &settings, true, row, &mut warnings).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        check_dynamic(&audit([(10.0, 0.0), (10.5, 0.0)]), &settings, true, row, &mut warnings).unwrap();
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].contains("changed by 4.8% of the energy of its motion"), "{warnings:?}");
        let lost = audit([(10.0, 0.0), (3.0, 0.0)]);
        let e = check_dynamic(&lost, &settings, true, row, &mut vec![]).unwrap_err();
        assert!(matches!(&e, Error::Accuracy { time, rows, .. } if *time == 1.0 && rows.is_empty()), "{e}");
        assert!(e.to_string().starts_with("energy drift 7.000e-1 at t = 1 s, above 5.000e-1"), "{e}");
        check_dynamic(&lost, &settings, false, row, &mut warnings).unwrap();
        assert_eq!(warnings.len(), 1);
    }

    /// A kinematic output passes up to `solver.tolerance` or `1e-6` of the mechanism's size
    /// (`2e-6` at 2 m); above it fails, blaming disagreeing redundant rows when the coordinates'
    /// round-off is below the tolerance.
    #[test]
    fn a_kinematic_residual_beyond_the_mechanism_fails() {
        let (q, qdot) = ([2.0, 0.0, 0.1], [0.0, 0.0, 1.0]);
        check_kinematic(0.5, &q, &qdot, 2e-6, || row(0), 1e-12).unwrap();
        check_kinematic(0.5, &q, &qdot, 1e-5, || row(0), 1e-4).unwrap();
        let e = check_kinematic(0.5, &q, &qdot, 3e-6, || row(0), 1e-12).unwrap_err();
        assert!(e.to_string().contains("the redundant constraints disagree"), "{e}");
    }
}
