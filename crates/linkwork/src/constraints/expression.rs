//! General constraint: one row given by any expression of coordinates and time, differentiated
//! exactly by forward-mode automatic differentiation (dual and hyper-dual numbers).
//!
//! Slot `k` of the expression is `vars[k]`: a coordinate `q[c]` or the time `t`. Let `z` gather the
//! slots and `v` be the direction `z` moves in as time runs: `qdot[c]` for a coordinate slot, `1`
//! for the time slot. Then
//!
//! ```text
//! Phi   = e(z)
//! Phi_q = de/dz over the coordinate slots (one Dual pass per slot; slots naming the same
//!         coordinate add up)                                               (1 x columns)
//! nu    = -Phi_t = -de/dt                                                  (one Dual pass)
//! gamma = -v^T H v   (H the Hessian of e in z)                             (one HyperDual pass)
//! ```
//! The last line is the acceleration right-hand side: along `q(s) = q + s qdot`, `t(s) = t + s`,
//! `d2 Phi / ds2 = (Phi_q qdot)_q qdot + 2 Phi_qt qdot + Phi_tt = v^T H v`. At most
//! [`MAX_SLOTS`] slots, so that the derivative passes run on stack arrays. Haug (1989) section
//! 3.5 (general constraints and drivers); derivatives by hyper-dual numbers (Fike and Alonso, 2011).

use super::schema::JointContext;
use super::CompiledJoint;
use super::{phi_tri_generic, Anchor, At, BodyIx, Config, Constraint, GenericPhi};
use crate::expr::{Dual, Expr, HyperDual, Scalar, MAX_SLOTS};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// What an expression slot stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Var {
    /// The coordinate `q[index]`.
    Coord(usize),
    /// The time `t`.
    Time,
}

/// A constraint row `e(q, t) = 0` from an expression.
#[derive(Debug, Clone)]
pub struct GeneralConstraint {
    expr: Expr,
    /// `(slots)` what each slot stands for.
    vars: Vec<Var>,
    /// `(slots)` the Jacobian column of each coordinate slot (index into `columns`).
    column_of: Vec<Option<usize>>,
    /// Distinct coordinate indices, in slot order.
    columns: Vec<usize>,
}

impl GeneralConstraint {
    /// The row `expr = 0` with slot `k` standing for `vars[k]`.
    ///
    /// # Errors
    ///
    /// More than [`MAX_SLOTS`] slots, or an expression slot without an entry in `vars`.
    pub fn try_new(expr: Expr, vars: Vec<Var>) -> Result<GeneralConstraint, String> {
        if vars.len() > MAX_SLOTS {
            return Err(format!("the expression uses {} names; at most {MAX_SLOTS} are supported", vars.len()));
        }
        if let Some(&s) = expr.slots().iter().find(|&&s| s >= vars.len()) {
            return Err(format!("expression slot {s} has no variable ({} given)", vars.len()));
        }
        let mut columns: Vec<usize> = Vec::new();
        let column_of = vars
            .iter()
            .map(|v| match *v {
                Var::Time => None,
                Var::Coord(c) => Some(columns.iter().position(|&k| k == c).unwrap_or_else(|| {
                    columns.push(c);
                    columns.len() - 1
                })),
            })
            .collect();
        Ok(GeneralConstraint { expr, vars, column_of, columns })
    }

    /// As [`GeneralConstraint::try_new`].
    ///
    /// # Panics
    ///
    /// Where [`GeneralConstraint::try_new`] returns an error.
    pub fn new(expr: Expr, vars: Vec<Var>) -> GeneralConstraint {
        match GeneralConstraint::try_new(expr, vars) {
            Ok(c) => c,
            Err(e) => panic!("invalid general constraint: {e}"),
        }
    }

    /// The expression.
    pub fn expr(&self) -> &Expr {
        &self.expr
    }

    /// What each slot stands for.
    pub fn vars(&self) -> &[Var] {
        &self.vars
    }

