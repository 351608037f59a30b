//! Expressions of time and the state in the model's names: forces' loads, measures and general
//! constraints, each name resolved to a coordinate, a rate, an acceleration or a reaction.

use super::*;

/// What expressions name of a body (`crank.phi`, `crank.omega`): its coordinates, their rates
/// and their accelerations.
const QUANTITIES: [&str; 9] = ["x", "y", "phi", "vx", "vy", "omega", "ax", "ay", "alpha"];

impl Cx<'_> {
    /// An expression of time and state: `<body>.x, .y, .phi, .vx, .vy, .omega` and `t`; for a
    /// `measure` also the accelerations `.ax, .ay, .alpha`, the joints' reactions
    /// `<joint>.fx, .fy, .torque` and the drivers' efforts `<driver>.effort`.
    pub(super) fn state_expr(&mut self, path: &str, src: &str, measure: bool) -> Option<StateExpr> {
        let var = |v: Option<(usize, usize)>| match v {
            None => StateVar::Time,
            Some((col, 0)) => StateVar::Position(col),
            Some((col, 1)) => StateVar::Velocity(col),
            Some((col, _)) => StateVar::Acceleration(col),
        };
        let reaction = measure.then_some(StateVar::Reaction as fn(usize) -> StateVar);
        self.expression(path, src, if measure { 9 } else { 6 }, var, reaction, StateExpr::try_new)
    }

    /// The expression `src` at `path` compiled by `build` from its variables: `t`, and
    /// `<body>.<q>` for `q` among the first `quantities` of [`QUANTITIES`]; `var` makes each
    /// variable from `None` (time) or `Some((column, order of derivative))`. With `reaction`, also
    /// `<joint>.fx, .fy, .torque` and `<driver>.effort`, made by `reaction` from their entry in
    /// the reactions row (every joint's three, then every driver's effort, in file order). `None`
    /// (with the problem recorded, unless it names an entry that could not be read) when it
    /// cannot be compiled.
    pub(super) fn expression<V: PartialEq, T>(
        &mut self,
        path: &str,
        src: &str,
        quantities: usize,
        var: impl Fn(Option<(usize, usize)>) -> V,
        reaction: Option<fn(usize) -> V>,
        build: impl FnOnce(Expr, Vec<V>) -> Result<T, String>,
    ) -> Option<T> {
        let spec = self.spec;
        let known = self.body_names().join(", ");
        let all_broken = self.broken;
        let broken = |section: &str| -> Vec<&str> {
            all_broken.iter().filter_map(|b| b.strip_prefix(section)?.strip_prefix('.')).collect()
        };
        let (broken_bodies, broken_joints, broken_drivers) = (broken("bodies"), broken("joints"), broken("drivers"));
        let names = |section: Vec<&str>, broken: &[&str]| {
            section.into_iter().chain(broken.iter().copied()).collect::<Vec<_>>().join(", ")
        };
        let joints = names(spec.joints.keys().map(String::as_str).collect(), &broken_joints);
        let drivers = names(spec.drivers.keys().map(String::as_str).collect(), &broken_drivers);
        let quantities = &QUANTITIES[..quantities];
        let hint = || {
            let mut q: Vec<String> = quantities.iter().map(|q| format!("<body>.{q}")).collect();
            if reaction.is_none() {
                return format!("expected {} or t, with a body among: {known}", q.join(", "));
            }
            q.extend(REACTION_QUANTITIES.iter().map(|q| format!("<joint>.{q}")));
            q.push("<driver>.effort".into());
            format!(
                "expected {} or t, with a body among: {known}; a joint among: {joints}; a driver among: {drivers}",
                q.join(", ")
            )
        };
        // The entry in the reactions row of `<owner>.<quantity>`: `Some(None)` for a joint or
        // driver that could not be read (its own problem is reported), `None` when the name is
        // not a reaction or effort.
        let reaction_of = |owner: &str, quantity: &str| -> Option<Option<usize>> {
            let component = REACTION_QUANTITIES.iter().position(|q| *q == quantity);
            if let Some(j) = spec.joints.get_index_of(owner) {
                return component.map(|c| Some(3 * j + c));
            }
            if let Some(d) = spec.drivers.get_index_of(owner) {
                return (quantity == "effort").then_some(Some(3 * spec.joints.len() + d));
            }
            let broken = (component.is_some() && broken_joints.contains(&owner))
                || (quantity == "effort" && broken_drivers.contains(&owner));
            broken.then_some(None)
        };
        let mut uses_broken = false;
        let mut vars: Vec<V> = Vec::new();
        let mut resolve = |name: &str| -> Result<usize, String> {
            let v = if name == "t" {
                var(None)
            } else {
                let (b, c) = name.split_once('.').ok_or_else(hint)?;
                let row = reaction.and_then(|r| Some((r, reaction_of(b, c)?)));
                match (spec.bodies.get_index_of(b), row) {
                    (None, Some((r, Some(k)))) => r(k),
                    (None, Some((r, None))) => {
                        uses_broken = true;
                        r(0)
                    }
                    (k, _) => {
                        let at = quantities.iter().position(|q| *q == c).ok_or_else(hint)?;
                        // A body that exists but could not be read: its own problem is reported.
                        let k = match k {
                            Some(k) => k,
                            None if broken_bodies.contains(&b) => {
                                uses_broken = true;
                                0
                            }
                            None => return Err(hint()),
                        };
                        var(Some((3 * k + at % 3, at / 3)))
                    }
                }
            };
            Ok(match vars.iter().position(|u| *u == v) {
                Some(s) => s,
                None => {
                    vars.push(v);
                    vars.len() - 1
                }
            })
        };
        let names = ModelNames { parameters: &self.spec.parameters, tables: &self.tables };
        let expr = match Expr::parse_with(src, &names, &mut resolve) {
            Ok(e) => e,
            Err(e) => {
                self.problem(path, format!("cannot read the expression '{src}': {e}"));
                return None;
            }
        };
        if uses_broken {
            return None;
        }
        match build(expr, vars) {
            Ok(t) => Some(t),
            Err(e) => {
                self.problem(path, e);
                None
            }
        }
    }
}
