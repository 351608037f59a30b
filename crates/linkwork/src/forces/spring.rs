//! Spring-damper-actuators: translational, between two points, and rotational, between two
//! bodies (Haug 1989 section 6.2.4; Nikravesh 2018 section 10.4).
//!
//! ```text
//! translational:  d = r_Q - r_P,  l = |d|,  u = d / l,  l' = u . (rdot_Q - rdot_P)
//!                 F = -k (l - l0) - c l' + a          (F > 0 pushes P and Q apart)
//!                 on j: f_j = F u at Q;  on i: f_i = -F u at P;   V = k (l - l0)^2 / 2
//! rotational:     theta = phi_i - phi_j,  T = -k (theta - theta0) - c theta' + a
//!                 on i: T;  on j: -T;                              V = k (theta - theta0)^2 / 2
//! ```
//! A point's velocity is `rdot + omega R90 A s'`.

use super::{cross, layout, rotate, Force, ForceContext, ForceLaw, Load, Local, Quantity};
use crate::element::fields;
use crate::element::PointRef;
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Translational spring-damper-actuator between point `s_p` of body i and `s_q` of body j.
#[derive(Debug, Clone)]
pub struct SpringDamper {
    i: Local,
    s_p: [f64; 2],
    j: Local,
    s_q: [f64; 2],
    stiffness: f64,
    damping: f64,
    free_length: f64,
    actuator: Load,
    columns: Vec<usize>,
}

impl SpringDamper {
    /// A spring-damper between the bodies whose `x` are `q[i]`, `q[j]` (`None` for ground).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        i: Option<usize>,
        s_p: [f64; 2],
        j: Option<usize>,
        s_q: [f64; 2],
        stiffness: f64,
        damping: f64,
        free_length: f64,
        mut actuator: Load,
    ) -> SpringDamper {
        let (columns, l) = layout(&[i, j], &mut [&mut actuator]);
        SpringDamper { i: l[0], s_p, j: l[1], s_q, stiffness, damping, free_length, actuator, columns }
    }

    /// `(d, l)` and the two lever arms `A s'`.
    #[inline]
    fn geometry<S: Scalar>(&self, x: &[S]) -> ([S; 2], S, [S; 2], [S; 2]) {
        let (pi, pj) = (self.i.pose(x), self.j.pose(x));
        let (ap, aq) = (rotate(pi[2], self.s_p), rotate(pj[2], self.s_q));
        let d = [pj[0] + aq[0] - pi[0] - ap[0], pj[1] + aq[1] - pi[1] - ap[1]];
        (d, (d[0] * d[0] + d[1] * d[1]).sqrt(), ap, aq)
    }
}

impl ForceLaw for SpringDamper {
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn load<S: Scalar>(&self, x: &[S], v: &[S], t: f64, out: &mut [S]) {
        out.fill(S::constant(0.0));
        let (d, l, ap, aq) = self.geometry(x);
        if l.value() < 1e-300 {
            return; // coincident points: no direction, no force
        }
        // Velocities of the points: rdot + omega R90 (A s').
        let (vi, vj) = (self.i.pose(v), self.j.pose(v));
        let dv = [vj[0] - vj[2] * aq[1] - vi[0] + vi[2] * ap[1], vj[1] + vj[2] * aq[0] - vi[1] - vi[2] * ap[0]];
        let rate = (d[0] * dv[0] + d[1] * dv[1]) / l;
        let f = S::constant(-self.stiffness) * (l - S::constant(self.free_length)) - S::constant(self.damping) * rate
            + self.actuator.value(x, v, t);
        let fu = [f * d[0] / l, f * d[1] / l];
        self.j.add(out, [fu[0], fu[1], cross(aq, fu)]);
        let neg = [-fu[0], -fu[1]];
        self.i.add(out, [neg[0], neg[1], cross(ap, neg)]);
    }
    fn conservative(&self) -> bool {
        self.damping == 0.0 && self.actuator.is_zero()
    }
    fn potential<S: Scalar>(&self, x: &[S]) -> S {
        let (_, l, _, _) = self.geometry(x);
        let e = l - S::constant(self.free_length);
        S::constant(0.5 * self.stiffness) * e * e
    }
}