    /// `(q, t) => z`, the slot values, as scalars with no derivative part.
    #[inline]
    fn slots<S: Scalar>(&self, q: &[f64], t: f64) -> [S; MAX_SLOTS] {
        let mut z = [S::constant(0.0); MAX_SLOTS];
        for (zk, v) in z.iter_mut().zip(&self.vars) {
            *zk = S::constant(match *v {
                Var::Coord(c) => q[c],
                Var::Time => t,
            });
        }
        z
    }
}

impl Constraint for GeneralConstraint {
    fn anchor(&self) -> Anchor {
        Anchor {
            i: self.columns.first().map_or(BodyIx::GROUND, |&c| BodyIx(Some(c - c % 3))),
            j: BodyIx::GROUND,
            point: [0.0, 0.0],
        }
    }
    fn row_names(&self) -> &[&'static str] {
        &["expression"]
    }
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn phi(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
        let z = self.slots::<f64>(q, t);
        out[0] = self.expr.eval(&z[..self.vars.len()]);
    }
    fn jacobian(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
        let n = self.vars.len();
        let mut z = self.slots::<Dual>(q, t);
        out[..self.columns.len()].fill(0.0);
        for &s in self.expr.slots() {
            if let Some(col) = self.column_of[s] {
                z[s].d = 1.0;
                out[col] += self.expr.eval(&z[..n]).d;
                z[s].d = 0.0;
            }
        }
    }
    fn nu(&self, q: &Config<'_>, t: f64, out: &mut [f64]) {
        let n = self.vars.len();
        let mut z = self.slots::<Dual>(q, t);
        let mut timed = false;
        for (zk, v) in z.iter_mut().zip(&self.vars) {
            if *v == Var::Time {
                zk.d = 1.0;
                timed = true;
            }
        }
        out[0] = if timed { -self.expr.eval(&z[..n]).d } else { 0.0 };
    }
    fn gamma(&self, q: &Config<'_>, qdot: &[f64], t: f64, out: &mut [f64]) {
        let n = self.vars.len();
        let mut z = self.slots::<HyperDual>(q, t);
        for (zk, v) in z.iter_mut().zip(&self.vars) {
            let dir = match *v {
                Var::Coord(c) => qdot[c],
                Var::Time => 1.0,
            };
            *zk = HyperDual::seed(zk.v, dir, dir);
        }
        out[0] = -self.expr.eval(&z[..n]).e12;
    }
    phi_tri_generic!();
}

/// No data: the expression's numbers are parameters, which `At` carries.
impl GenericPhi for GeneralConstraint {
    fn parameters(&self) -> &[usize] {
        self.expr.parameters()
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, _data: &[S], out: &mut [S]) {
        let mut z = [S::constant(0.0); MAX_SLOTS];
        for (zk, v) in z.iter_mut().zip(&self.vars) {
            *zk = match *v {
                Var::Coord(c) => at.q[c],
                Var::Time => at.t,
            };
        }
        out[0] = self.expr.eval_params(&z[..self.vars.len()], at.params);
    }
}

/// A general constraint `expression = 0` in body coordinates (`crank.x`, `crank.y`,
/// `crank.phi`) and time `t`, differentiated exactly. 1 equation.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ExpressionJoint {
    /// The left-hand side, e.g. `"crank.x^2 + crank.y^2 - 0.5625"`.
    pub expression: String,
}

