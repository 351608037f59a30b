//! What each result column holds: a length, an angle, a force ... ([`Model::column_quantity`]),
//! the one place that says it, for the units results are shown in
//! ([`crate::model::units::Display`]) and the labels of tables and plots.

use super::{BODY_QUANTITIES, FRICTION_QUANTITY, REACTION_QUANTITIES};
use crate::model::spec::PointComponent;
use crate::model::{MeasureKind, Model, CONTACT_QUANTITIES, ENERGY_COLUMNS, INVERSE_COLUMNS};

/// The quantity of each body column, in the order of [`BODY_QUANTITIES`].
const BODY: [&str; 9] = [
    "length",
    "length",
    "angle",
    "velocity",
    "velocity",
    "angular_velocity",
    "acceleration",
    "acceleration",
    "angular_acceleration",
];

impl Model {
    /// The quantity (one of [`crate::model::units::QUANTITIES`]) of the result column `name`
    /// (`time` included); `None` for a pure number (a velocity ratio, a mechanical advantage)
    /// and for a column whose quantity is not known: an expression measure, the constraint
    /// residuals (metres and radians together), a name that is no column of this model.
    pub fn column_quantity(&self, name: &str) -> Option<&'static str> {
        if name == "time" {
            return Some("time");
        }
        if let Some(m) = self.measures.iter().find(|m| m.name == name) {
            return match &m.kind {
                MeasureKind::Point { component, .. } => Some(match component {
                    PointComponent::X | PointComponent::Y => "length",
                    PointComponent::Vx | PointComponent::Vy => "velocity",
                    PointComponent::Ax | PointComponent::Ay => "acceleration",
                }),
                MeasureKind::TransmissionAngle { .. } | MeasureKind::PressureAngle(_) => Some("angle"),
                MeasureKind::Expression(_)
                | MeasureKind::VelocityRatio { .. }
                | MeasureKind::MechanicalAdvantage { .. } => None,
            };
        }
        if ENERGY_COLUMNS[..3].contains(&name) || INVERSE_COLUMNS[..2].contains(&name) {
            return Some("energy");
        }
        if INVERSE_COLUMNS[2..].contains(&name) {
            return Some("power");
        }
        let (owner, quantity) = name.rsplit_once('.')?;
        if self.bodies.iter().any(|b| b.name == owner) {
            return BODY_QUANTITIES.iter().position(|q| *q == quantity).map(|k| BODY[k]);
        }
        if let Some(j) = self.joints.iter().find(|j| j.name == owner) {
            return match quantity {
                q if q == REACTION_QUANTITIES[2] => Some("torque"),
                q if REACTION_QUANTITIES.contains(&q) => Some("force"),
                // A pin's friction is a torque, a slider's a force along its axis.
                FRICTION_QUANTITY => Some(if j.kind == "revolute" { "torque" } else { "force" }),
                _ => None,
            };
        }
        if let Some(d) = self.drivers.iter().find(|d| d.name == owner) {
            // An angle's driver holds it with a torque; a distance's or a coordinate's with a force.
            let rotational = matches!(d.kind, "angle" | "relative_angle");
            return (quantity == "effort").then_some(if rotational { "torque" } else { "force" });
        }
        if self.forces.iter().any(|f| f.name == owner) {
            return match quantity {
                q if q == CONTACT_QUANTITIES[2] => Some("length"),
                q if CONTACT_QUANTITIES.contains(&q) => Some("force"),
                _ => None,
            };
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use crate::{Model, Overrides};

    /// The columns of a run of the first analysis of `example` (t_end cut short: the names are
    /// wanted, not the motion).
    fn columns(example: &str) -> (Model, Vec<String>) {
        let path = format!("{}/../../examples/{example}", env!("CARGO_MANIFEST_DIR"));
        let model = Model::load(&path).unwrap();
        let analysis = model.analyses.keys().next().unwrap().clone();
        let overrides = Overrides { t_end: Some(0.01), ..Overrides::default() };
        let results = model.run(&analysis, &overrides.clone().into()).unwrap();
        (model, results.names)
    }

    /// Every column of runs with reactions, efforts of angle and distance drivers, friction,
    /// contacts and measures has its quantity, as docs/model-format.md gives each, but the pure
    /// numbers and the quantities not known.
    #[test]
    fn every_column_has_its_quantity() {
        let expected: &[(&str, &str, Option<&str>)] = &[
            ("slider_crank_friction.yaml", "crank.x", Some("length")),
            ("slider_crank_friction.yaml", "crank.phi", Some("angle")),
            ("slider_crank_friction.yaml", "rod.vy", Some("velocity")),
            ("slider_crank_friction.yaml", "rod.omega", Some("angular_velocity")),
            ("slider_crank_friction.yaml", "rod.ax", Some("acceleration")),
            ("slider_crank_friction.yaml", "rod.alpha", Some("angular_acceleration")),
            ("slider_crank_friction.yaml", "motor.effort", Some("torque")),
            ("slider_crank_friction.yaml", "driver_power", Some("power")),
            ("slider_crank_friction.yaml", "kinetic_energy", Some("energy")),
            ("slider_crank_friction.yaml", "time", Some("time")),
            ("bouncing_disc.yaml", "position_residual", None),
            ("bouncing_disc.yaml", "nonconservative_work", Some("energy")),
            ("fourbar_measures.yaml", "mu", Some("angle")),
            ("fourbar_measures.yaml", "O2.fx", Some("force")),
            ("fourbar_measures.yaml", "O2.torque", Some("torque")),
            ("fourbar_measures.yaml", "no_such.x", None),
        ];
        for &(example, column, quantity) in expected {
            let (model, _) = columns(example);
            assert_eq!(model.column_quantity(column), quantity, "{example}: {column}");
        }
        // Nothing forgotten: every column of these runs is known but the residuals and the
        // measures that are pure numbers or expressions.
        let unknown = |model: &Model, c: &str| {
            c.ends_with("_residual")
                || model.measures.iter().any(|m| {
                    m.name == c
                        && matches!(
                            m.kind,
                            crate::model::MeasureKind::Expression(_)
                                | crate::model::MeasureKind::VelocityRatio { .. }
                                | crate::model::MeasureKind::MechanicalAdvantage { .. }
                        )
                })
        };
        for example in ["slider_crank_friction.yaml", "bouncing_disc.yaml", "fourbar_measures.yaml"] {
            let (model, names) = columns(example);
            for c in &names {
                assert_eq!(model.column_quantity(c).is_some(), !unknown(&model, c), "{example}: {c}");
            }
        }
        let (model, names) = columns("slider_crank_friction.yaml");
        let friction: Vec<_> = names.iter().filter(|c| c.ends_with(".friction")).collect();
        assert!(!friction.is_empty());
        for c in friction {
            let joint = &model.joints.iter().find(|j| c.starts_with(&format!("{}.", j.name))).unwrap();
            let want = if joint.kind == "revolute" { "torque" } else { "force" };
            assert_eq!(model.column_quantity(c), Some(want), "{c}");
        }
        let (model, names) = columns("bouncing_disc.yaml");
        assert!(names.iter().any(|c| model.column_quantity(c) == Some("force") && c.ends_with(".fn")), "{names:?}");
    }
}