/// Rotational spring-damper-actuator between body i and body j.
#[derive(Debug, Clone)]
pub struct RotationalSpringDamper {
    i: Local,
    j: Local,
    stiffness: f64,
    damping: f64,
    free_angle: f64,
    actuator: Load,
    columns: Vec<usize>,
}

impl RotationalSpringDamper {
    /// A rotational spring-damper between the bodies whose `x` are `q[i]`, `q[j]` (`None` for
    /// ground).
    pub fn new(
        i: Option<usize>,
        j: Option<usize>,
        stiffness: f64,
        damping: f64,
        free_angle: f64,
        mut actuator: Load,
    ) -> RotationalSpringDamper {
        let (columns, l) = layout(&[i, j], &mut [&mut actuator]);
        RotationalSpringDamper { i: l[0], j: l[1], stiffness, damping, free_angle, actuator, columns }
    }
}

impl ForceLaw for RotationalSpringDamper {
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn load<S: Scalar>(&self, x: &[S], v: &[S], t: f64, out: &mut [S]) {
        out.fill(S::constant(0.0));
        let theta = self.i.pose(x)[2] - self.j.pose(x)[2];
        let rate = self.i.pose(v)[2] - self.j.pose(v)[2];
        let torque = S::constant(-self.stiffness) * (theta - S::constant(self.free_angle))
            - S::constant(self.damping) * rate
            + self.actuator.value(x, v, t);
        let zero = S::constant(0.0);
        self.i.add(out, [zero, zero, torque]);
        self.j.add(out, [zero, zero, -torque]);
    }
    fn conservative(&self) -> bool {
        self.damping == 0.0 && self.actuator.is_zero()
    }
    fn potential<S: Scalar>(&self, x: &[S]) -> S {
        let e = self.i.pose(x)[2] - self.j.pose(x)[2] - S::constant(self.free_angle);
        S::constant(0.5 * self.stiffness) * e * e
    }
}

fields! {
    /// Translational spring-damper-actuator between two points.
    #[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
    #[serde(deny_unknown_fields)]
    pub struct SpringDamperSpec {
        [body_i, point_i, body_j, point_j,]
        /// Stiffness, N/m. Default 0.
        #[serde(default)]
        pub stiffness: f64,
        /// Damping, N s/m. Default 0.
        #[serde(default)]
        pub damping: f64,
        /// Length at which the spring exerts no force, m. Default: the distance in the initial guess.
        #[serde(default)]
        pub free_length: Option<f64>,
        /// Actuator force pushing the points apart, N: a number or an expression. Default 0.
        #[serde(default)]
        pub actuator: Quantity,
    }
}

/// Rotational spring-damper-actuator between two bodies (or a body and ground).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RotationalSpringDamperSpec {
    /// First body (the torque is reported on it).
    pub body_i: String,
    /// Second body.
    pub body_j: String,
    /// Stiffness, N m/rad. Default 0.
    #[serde(default)]
    pub stiffness: f64,
    /// Damping, N m s/rad. Default 0.
    #[serde(default)]
    pub damping: f64,
    /// Relative angle `phi_i - phi_j` at which the spring exerts no torque, rad. Default: its
    /// value in the initial guess.
    #[serde(default)]
    pub free_angle: Option<f64>,
    /// Actuator torque on `body_i` (its opposite on `body_j`), N m: a number or an expression.
    /// Default 0.
    #[serde(default)]
    pub actuator: Quantity,
}

/// A spring-damper at `path` compiled in `cx`; its free length defaults to the initial distance.
pub(crate) fn compile(spec: &SpringDamperSpec, cx: &mut impl ForceContext, path: &str) -> Option<Box<dyn Force>> {
    let SpringDamperSpec { body_i, point_i, body_j, point_j, stiffness, damping, free_length, actuator } = spec;
    let ends = cx.ends(path, body_i, point_i, body_j, point_j);
    let k = cx.non_negative(&format!("{path}.stiffness"), *stiffness);
    let c = cx.non_negative(&format!("{path}.damping"), *damping);
    let act = cx.load(&format!("{path}.actuator"), actuator);
    let (ends, k, c, act) = (ends?, k?, c?, act?);
    let [(i, sp), (j, sq)] = ends;
    let l0 = match free_length {
        Some(l) => cx.non_negative(&format!("{path}.free_length"), *l)?,
        None => cx.initial_distance(ends),
    };
    Some(Box::new(SpringDamper::new(i.0, sp, j.0, sq, k, c, l0, act)))
}

