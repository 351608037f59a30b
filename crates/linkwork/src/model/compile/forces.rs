//! Force elements: applied forces and torques, spring-dampers and contacts, their fields checked
//! and their bodies resolved.

use super::*;

/// The exponent of a contact's penetration when none is given: 1.5, Hertz's for two cylinders'
/// ends or spheres, the usual choice (Lankarani and Nikravesh 1990).
pub const DEFAULT_CONTACT_EXPONENT: f64 = 1.5;

/// A contact's `max_penetration` when none is given, as a fraction of the smallest radius of the
/// pair: 1e-3. A step into first contact then ends at most that deep, where the force is a small
/// fraction of its peak in any impact that deforms the shapes less than their size.
pub const DEFAULT_PENETRATION_FRACTION: f64 = 1e-3;

impl Cx<'_> {
    /// A force's number or expression of time and state at `path`.
    pub(super) fn load(&mut self, path: &str, q: &Quantity) -> Option<Load> {
        match q {
            Quantity::Number(v) => self.finite(path, *v).map(Load::Constant),
            Quantity::Expression(src) => self.state_expr(path, src, false).map(Load::Expression),
        }
    }

    /// The coordinates' index of the moving body `name` at `path`; ground is refused.
    pub(super) fn moving(&mut self, path: &str, name: &str) -> Option<usize> {
        let b = self.body(path, name)?;
        if b == BodyIx::GROUND {
            self.problem(path, "ground does not move: name a moving body");
            return None;
        }
        b.0
    }

    /// A force element at `path`, its fields checked and its bodies resolved.
    pub(super) fn force(&mut self, path: &str, f: &ForceSpec) -> Option<Box<dyn Force>> {
        Some(match f {
            ForceSpec::Force(PointForce { body, point, frame, fx, fy }) => {
                let b = self.moving(&format!("{path}.body"), body);
                let s = self.point(&format!("{path}.point"), body, point);
                let fx = self.load(&format!("{path}.fx"), fx);
                let fy = self.load(&format!("{path}.fy"), fy);
                Box::new(PointLoad::new(b?, s?, *frame == ForceFrame::Body, fx?, fy?))
            }
            ForceSpec::Torque(TorqueSpec { body, torque }) => {
                let b = self.moving(&format!("{path}.body"), body);
                let t = self.load(&format!("{path}.torque"), torque);
                Box::new(Torque::new(b?, t?))
            }
            ForceSpec::SpringDamper(SpringDamperSpec {
                body_i,
                point_i,
                body_j,
                point_j,
                stiffness,
                damping,
                free_length,
                actuator,
            }) => {
                let ends = self.ends(path, body_i, point_i, body_j, point_j);
                let k = self.non_negative(&format!("{path}.stiffness"), *stiffness);
                let c = self.non_negative(&format!("{path}.damping"), *damping);
                let act = self.load(&format!("{path}.actuator"), actuator);
                let (ends, k, c, act) = (ends?, k?, c?, act?);
                let [(i, sp), (j, sq)] = ends;
                let l0 = match free_length {
                    Some(l) => self.non_negative(&format!("{path}.free_length"), *l)?,
                    None => self.initial_distance(ends),
                };
                Box::new(SpringDamper::new(i.0, sp, j.0, sq, k, c, l0, act))
            }
            ForceSpec::RotationalSpringDamper(RotationalSpringDamperSpec {
                body_i,
                body_j,
                stiffness,
                damping,
                free_angle,
                actuator,
            }) => {
                let origin = PointRef::default();
                let ends = self.ends(path, body_i, &origin, body_j, &origin);
                let k = self.non_negative(&format!("{path}.stiffness"), *stiffness);
                let c = self.non_negative(&format!("{path}.damping"), *damping);
                let act = self.load(&format!("{path}.actuator"), actuator);
                let ([(i, _), (j, _)], k, c, act) = (ends?, k?, c?, act?);
                let theta0 = match free_angle {
                    Some(a) => self.finite(&format!("{path}.free_angle"), *a)?,
                    None => i.coords(&self.q0)[2] - j.coords(&self.q0)[2],
                };
                Box::new(RotationalSpringDamper::new(i.0, j.0, k, c, theta0, act))
            }
            ForceSpec::Contact(spec) => self.contact(path, spec)?,
        })
    }

    /// A contact: its bodies, shapes (one a circle), normal law, friction and event depth.
    pub(super) fn contact(&mut self, path: &str, spec: &ContactSpec) -> Option<Box<dyn Force>> {
        let bi = self.body(&format!("{path}.body_i"), &spec.body_i);
        let bj = self.body(&format!("{path}.body_j"), &spec.body_j);
        if spec.body_i == spec.body_j {
            let message = format!("a contact needs two different bodies, found '{}' twice", spec.body_i);
            self.problem(format!("{path}.body_j"), message);
        }
        let si = self.shape(&format!("{path}.shape_i"), &spec.shape_i);
        let sj = self.shape(&format!("{path}.shape_j"), &spec.shape_j);
        let k = self.positive(&format!("{path}.stiffness"), spec.stiffness);
        let e = match spec.exponent {
            Some(e) => self.finite(&format!("{path}.exponent"), e).and_then(|e| {
                if e < 1.0 {
                    self.problem(format!("{path}.exponent"), format!("expected a number >= 1 (the force's derivative is infinite at first touch below 1), found {e}"));
                    return None;
                }
                Some(e)
            }),
            None => Some(DEFAULT_CONTACT_EXPONENT),
        };
        let c = self.non_negative(&format!("{path}.damping"), spec.damping);
        let friction = match &spec.friction {
            Some(ContactFriction { mu, transition_velocity }) => {
                let mu = self.non_negative(&format!("{path}.friction.mu"), *mu);
                let v_s = match transition_velocity {
                    Some(v) => self.positive(&format!("{path}.friction.transition_velocity"), *v),
                    None => Some(DEFAULT_TRANSITION_VELOCITY),
                };
                mu.zip(v_s)
            }
            None => Some((0.0, DEFAULT_TRANSITION_VELOCITY)),
        };
        let depth = spec.max_penetration.map(|d| self.positive(&format!("{path}.max_penetration"), d));
        let (bi, bj, si, sj, k, e, c, friction) = (bi?, bj?, si?, sj?, k?, e?, c?, friction?);
        if bi == BodyIx::GROUND && bj == BodyIx::GROUND {
            self.problem(format!("{path}.body_j"), "both shapes are on ground: name a moving body");
            return None;
        }
        let ((a, (centre, radius)), (b, other)) = match (si, sj) {
            (ContactShape::Circle(centre, radius), other) => ((bi, (centre, radius)), (bj, other)),
            (other, ContactShape::Circle(centre, radius)) => ((bj, (centre, radius)), (bi, other)),
            _ => {
                self.problem(
                    format!("{path}.shape_j"),
                    "a contact between two segments or polylines is not supported; expected a circle on one of the bodies",
                );
                return None;
            }
        };
        let smallest = match other {
            ContactShape::Circle(_, r) => radius.min(r),
            ContactShape::Polyline(_) => radius,
        };
        let depth = match depth {
            Some(d) => d?,
            None => DEFAULT_PENETRATION_FRACTION * smallest,
        };
        Some(Box::new(Contact::new(a.0, centre, radius, b.0, other, (k, e, c), friction, depth)))
    }

    /// A contact shape, in its body's frame.
    pub(super) fn shape(&mut self, path: &str, spec: &ShapeSpec) -> Option<ContactShape> {
        match (&spec.circle, &spec.segment, &spec.polyline) {
            (Some(CircleShape { centre, radius }), None, None) => {
                let c = self.vec2(&format!("{path}.circle.centre"), *centre);
                let r = self.positive(&format!("{path}.circle.radius"), *radius);
                Some(ContactShape::Circle(c?, r?))
            }
            (None, Some(points), None) => self.polyline(&format!("{path}.segment"), points),
            (None, None, Some(points)) => self.polyline(&format!("{path}.polyline"), points),
            _ => {
                self.problem(path, "expected exactly one of circle, segment, polyline");
                None
            }
        }
    }

    /// A chain of two or more points, each segment of positive length.
    pub(super) fn polyline(&mut self, path: &str, points: &[[f64; 2]]) -> Option<ContactShape> {
        if points.len() < 2 {
            self.problem(path, format!("expected two or more points, found {}", points.len()));
            return None;
        }
        let mut ok = true;
        for (k, p) in points.iter().enumerate() {
            ok &= self.vec2(&format!("{path}[{k}]"), *p).is_some();
        }
        if !ok {
            return None;
        }
        for (k, w) in points.windows(2).enumerate() {
            if (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) < 1e-12 {
                self.problem(
                    format!("{path}[{}]", k + 1),
                    format!("the point repeats point {k}: a segment needs two distinct ends"),
                );
                ok = false;
            }
        }
        ok.then(|| ContactShape::Polyline(points.to_vec()))
    }
}
