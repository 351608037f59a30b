//! Measures and summaries: named output quantities (expressions, point components, the
//! standard quantities of mechanism design) and whole-run functionals of the columns.

use super::*;

/// The name of the column that says how a run or a sweep's variant ended (summary.json's
/// `status`, the sweep table's column): no measure may take it.
const STATUS: &str = "status";

impl Cx<'_> {
    /// A measure is read by name (its column of `results.csv`, by summaries, sweep outputs and
    /// Python), and expressions read the parameters by name: a measure named as a built-in column
    /// (`time`, `kinetic_energy` ...), as `status` (of a run and of a sweep's variant) or as a
    /// parameter is a problem at it naming the other (a measure `kinetic_energy` gave
    /// `results.csv` two columns of that name, and Python and the summaries read different ones).
    /// Summaries have names of their own (keys of `summary.json`'s `summaries`, read by nothing
    /// else), which collide with none of these.
    pub(super) fn distinct_measures(&mut self) {
        let spec = self.spec;
        let built_in = std::iter::once(TIME).chain(ENERGY_COLUMNS).chain(INVERSE_COLUMNS);
        for name in spec.measures.keys() {
            let other = if built_in.clone().any(|c| c == name) {
                format!("the built-in column {name} of results.csv")
            } else if name == STATUS {
                "the status of a run (summary.json) and of a sweep's variant (a column of its table)".to_string()
            } else if spec.parameters.contains_key(name) {
                format!("the parameter parameters.{name}, which expressions read by that name")
            } else {
                continue;
            };
            self.problem(format!("measures.{name}"), format!("'{name}' is already {other}; choose another name"));
        }
    }

    /// A summary: a functional of the result columns, with the model's parameters and tables.
    pub(super) fn summary(&mut self, path: &str, source: &str) -> Option<Functional> {
        let names = ModelNames { parameters: &self.spec.parameters, tables: &self.tables };
        Functional::parse(source, &names).map_err(|message| self.problem(path, message)).ok()
    }

    /// A measure; `joints`: the joints compiled, whose pins a transmission angle takes.
    pub(super) fn measure(&mut self, path: &str, m: &MeasureSpec, joints: &[Element]) -> Option<MeasureKind> {
        match m {
            MeasureSpec::Expression(src) => self.state_expr(path, src, true).map(MeasureKind::Expression),
            MeasureSpec::Point(PointMeasure { body, point, component }) => {
                let b = self.moving(&format!("{path}.body"), body);
                let s = self.point(&format!("{path}.point"), body, point);
                Some(MeasureKind::Point { body: b?, s: s?, component: *component })
            }
            MeasureSpec::Standard(StandardMeasure::TransmissionAngle(TransmissionAngleMeasure {
                joint,
                coupler_joint,
                rocker_joint,
            })) => {
                let b = self.pin(&format!("{path}.joint"), joint, joints);
                let c = self.pin(&format!("{path}.coupler_joint"), coupler_joint, joints);
                let r = self.pin(&format!("{path}.rocker_joint"), rocker_joint, joints);
                let (b, c, r) = (b?, c?, r?);
                let coupler = self.link(&format!("{path}.coupler_joint"), "coupler", (joint, &b), (coupler_joint, &c));
                let rocker = self.link(&format!("{path}.rocker_joint"), "rocker", (joint, &b), (rocker_joint, &r));
                let (coupler, rocker) = (coupler?, rocker?);
                if coupler.0 == rocker.0 {
                    let body = self.body_name(coupler.0);
                    self.problem(
                        format!("{path}.rocker_joint"),
                        format!("'{rocker_joint}' is a pin of '{body}', the coupler (the body '{joint}' shares with '{coupler_joint}'); expected a pin of the other body of '{joint}'"),
                    );
                    return None;
                }
                self.hand_line((path, "coupler"), (joint, &b), (coupler_joint, &c), coupler);
                self.hand_line((path, "rocker"), (joint, &b), (rocker_joint, &r), rocker);
                Some(MeasureKind::TransmissionAngle { coupler, rocker })
            }
            MeasureSpec::Standard(StandardMeasure::VelocityRatio(VelocityRatioMeasure { input, output })) => {
                let i = self.moving(&format!("{path}.input"), input);
                let o = self.moving(&format!("{path}.output"), output);
                Some(MeasureKind::VelocityRatio { input: i? + 2, output: o? + 2 })
            }
            MeasureSpec::Standard(StandardMeasure::MechanicalAdvantage(MechanicalAdvantageMeasure {
                input,
                output,
            })) => {
                let i = self.effort(&format!("{path}.input"), input);
                let o = self.effort(&format!("{path}.output"), output);
                Some(MeasureKind::MechanicalAdvantage { input: i?, output: o? })
            }
            MeasureSpec::Standard(StandardMeasure::PressureAngle(PressureAngleMeasure { joint })) => {
                let (measure, path) = (path, format!("{path}.joint"));
                let cam = match self.spec.joints.get(joint) {
                    // A cam joint that did not compile has its own problem.
                    Some(JointSpec::Cam(cam)) if joints.iter().any(|j| j.name == *joint) => cam,
                    Some(JointSpec::Cam(_)) => return None,
                    Some(other) => {
                        self.problem(path, format!("'{joint}' is a {} joint; expected a cam joint", other.name()));
                        return None;
                    }
                    None => {
                        if !self.broken.iter().any(|b| b.strip_prefix("joints.") == Some(joint)) {
                            let known: Vec<&str> = self.spec.joints.keys().map(String::as_str).collect();
                            self.problem(
                                path,
                                format!("unknown joint '{joint}'; expected one of: {}", known.join(", ")),
                            );
                        }
                        return None;
                    }
                };
                let row = cam_row(cam, self, &format!("joints.{joint}"))?;
                // The measure's numbers are the joint's, and so are their derivatives: each as
                // handed to the joint, or zero for a number the file does not write (a default
                // centre; the joint's own data are checked to be handed when it writes them).
                if self.spec.gradients.count() > 0 {
                    for (field, v) in row.data() {
                        let handed = self.handed.get(&format!("joints.{joint}.{field}")).cloned();
                        let given = handed.unwrap_or_else(|| (v, vec![0.0; self.spec.gradients.count()]));
                        self.handed.insert(format!("{measure}.{field}"), given);
                    }
                }
                Some(MeasureKind::PressureAngle(row))
            }
        }
    }

    /// The name of body `b` (`ground` for ground).
    pub(super) fn body_name(&self, b: BodyIx) -> &str {
        b.0.map_or("ground", |k| self.spec.bodies.get_index(k / 3).map_or("ground", |(n, _)| n.as_str()))
    }

    /// The revolute joint `name` at `path` as its [`Sketch`] (its two bodies and their points);
    /// `None` with a problem when there is no such joint or it is not a pin (nothing more when
    /// the joint's own entry has a problem, reported there).
    pub(super) fn pin(&mut self, path: &str, name: &str, joints: &[Element]) -> Option<Sketch> {
        let Some(spec) = self.spec.joints.get(name) else {
            if !self.broken.iter().any(|b| b.strip_prefix("joints.") == Some(name)) {
                let known: Vec<&str> = self.spec.joints.keys().map(String::as_str).collect();
                self.problem(path, format!("unknown joint '{name}'; expected one of: {}", known.join(", ")));
            }
            return None;
        };
        let sketch = joints.iter().find(|j| j.name == name)?.constraint.sketch();
        match sketch {
            Some(s @ Sketch { shape: Shape::Pin, .. }) => Some(s),
            _ => {
                self.problem(path, format!("'{name}' is a {} joint; expected a revolute joint (a pin)", spec.name()));
                None
            }
        }
    }

    /// One of the two links whose lines make a transmission angle (`role`: coupler or rocker):
    /// the body the pin `common` shares with the pin `other` (named at `path`), and the line from
    /// `common` to `other` in its frame.
    pub(super) fn link(
        &mut self,
        path: &str,
        role: &str,
        (common, b): (&str, &Sketch),
        (other, o): (&str, &Sketch),
    ) -> Option<(BodyIx, [f64; 2])> {
        let ends = |s: &Sketch| [(s.i, s.p), (s.j, s.q)];
        let shared: Vec<(BodyIx, [f64; 2], [f64; 2])> = ends(b)
            .into_iter()
            .flat_map(|(bb, sb)| ends(o).into_iter().filter(move |(ob, _)| *ob == bb).map(move |(_, so)| (bb, sb, so)))
            .collect();
        let bodies = |s: &Sketch| format!("'{}' and '{}'", self.body_name(s.i), self.body_name(s.j));
        let [(body, from, to)] = shared[..] else {
            let why = if shared.is_empty() { "shares no body with" } else { "joins the same two bodies as" };
            let message = format!(
                "'{other}' (between {}) {why} '{common}' (between {}); expected the {role}'s other pin, on one of the bodies of '{common}'",
                bodies(o),
                bodies(b)
            );
            self.problem(path, message);
            return None;
        };
        let line = [to[0] - from[0], to[1] - from[1]];
        // Pins closer than 1e-12 m (the round-off of coordinates of a few metres) give the line
        // no direction.
        if line[0].hypot(line[1]) < 1e-12 {
            let body = self.body_name(body).to_string();
            self.problem(path, format!("'{other}' and '{common}' are at the same point of '{body}': the {role}'s line is undefined; expected its pin at the other end of the {role}"));
            return None;
        }
        Some((body, line))
    }

    /// The input or output of a mechanical advantage at `path`: a driver (its effort) or a
    /// `torque` force (its torque).
    pub(super) fn effort(&mut self, path: &str, name: &str) -> Option<Effort> {
        let spec = self.spec;
        if let Some(d) = spec.drivers.get_index_of(name) {
            return Some(Effort::Driver { slot: 3 * spec.joints.len() + d });
        }
        match spec.forces.get_full(name) {
            Some((k, _, ForceSpec::Torque(TorqueSpec { torque, .. }))) => {
                // The torque is compiled again over global coordinates; its problems are the
                // force's, reported at its own entry.
                let before = self.problems.len();
                let torque = self.load(&format!("forces.{name}.torque"), torque);
                self.problems.truncate(before);
                Some(Effort::Torque { force: k, torque: torque? })
            }
            Some((_, _, other)) => {
                self.problem(path, format!("'{name}' is a {} force; expected a driver or a torque force (for another load, write an expression of the result columns)", other.name()));
                None
            }
            None if self.broken.iter().any(|b| [format!("drivers.{name}"), format!("forces.{name}")].contains(b)) => {
                None
            }
            None => {
                let torques =
                    spec.forces.iter().filter(|(_, f)| matches!(f, ForceSpec::Torque(..))).map(|(n, _)| n.as_str());
                let known: Vec<&str> = spec.drivers.keys().map(String::as_str).chain(torques).collect();
                self.problem(path, format!("unknown driver or torque '{name}'; expected one of: {}", known.join(", ")));
                None
            }
        }
    }
}
