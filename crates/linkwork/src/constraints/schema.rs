//! What the joints' and drivers' compile steps ask beyond the [`Context`] every element shares:
//! general constraints of the coordinates and the joints' friction ([`JointContext`]).

use super::{CompiledJoint, Constraint, Friction, FrictionLaw, GeneralConstraint, DEFAULT_TRANSITION_VELOCITY};
use crate::element::Context;

/// The [`Context`] of a joint or a driver: it also compiles general constraints and checks a
/// joint's friction.
pub(crate) trait JointContext: Context {
    /// A general constraint `src = 0` at `path`: an expression of `<body>.x, .y, .phi` and `t`.
    fn coordinate_constraint(&mut self, path: &str, src: &str) -> Option<GeneralConstraint>;

    /// The coefficient and transition velocity of the `friction:` mapping at `path`, checked.
    fn friction_law(&mut self, path: &str, mu: f64, transition_velocity: Option<f64>) -> Option<FrictionLaw> {
        let mu = self.finite(&format!("{path}.mu"), mu).and_then(|mu| {
            if mu >= 0.0 {
                Some(mu)
            } else {
                self.problem(format!("{path}.mu"), format!("expected a coefficient of friction >= 0, found {mu}"));
                None
            }
        });
        let v_s = match transition_velocity {
            Some(v) => self.positive(&format!("{path}.transition_velocity"), v),
            None => Some(DEFAULT_TRANSITION_VELOCITY),
        };
        Some(FrictionLaw { mu: mu?, transition_velocity: v_s? })
    }

    /// The `friction:` mapping at `path` of a joint that has one, checked: its law, and its size
    /// (`field`: the pin's radius, the block's length) `> 0`. `None` when either is bad.
    fn sized_friction(
        &mut self,
        path: &str,
        mu: f64,
        transition_velocity: Option<f64>,
        (field, size): (&str, f64),
    ) -> Option<(FrictionLaw, f64)> {
        let at = format!("{path}.friction");
        let law = self.friction_law(&at, mu, transition_velocity);
        let size = self.positive(&format!("{at}.{field}"), size);
        Some((law?, size?))
    }
}

/// A joint compiled with its friction: `joint`, and, when it has a `friction:` mapping (`law`,
/// checked by [`JointContext::sized_friction`]), the friction `make` builds from its law and size;
/// `None` when the mapping was bad.
pub(crate) fn with_friction<J: Constraint + 'static>(
    joint: J,
    law: Option<Option<(FrictionLaw, f64)>>,
    make: impl FnOnce(&J, FrictionLaw, f64) -> Friction,
) -> Option<CompiledJoint> {
    let friction = match law {
        Some(law) => {
            let (law, size) = law?;
            Some(make(&joint, law, size))
        }
        None => None,
    };
    Some((Box::new(joint), friction))
}