/// A rotational spring-damper at `path` compiled in `cx`; its free angle defaults to the initial
/// relative angle.
pub(crate) fn compile_rotational(
    spec: &RotationalSpringDamperSpec,
    cx: &mut impl ForceContext,
    path: &str,
) -> Option<Box<dyn Force>> {
    let RotationalSpringDamperSpec { body_i, body_j, stiffness, damping, free_angle, actuator } = spec;
    let origin = PointRef::default();
    let ends = cx.ends(path, body_i, &origin, body_j, &origin);
    let k = cx.non_negative(&format!("{path}.stiffness"), *stiffness);
    let c = cx.non_negative(&format!("{path}.damping"), *damping);
    let act = cx.load(&format!("{path}.actuator"), actuator);
    let ([(i, _), (j, _)], k, c, act) = (ends?, k?, c?, act?);
    let theta0 = match free_angle {
        Some(a) => cx.finite(&format!("{path}.free_angle"), *a)?,
        None => i.coords(cx.q0())[2] - j.coords(cx.q0())[2],
    };
    Some(Box::new(RotationalSpringDamper::new(i.0, j.0, k, c, theta0, act)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::testing::{check_conservative, check_derivatives, expression};

    /// Hand-derived: points 2 m apart along x with free length 1.5 and stiffness 10: the spring
    /// pulls them together with 5 N; a damper of 3 N s/m with the second point receding at
    /// 1 m/s adds 3 N more. Potential `10 * 0.5^2 / 2 = 1.25` J.
    #[test]
    fn spring_hand_derived() {
        let s = SpringDamper::new(None, [0.0, 0.0], Some(0), [0.0, 0.0], 10.0, 3.0, 1.5, Load::Constant(0.0));
        let mut out = [0.0; 3];
        ForceLaw::load(&s, &[2.0, 0.0, 0.0], &[1.0, 0.0, 0.0], 0.0, &mut out);
        assert!((out[0] + 8.0).abs() < 1e-14 && out[1].abs() < 1e-14 && out[2].abs() < 1e-14, "{out:?}");
        assert!((ForceLaw::potential(&s, &[2.0, 0.0, 0.0]) - 1.25).abs() < 1e-14);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let act = expression("2*sin(t) + 0.5*b0.vx*b1.omega", 2);
        let s = SpringDamper::new(Some(0), [0.2, 0.1], Some(3), [-0.3, 0.4], 40.0, 2.5, 0.7, act.clone());
        check_derivatives(&s, 6, 21);
        let g = SpringDamper::new(None, [1.0, -2.0], Some(3), [-0.3, 0.4], 40.0, 2.5, 0.7, Load::Constant(1.0));
        check_derivatives(&g, 6, 22);
        let r = RotationalSpringDamper::new(Some(0), Some(3), 12.0, 0.8, 0.3, act);
        check_derivatives(&r, 6, 23);
        let rg = RotationalSpringDamper::new(Some(3), None, 12.0, 0.8, 0.3, Load::Constant(0.0));
        check_derivatives(&rg, 6, 24);
    }

    /// Without damping or actuator, each spring's load is minus its potential's gradient.
    #[test]
    fn springs_are_conservative() {
        let s = SpringDamper::new(Some(0), [0.2, 0.1], Some(3), [-0.3, 0.4], 40.0, 0.0, 0.7, Load::Constant(0.0));
        check_conservative(&s, 31);
        let r = RotationalSpringDamper::new(Some(0), None, 12.0, 0.0, 0.3, Load::Constant(0.0));
        check_conservative(&r, 32);
    }
}