/// An expression joint at `path` compiled in `cx`.
pub(crate) fn compile(spec: &ExpressionJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    let c = cx.coordinate_constraint(&format!("{path}.expression"), &spec.expression)?;
    Some((Box::new(c), None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::OnSlice;
    use crate::constraints::testing::{assert_data_fields, check_fd_random, check_generic_random};

    /// Parse `src` over names `<x|y|phi><body>` (body 0 or 1) and `t`, slots in order of first use.
    fn general(src: &str) -> GeneralConstraint {
        let mut vars = Vec::new();
        let expr = Expr::parse(src, &mut |name| {
            let var = if name == "t" {
                Var::Time
            } else {
                let (c, b) = name.split_at(name.len() - 1);
                let off = ["x", "y", "phi"].iter().position(|n| *n == c).ok_or("unknown")?;
                Var::Coord(3 * b.parse::<usize>().map_err(|e| e.to_string())? + off)
            };
            Ok(vars.iter().position(|v| *v == var).unwrap_or_else(|| {
                vars.push(var);
                vars.len() - 1
            }))
        })
        .unwrap();
        GeneralConstraint::new(expr, vars)
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let c = general("x0*cos(phi1) - y1^2*sin(t*phi0) + 0.3*t^2*x1 + exp(0.1*y0*x0) - 1.5");
        assert_eq!(c.columns(), [0, 5, 4, 2, 3, 1]);
        check_fd_random(&c, 2, 1);
        check_generic_random(&c, 2, 1);
        assert_data_fields::<ExpressionJoint>(&c);
        let one_body = general("atan2(y1, x1) + phi1^3 - 2");
        check_fd_random(&one_body, 2, 2);
        check_generic_random(&one_body, 2, 2);
        let no_time = general("x0^2 + y0^2 - 0.5625");
        check_fd_random(&no_time, 2, 3);
        check_generic_random(&no_time, 2, 3);
    }

    /// A coordinate named in two slots: its Jacobian column is the sum of both slots' derivatives.
    #[test]
    fn repeated_coordinate_adds_up() {
        let expr = Expr::parse("a * b", &mut |n| Ok(if n == "a" { 0 } else { 1 })).unwrap();
        let c = GeneralConstraint::new(expr, vec![Var::Coord(2), Var::Coord(2)]);
        assert_eq!(c.columns(), [2]);
        let mut jac = [0.0];
        c.jacobian_at(&[0.0, 0.0, 1.5], 0.0, &mut jac);
        assert_eq!(jac, [3.0]);
        check_fd_random(&c, 1, 4);
        check_generic_random(&c, 1, 4);
    }

    /// Hand-derived: Phi = x^2 + y^2 - 0.5625 + x t at (x, y) = (0.6, 0.45), t = 0: Phi = 0,
    /// Phi_x = 2 x + t = 1.2, Phi_y = 0.9, nu = -x = -0.6; with velocity (vx, vy) = (2, -1):
    /// gamma = -(2 vx^2 + 2 vy^2 + 2 vx) = -(8 + 2 + 4) = -14.
    #[test]
    fn hand_derived_circle_with_time() {
        let c = general("x0^2 + y0^2 - 0.5625 + x0*t");
        let q = [0.6, 0.45, 0.0];
        let (mut phi, mut jac, mut nu, mut g) = ([1.0], [0.0; 2], [0.0], [0.0]);
        c.phi_at(&q, 0.0, &mut phi);
        c.jacobian_at(&q, 0.0, &mut jac);
        c.nu_at(&q, 0.0, &mut nu);
        c.gamma_at(&q, &[2.0, -1.0, 0.0], 0.0, &mut g);
        assert!(phi[0].abs() < 1e-15, "{phi:?}");
        assert!((jac[0] - 1.2).abs() < 1e-15 && (jac[1] - 0.9).abs() < 1e-15, "{jac:?}");
        assert!((nu[0] + 0.6).abs() < 1e-15, "{nu:?}");
        assert!((g[0] + 14.0).abs() < 1e-14, "{g:?}");
        assert_eq!(c.row_names(), ["expression"]);
    }

    #[test]
    fn too_many_slots_is_an_error() {
        let src: Vec<String> = (0..65).map(|k| format!("v{k}")).collect();
        let expr = Expr::parse(&src.join(" + "), &mut |n| Ok(n[1..].parse::<usize>().unwrap())).unwrap();
        let err = GeneralConstraint::try_new(expr.clone(), vec![Var::Time; 65]).unwrap_err();
        assert!(err.contains("at most 64"), "{err}");
        let err = GeneralConstraint::try_new(expr, vec![Var::Time; 3]).unwrap_err();
        assert!(err.contains("no variable"), "{err}");
    }
}
