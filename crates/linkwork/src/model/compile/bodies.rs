//! Bodies and their points: each body's mass, inertia, initial pose and named points, the
//! names every section must keep distinct, the points whose paths are drawn, and the declared
//! branches of the dyads.

use super::*;

impl Cx<'_> {
    /// Every body of the file with its named points placed, in file order.
    pub(super) fn bodies(&mut self) -> Vec<Body> {
        if self.body_names().is_empty() {
            self.problem("bodies", "at least one moving body is required");
        }
        let spec = self.spec;
        let Drawn { poses, points, placed, gradients, pose_gradients } = drawn(spec, self.broken, &mut self.problems);
        self.placed.extend(placed);
        (self.point_gradients, self.pose_gradients) = (gradients, pose_gradients);
        let bodies = spec
            .bodies
            .iter()
            .enumerate()
            .map(|(k, (name, b))| {
                let path = format!("bodies.{name}");
                if name == "ground" {
                    self.problem(&path, "'ground' is the fixed body and cannot be listed among the moving bodies");
                }
                self.name(&path, name);
                if let Some(m) = self.finite(&format!("{path}.mass"), b.mass) {
                    if m < 0.0 {
                        self.problem(format!("{path}.mass"), format!("expected a mass >= 0 kg, found {m}"));
                    }
                }
                if let Some(j) = self.finite(&format!("{path}.inertia"), b.inertia) {
                    if j < 0.0 {
                        self.problem(
                            format!("{path}.inertia"),
                            format!("expected a moment of inertia >= 0 kg m^2, found {j}"),
                        );
                    }
                }
                let q0 = poses.get(name).copied().unwrap_or_default();
                let vel = self.vec2(&format!("{path}.velocity"), b.velocity).unwrap_or([0.0; 2]);
                let omega = self.finite(&format!("{path}.omega"), b.omega).unwrap_or(0.0);
                let points = points.get(name).cloned().unwrap_or_default();
                let mut given = [false; 6];
                for g in &b.given {
                    given[*g as usize] = true;
                }
                Body {
                    name: name.clone(),
                    index: k,
                    mass: b.mass,
                    inertia: b.inertia,
                    points,
                    q0,
                    v0: [vel[0], vel[1], omega],
                    given,
                }
            })
            .collect();
        self.points = points;
        bodies
    }

    /// Names are shared by bodies, joints, drivers, forces and measures (they label output
    /// columns).
    /// The declared assembly modes (`branches:`), each a dyad of the joints it names; a joint
    /// that is missing (or was not read) or does not make a dyad is a problem at its entry.
    pub(super) fn branches(&mut self, joints: &[Element], bodies: &[Body]) -> Vec<(Dyad, Side)> {
        let spec = self.spec;
        let mut out = Vec::new();
        for (name, branch) in &spec.branches {
            let path = format!("branches.{name}");
            let broken = |j: &str| self.broken.iter().any(|b| b.strip_prefix("joints.") == Some(j));
            let index = |j: &str| joints.iter().position(|e| e.name == j);
            let names = [branch.line[0].as_str(), name.as_str(), branch.line[1].as_str()];
            let fields = [format!("{path}.line[0]"), path.clone(), format!("{path}.line[1]")];
            let mut found = [0; 3];
            let mut ok = true;
            for ((j, field), slot) in names.iter().zip(&fields).zip(&mut found) {
                match index(j) {
                    Some(k) => *slot = k,
                    None => {
                        ok = false;
                        if !broken(j) && !spec.joints.contains_key(*j) {
                            let known: Vec<&str> = spec.joints.keys().map(String::as_str).collect();
                            self.problem(field, format!("unknown joint '{j}'; expected one of: {}", known.join(", ")));
                        }
                    }
                }
            }
            if !ok {
                continue;
            }
            match Dyad::new(joints, bodies, found) {
                Ok(dyad) => out.push((dyad, branch.side)),
                Err(why) => self.problem(
                    path,
                    format!("{why}; expected a dyad: the entry's joint a pin between two moving bodies, `line` the pins [E, D] joining each of them to another body"),
                ),
            }
        }
        out
    }

    /// A problem for each name that two sections share (a joint and a driver both `motor`).
    pub(super) fn unique_names(&mut self) {
        let spec = self.spec;
        let mut seen: IndexMap<&str, &str> = IndexMap::new();
        let broken = self.broken.iter().filter_map(|b| b.split_once('.'));
        let all = spec
            .bodies
            .keys()
            .map(|k| ("bodies", k.as_str()))
            .chain(spec.joints.keys().map(|k| ("joints", k.as_str())))
            .chain(spec.drivers.keys().map(|k| ("drivers", k.as_str())))
            .chain(spec.forces.keys().map(|k| ("forces", k.as_str())))
            .chain(spec.measures.keys().map(|k| ("measures", k.as_str())))
            .chain(broken.filter(|(s, _)| ["bodies", "joints", "drivers", "forces", "measures"].contains(s)));
        for (section, name) in all {
            if let Some(first) = seen.get(name) {
                self.problem(
                    format!("{section}.{name}"),
                    format!("duplicate name: '{name}' is already used in {first}"),
                );
            } else {
                seen.insert(name, section);
            }
        }
    }

    /// The points of `paths:` (each `<body>.<point>` or `<body>`), or when it names none the
    /// points of the point measures, each once (a measure's own problems are reported at it).
    pub(super) fn paths(&mut self) -> Vec<PathPoint> {
        let spec = self.spec;
        let mut out: Vec<PathPoint> = Vec::new();
        if spec.paths.is_empty() {
            for m in spec.measures.values() {
                let MeasureSpec::Point(PointMeasure { body, point, .. }) = m else { continue };
                let Some(points) = self.points.get(body) else { continue };
                let (named, s) = match point {
                    PointRef::Name(n) => (points.get_key_value(n), points.get(n).copied()),
                    PointRef::Coords(v) => (points.iter().find(|(_, s)| *s == v), Some(*v)),
                };
                let Some(s) = s.filter(|s| s.iter().all(|x| x.is_finite())) else { continue };
                let name = match named {
                    Some((n, _)) => format!("{body}.{n}"),
                    None if s == [0.0; 2] => body.clone(),
                    None => format!("{body} [{}, {}]", s[0], s[1]),
                };
                if !out.iter().any(|p| p.body == *body && p.point == s) {
                    out.push(PathPoint { name, body: body.clone(), point: s });
                }
            }
            return out;
        }
        for (k, entry) in spec.paths.iter().enumerate() {
            let path = format!("paths[{k}]");
            let (body, point) = match entry.split_once('.') {
                Some((body, point)) => (body, Some(point)),
                None => (entry.as_str(), None),
            };
            if self.moving(&path, body).is_none() {
                continue;
            }
            let Some(points) = self.points.get(body) else { continue };
            let s = match point {
                None => [0.0; 2],
                Some(p) => match points.get(p) {
                    Some(s) => *s,
                    None => {
                        let known: Vec<&str> = points.keys().map(String::as_str).collect();
                        let list = if known.is_empty() {
                            "it has no named points".to_string()
                        } else {
                            format!("it has {}", known.join(", "))
                        };
                        self.problem(&path, format!("unknown point '{p}' of body '{body}' ({list}); expected <body>.<point>, or <body> for its centre of mass"));
                        continue;
                    }
                },
            };
            if let Some(first) = spec.paths[..k].iter().position(|e| e == entry) {
                self.problem(&path, format!("'{entry}' is already paths[{first}]: name each point once"));
                continue;
            }
            out.push(PathPoint { name: entry.clone(), body: body.to_string(), point: s });
        }
        out
    }
}
