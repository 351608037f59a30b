//! The derivatives of the compiled model's numbers with respect to its parameters
//! ([`DataGradients`]): each body's mass, inertia and named points, gravity, and the data of each
//! joint, driver and measure, found under the path of the field each number was handed to the
//! element from while it compiled ([`Context::hand`], [`Context::place`]). A file without
//! parameters computes none of them.

use super::super::placement::{local_gradient, unrotate_gradient};
use super::super::DataGradients;
use super::*;

impl Cx<'_> {
    /// How many parameters the derivatives are taken with respect to (0: none are computed).
    fn count(&self) -> usize {
        self.spec.gradients.count()
    }

    /// The derivatives of a pair that could not be found: not a number, never zero.
    fn unknown(&self) -> Grad2 {
        [0, 1].map(|_| vec![f64::NAN; self.count()])
    }

    /// Keep the pair `v` with its derivatives `g` under `path[0]` and `path[1]`.
    fn hand_pair(&mut self, path: &str, v: [f64; 2], g: Grad2) {
        for (k, (v, d)) in v.into_iter().zip(g).enumerate() {
            self.handed.insert(format!("{path}[{k}]"), (v, d));
        }
    }

    /// Keep the point `v`, point `name` of `body` (its frame), with its derivatives as the pair
    /// at `path`, where an element names it.
    pub(super) fn hand_point(&mut self, path: &str, (body, name): (&str, &str), v: [f64; 2]) {
        if self.count() > 0 {
            let g = self.point_gradients.get(body).and_then(|ps| ps.get(name)).cloned();
            let g = g.unwrap_or_else(|| self.unknown());
            self.hand_pair(path, v, g);
        }
    }

    /// Keep the pair `v` placed at `path` in a body frame `from` a global point or direction,
    /// with its derivatives through the body's initial pose.
    pub(super) fn differentiate_placed(&mut self, path: &str, v: [f64; 2], from: Placed<'_>) {
        let count = self.count();
        if count == 0 {
            return;
        }
        let (Placed::Point { body, global, field } | Placed::Direction { body, global, field }) = from;
        let written = [0, 1].map(|k| self.spec.gradients.field(&format!("{field}[{k}]")));
        let pose = if body == "ground" {
            Some([0, 1, 2].map(|_| vec![0.0; count]))
        } else {
            self.pose_gradients.get(body).cloned()
        };
        let g = match (self.initial_frame(body), pose, from) {
            (Some(f), Some(df), Placed::Point { .. }) => local_gradient(&f, &df, global, &written),
            (Some(f), Some(df), Placed::Direction { .. }) => unrotate_gradient(&f, &df[2], global, &written),
            // An unknown body is reported where the element names it.
            _ => self.unknown(),
        };
        self.hand_pair(path, v, g);
    }

    /// Keep a transmission angle's line `v` with its derivatives (`<path>.<role>`, the point of the
    /// pin `other` minus that of the pin `common`, both on `body`), from those its pins' joints
    /// were handed.
    pub(super) fn hand_line(
        &mut self,
        (path, role): (&str, &str),
        (common, b): (&str, &Sketch),
        (other, o): (&str, &Sketch),
        (body, v): (BodyIx, [f64; 2]),
    ) {
        if self.count() == 0 {
            return;
        }
        let end = |joint: &str, s: &Sketch| {
            let field = if s.i == body { "point_i" } else { "point_j" };
            [0, 1].map(|k| self.handed.get(&format!("joints.{joint}.{field}[{k}]")).map(|(_, d)| d.clone()))
        };
        let g = match (end(common, b), end(other, o)) {
            ([Some(fx), Some(fy)], [Some(tx), Some(ty)]) => {
                let minus = |t: Vec<f64>, f: Vec<f64>| t.iter().zip(&f).map(|(t, f)| t - f).collect();
                [minus(tx, fx), minus(ty, fy)]
            }
            _ => self.unknown(),
        };
        self.hand_pair(&format!("{path}.{role}"), v, g);
    }

    /// The derivatives of the model's numbers with respect to its parameters, once every
    /// element has compiled; empty for a file without parameters.
    pub(super) fn gradients(
        &mut self,
        bodies: &[Body],
        joints: &[Element],
        drivers: &[Element],
        forces: &[ForceElement],
        measures: &[Measure],
    ) -> DataGradients {
        if self.count() == 0 {
            return DataGradients::default();
        }
        let spec = self.spec;
        let g = &spec.gradients;
        let friction = joints
            .iter()
            .map(|e| {
                let data = e.friction.as_ref().map(crate::constraints::Friction::data).unwrap_or_default();
                self.data(&format!("joints.{}", e.name), &data, spec.joints.get(&e.name))
            })
            .collect();
        let joints = joints
            .iter()
            .map(|e| self.data(&format!("joints.{}", e.name), &e.constraint.data(), spec.joints.get(&e.name)))
            .collect();
        let drivers = drivers
            .iter()
            .map(|e| self.data(&format!("drivers.{}", e.name), &e.constraint.data(), spec.drivers.get(&e.name)))
            .collect();
        let forces = forces
            .iter()
            .map(|f| self.data(&format!("forces.{}", f.name), &f.force.data(), spec.forces.get(&f.name)))
            .collect();
        // Every number of a measure is written or read from a joint's, none taken from the
        // initial configuration.
        let measures =
            measures.iter().map(|m| self.data(&format!("measures.{}", m.name), &m.kind.data(), None::<&()>)).collect();
        let points = bodies
            .iter()
            .map(|b| {
                let of = self.point_gradients.get(&b.name);
                b.points
                    .keys()
                    .map(|p| of.and_then(|ps| ps.get(p)).cloned().unwrap_or_else(|| self.unknown()))
                    .collect()
            })
            .collect();
        DataGradients {
            params: g.params.clone(),
            joints,
            drivers,
            friction,
            bodies: bodies
                .iter()
                .map(|b| ["mass", "inertia"].map(|f| g.field(&format!("bodies.{}.{f}", b.name))))
                .collect(),
            points,
            measures,
            gravity: [0, 1].map(|k| g.field(&format!("gravity[{k}]"))),
            forces,
        }
    }

    /// The derivatives of each of an entry's `data` (the entry at `path`, `entry` its spec): each
    /// as handed to it under `<path>.<field>`. A number not handed that the entry does not
    /// write was taken from the initial configuration, which is held: zero. Any other is a bug
    /// of the engine: an error (a panic in a debug build), never a silent zero.
    fn data<T: serde::Serialize>(
        &mut self,
        path: &str,
        data: &[(&'static str, f64)],
        entry: Option<&T>,
    ) -> Vec<Vec<f64>> {
        data.iter()
            .map(|(field, _)| {
                let at = format!("{path}.{field}");
                if let Some((_, d)) = self.handed.get(&at) {
                    return d.clone();
                }
                let name = field.split('[').next().unwrap_or(field);
                if entry.is_some_and(|e| !writes(e, name)) {
                    return vec![0.0; self.count()];
                }
                let message = "internal error: the derivatives of this number with respect to the parameters \
                               were not kept when the entry compiled; please report it";
                if cfg!(debug_assertions) {
                    panic!("{at}: {message}");
                }
                self.problem(at, message);
                vec![f64::NAN; self.count()]
            })
            .collect()
    }
}

/// Whether a section's entry (serialized as its fields, its `type` among them) writes `field`,
/// or the nested field at the path `field` (`friction.mu`, `shape_j.circle.radius`).
fn writes<T: serde::Serialize>(entry: &T, field: &str) -> bool {
    let value = serde_json::to_value(entry).unwrap_or_default();
    let at = field.split('.').try_fold(&value, |v, part| v.get(part));
    at.is_some_and(|v| !v.is_null())
}

#[cfg(test)]
mod tests {
    use super::super::super::parse::parse_partial_with;
    use super::*;
    use std::path::PathBuf;

    /// The examples folder.
    fn examples() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
    }

    /// Every example that has parameters: its name and text.
    fn with_parameters() -> Vec<(String, String)> {
        let mut out: Vec<(String, String)> = std::fs::read_dir(examples())
            .expect("the examples folder")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
            .filter_map(|p| {
                let text = std::fs::read_to_string(&p).ok()?;
                let name = p.file_name()?.to_string_lossy().into_owned();
                text.lines().any(|l| l.starts_with("parameters:")).then_some((name, text))
            })
            .collect();
        out.sort();
        out
    }

    /// The model of `text` with the values `set`, and every number handed to its elements.
    fn build(name: &str, text: &str, set: &[(String, String)]) -> (Model, Handed) {
        let parsed = parse_partial_with(text, set).unwrap_or_else(|p| panic!("{name}: {p:?}"));
        assert!(parsed.problems.is_empty(), "{name}: {:?}", parsed.problems);
        let (model, handed) = compiled(&parsed.spec, &parsed.broken, &examples());
        (model.unwrap_or_else(|p| panic!("{name}: {p:?}")), handed)
    }

    /// Every number of the model that has derivatives, by a name for the messages, in a fixed
    /// order: the parameters, each body's mass, inertia and points, gravity, each joint's,
    /// driver's and measure's data, and every number handed to an element.
    fn numbers(model: &Model, handed: &Handed) -> Vec<(String, f64, Vec<f64>)> {
        let g = &model.gradients;
        let mut out = Vec::new();
        for ((name, v), d) in model.parameters.iter().zip(&g.params) {
            out.push((format!("parameters.{name}"), *v, d.clone()));
        }
        for (k, b) in model.bodies.iter().enumerate() {
            let [dm, di] = &g.bodies[k];
            out.push((format!("bodies.{}.mass", b.name), b.mass, dm.clone()));
            out.push((format!("bodies.{}.inertia", b.name), b.inertia, di.clone()));
            for ((p, s), ds) in b.points.iter().zip(&g.points[k]) {
                for c in 0..2 {
                    out.push((format!("bodies.{}.points.{p}[{c}]", b.name), s[c], ds[c].clone()));
                }
            }
        }
        for c in 0..2 {
            out.push((format!("gravity[{c}]"), model.gravity[c], g.gravity[c].clone()));
        }
        let elements = [("joints", &model.joints, &g.joints), ("drivers", &model.drivers, &g.drivers)];
        for (section, elements, gradients) in elements {
            for (e, d) in elements.iter().zip(gradients) {
                for ((field, v), d) in e.constraint.data().iter().zip(d) {
                    out.push((format!("{section}.{}.{field}", e.name), *v, d.clone()));
                }
            }
        }
        for (e, d) in model.joints.iter().zip(&g.friction) {
            let data = e.friction.as_ref().map(crate::constraints::Friction::data).unwrap_or_default();
            for ((field, v), d) in data.iter().zip(d) {
                out.push((format!("joints.{}.{field} (its friction's)", e.name), *v, d.clone()));
            }
        }
        for (f, d) in model.forces.iter().zip(&g.forces) {
            for ((field, v), d) in f.force.data().iter().zip(d) {
                out.push((format!("forces.{}.{field}", f.name), *v, d.clone()));
            }
        }
        for (m, d) in model.measures.iter().zip(&g.measures) {
            for ((field, v), d) in m.kind.data().iter().zip(d) {
                out.push((format!("measures.{}.{field}", m.name), *v, d.clone()));
            }
        }
        let mut paths: Vec<&String> = handed.keys().collect();
        paths.sort();
        out.extend(paths.into_iter().map(|p| (format!("handed {p}"), handed[p].0, handed[p].1.clone())));
        out
    }

    /// Each derivative against central differences of compiling the model with the parameter a
    /// little up and down (`--set`), for every example with parameters. Step: 1e-6 of the
    /// parameter (1e-6 for a parameter at zero); its truncation error is `h^2 |f'''| / 6`,
    /// about 1e-13 of the derivative for the geometry here, and its round-off `eps |f| / h`.
    /// Tolerance: 1e-8 of the derivative's own scale, the larger of `|df/dp|` and `|f| / |p|`
    /// (the round-off is 2e-10 of the latter), or 1e-12 absolute; a zero derivative is zero in
    /// both (the number does not depend on the parameter: its two compiles agree bit for bit).
    #[test]
    fn every_examples_derivatives_are_central_differences_of_its_compiles() {
        let examples = with_parameters();
        assert!(examples.len() >= 8, "{:?}", examples.iter().map(|e| &e.0).collect::<Vec<_>>());
        // The derivatives checked that are not zero, each example's, so that the check is
        // not one of zeros against zeros.
        let mut moving = Vec::new();
        for (name, text) in &examples {
            for (param, handed) in against_compiles(name, text) {
                moving.push((name, param, handed.iter().filter(|w| w.starts_with("handed ")).count()));
            }
        }
        let at_least = |example: &str, count: usize| {
            let found: usize = moving.iter().filter(|(n, ..)| *n == example).map(|(.., c)| c).sum();
            assert!(found >= count, "{example}: {found} numbers handed to elements move with a parameter");
        };
        // quick_return_a: 6 points named by its joints move; fourbar_placed: its joints' `at`
        // and the points placed from it; sixbar_leg: points placed by lengths.
        at_least("quick_return_a.yaml", 6);
        at_least("fourbar_placed.yaml", 8);
        at_least("sixbar_leg.yaml", 8);
    }

    /// The check of [`every_examples_derivatives_are_central_differences_of_its_compiles`] on
    /// the model `text` (named `name` in messages): for each parameter, the names of the numbers
    /// whose derivative with respect to it is not zero.
    fn against_compiles(name: &str, text: &str) -> Vec<(String, Vec<String>)> {
        let (model, handed) = build(name, text, &[]);
        let base = numbers(&model, &handed);
        let mut moving = Vec::new();
        for (k, (param, &p)) in model.parameters.iter().enumerate() {
            let h = 1e-6 * if p == 0.0 { 1.0 } else { p.abs() };
            let at = |v: f64| {
                let (model, handed) = build(name, text, &[(param.clone(), format!("{v}"))]);
                numbers(&model, &handed)
            };
            let (up, down) = (at(p + h), at(p - h));
            assert_eq!(up.len(), base.len(), "{name}: {param}");
            for ((what, v, d), ((_, a, _), (_, b, _))) in base.iter().zip(up.iter().zip(&down)) {
                let fd = (a - b) / ((p + h) - (p - h));
                let scale = d[k].abs().max(v.abs() / p.abs().max(1e-300)).max(fd.abs());
                let err = (fd - d[k]).abs();
                assert!(
                    err <= 1e-8 * scale || err <= 1e-12,
                    "{name}: d {what} / d {param}: {} against central differences {fd} (error {err:e}, scale {scale:e})",
                    d[k]
                );
            }
            let nonzero = base.iter().filter(|(_, _, d)| d[k] != 0.0).map(|(what, ..)| what.clone()).collect();
            moving.push((param.clone(), nonzero));
        }
        moving
    }

    /// Every force's numbers written with parameters (`tests/models/forces_param.yaml`): their
    /// derivatives against central differences of compiling the model again, as the examples';
    /// the ones that must move do (a spring's points, stiffness and damping, a rotational
    /// spring's, a number of a force, a contact's law and friction), and those a parameter does
    /// not write (a contact's shapes and exponent, numbers written as such) are zero.
    #[test]
    fn every_forces_numbers_are_central_differences_of_its_compiles() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/models/forces_param.yaml");
        let text = std::fs::read_to_string(path).expect("the model");
        let moving: Vec<String> =
            against_compiles("forces_param", &text).into_iter().flat_map(|(_, names)| names).collect();
        let must = [
            "forces.spring.point_i[1]",
            "forces.spring.point_j[0]",
            "forces.spring.stiffness",
            "forces.spring.damping",
            "forces.coil.stiffness",
            "forces.coil.free_angle",
            "forces.push.point[0]",
            "forces.floor.stiffness",
            "forces.floor.damping",
            "forces.floor.friction.mu",
        ];
        for name in must {
            assert!(moving.iter().any(|m| m == name), "{name} has no derivative");
        }
        let (model, _) = build("forces_param", &text, &[]);
        let data: Vec<String> = model
            .forces
            .iter()
            .flat_map(|f| f.force.data().into_iter().map(move |(d, _)| format!("forces.{}.{d}", f.name)))
            .collect();
        for name in [
            "forces.floor.exponent",
            "forces.floor.shape_j.circle.radius",
            "forces.floor.shape_i.segment[1][0]",
            "forces.push.fy",
            "forces.coil.damping",
        ] {
            assert!(data.iter().any(|d| d == name), "{name} is a datum");
            assert!(!moving.iter().any(|m| m == name), "{name} moves");
        }
    }

    /// The recording itself, by hand: quick_return_a's joint A holds the rocker to ground at
    /// `point_j: [0, -pivots]`, so its derivatives are `(0, -1)` with respect to `pivots` and
    /// zero with respect to the others; B_slot's `point_j: A` is the rocker's point
    /// `[rocker/2, 0]`, `(1/2, 0)` with respect to `rocker`.
    #[test]
    fn a_joints_point_has_the_derivatives_of_its_expression() {
        let text = std::fs::read_to_string(examples().join("quick_return_a.yaml")).expect("the example");
        let (model, handed) = build("quick_return_a", &text, &[]);
        let names: Vec<&str> = model.parameters.keys().map(String::as_str).collect();
        let unit =
            |name: &str, by: f64| -> Vec<f64> { names.iter().map(|n| if *n == name { by } else { 0.0 }).collect() };
        let zero = vec![0.0; names.len()];
        assert_eq!(handed["joints.A.point_j[0]"], (0.0, zero.clone()));
        assert_eq!(handed["joints.A.point_j[1]"], (-2.0, unit("pivots", -1.0)));
        assert_eq!(handed["joints.B_slot.point_j[0]"], (2.0, unit("rocker", 0.5)));
        assert_eq!(handed["joints.B_slot.point_j[1]"], (0.0, zero));
    }

    /// A field is written when the entry gives it: a distance joint's length, left out, is
    /// taken from the initial configuration (held); its points are written; a contact's
    /// `friction.mu` is written, its `friction.transition_velocity` left to its default.
    #[test]
    fn an_entry_writes_the_fields_it_gives() {
        let joint = |text: &str| -> JointSpec { serde_yaml_ng::from_str(text).expect("a joint") };
        let bare = joint("{type: distance, body_i: a, point_i: [0, 0], body_j: b, point_j: [1, 0]}");
        let long = joint("{type: distance, body_i: a, point_i: [0, 0], body_j: b, point_j: [1, 0], length: 2}");
        assert!(!writes(&bare, "length") && writes(&long, "length"));
        assert!(writes(&bare, "point_i") && writes(&bare, "body_j") && !writes(&bare, "radius"));
        // A nested field: a contact's friction and shapes.
        let contact: crate::forces::ForceSpec = serde_yaml_ng::from_str(
            "{type: contact, body_i: a, shape_i: {circle: {radius: 1}}, body_j: b, \
             shape_j: {segment: [[0, 0], [1, 0]]}, stiffness: 1, friction: {mu: 0.3}}",
        )
        .expect("a contact");
        assert!(writes(&contact, "friction.mu") && !writes(&contact, "friction.transition_velocity"));
        assert!(writes(&contact, "shape_j.segment") && !writes(&contact, "shape_j.circle"));
        assert!(writes(&contact, "shape_i.circle.radius") && !writes(&contact, "exponent"));
    }

    /// A file without parameters computes no derivatives at all.
    #[test]
    fn a_model_without_parameters_has_no_derivatives() {
        let text = std::fs::read_to_string(examples().join("fourbar.yaml")).expect("the example");
        let (model, handed) = build("fourbar", &text, &[]);
        assert!(model.parameters.is_empty() && handed.is_empty());
        assert_eq!(model.gradients, DataGradients::default());
    }

    /// Every example compiles with its derivatives, and each joint's, driver's and force's data
    /// has one (a name its element lists that the compiler did not keep fails the compile).
    #[test]
    fn every_elements_data_has_derivatives() {
        for (name, text) in with_parameters() {
            let (model, _) = build(&name, &text, &[]);
            let g = &model.gradients;
            let mut counts = Vec::new();
            for (elements, gradients) in [(&model.joints, &g.joints), (&model.drivers, &g.drivers)] {
                assert_eq!(elements.len(), gradients.len(), "{name}");
                counts.extend(elements.iter().map(|e| (e.name.as_str(), e.constraint.data().len())).zip(gradients));
            }
            assert_eq!(model.forces.len(), g.forces.len(), "{name}");
            counts.extend(model.forces.iter().map(|f| (f.name.as_str(), f.force.data().len())).zip(&g.forces));
            for ((element, count), d) in counts {
                assert_eq!(count, d.len(), "{name}: {element}");
                assert!(d.iter().all(|d| d.len() == model.parameters.len()), "{name}: {element}");
            }
        }
    }
}
