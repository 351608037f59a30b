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

use super::{cross, layout, rotate, Data, Force, ForceContext, ForceLaw, Load, Local, Quantity};
use crate::element::fields;
use crate::element::{vector, PointRef, Source, POINT_I, POINT_J};
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
    /// Where `free_length` comes from: the file (a data slot) or the initial configuration.
    free_length_from: Source,
    actuator: Load,
    columns: Vec<usize>,
}

/// A translational spring-damper's numbers over any [`Scalar`]: its own as constants
/// ([`ForceLaw::load`]) or its data ([`ForceLaw::load_data`]).
struct SpringNumbers<S> {
    s_p: [S; 2],
    s_q: [S; 2],
    /// Minus the stiffness (the law multiplies by it as such).
    neg_stiffness: S,
    damping: S,
    free_length: S,
    actuator: S,
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
        let free_length_from = Source::File;
        SpringDamper {
            i: l[0],
            s_p,
            j: l[1],
            s_q,
            stiffness,
            damping,
            free_length,
            free_length_from,
            actuator,
            columns,
        }
    }

    /// `(d, l)` and the two lever arms `A s'` of the points `s_p`, `s_q` of bodies at `pi`, `pj`.
    #[inline]
    fn geometry<S: Scalar>(pi: [S; 3], pj: [S; 3], s_p: [S; 2], s_q: [S; 2]) -> ([S; 2], S, [S; 2], [S; 2]) {
        let (ap, aq) = (rotate(pi[2], s_p), rotate(pj[2], s_q));
        let d = [pj[0] + aq[0] - pi[0] - ap[0], pj[1] + aq[1] - pi[1] - ap[1]];
        (d, (d[0] * d[0] + d[1] * d[1]).sqrt(), ap, aq)
    }

    /// Its own numbers, as constants.
    fn numbers<S: Scalar>(&self, actuator: S) -> SpringNumbers<S> {
        SpringNumbers {
            s_p: self.s_p.map(S::constant),
            s_q: self.s_q.map(S::constant),
            neg_stiffness: S::constant(-self.stiffness),
            damping: S::constant(self.damping),
            free_length: S::constant(self.free_length),
            actuator,
        }
    }

    /// `Q_e` at `(x, v)` with the numbers `n`.
    #[inline]
    fn law<S: Scalar>(&self, x: &[S], v: &[S], n: SpringNumbers<S>, out: &mut [S]) {
        out.fill(S::constant(0.0));
        let (d, l, ap, aq) = SpringDamper::geometry(self.i.pose(x), self.j.pose(x), n.s_p, n.s_q);
        if l.value() < 1e-300 {
            return; // coincident points: no direction, no force
        }
        // Velocities of the points: rdot + omega R90 (A s').
        let (vi, vj) = (self.i.pose(v), self.j.pose(v));
        let dv = [vj[0] - vj[2] * aq[1] - vi[0] + vi[2] * ap[1], vj[1] + vj[2] * aq[0] - vi[1] - vi[2] * ap[0]];
        let rate = (d[0] * dv[0] + d[1] * dv[1]) / l;
        let f = n.neg_stiffness * (l - n.free_length) - n.damping * rate + n.actuator;
        let fu = [f * d[0] / l, f * d[1] / l];
        self.j.add(out, [fu[0], fu[1], cross(aq, fu)]);
        let neg = [-fu[0], -fu[1]];
        self.i.add(out, [neg[0], neg[1], cross(ap, neg)]);
    }
}

impl ForceLaw for SpringDamper {
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn load<S: Scalar>(&self, x: &[S], v: &[S], t: f64, out: &mut [S]) {
        self.law(x, v, self.numbers(self.actuator.value(x, v, t)), out);
    }
    fn conservative(&self) -> bool {
        self.damping == 0.0 && self.actuator.is_zero()
    }
    fn potential<S: Scalar>(&self, x: &[S]) -> S {
        let n = self.numbers(S::constant(0.0));
        let (_, l, _, _) = SpringDamper::geometry(self.i.pose(x), self.j.pose(x), n.s_p, n.s_q);
        let e = l - S::constant(self.free_length);
        S::constant(0.5 * self.stiffness) * e * e
    }
    /// `point_i`, `point_j`, `stiffness`, `damping`, `actuator` when it is a number, and
    /// `free_length` when the file gives it.
    fn data(&self) -> Vec<(&'static str, f64)> {
        let mut data = [vector(POINT_I, self.s_p), vector(POINT_J, self.s_q)].concat();
        data.extend([("stiffness", self.stiffness), ("damping", self.damping)]);
        data.extend(self.actuator.data("actuator"));
        self.free_length_from.data(data, "free_length", self.free_length)
    }
    /// A free length from the initial configuration is the points' distance at the held
    /// initial poses: it follows the points.
    fn load_data<S: Scalar>(&self, x: &[S], v: &[S], t: f64, data: &[S], params: &[S], out: &mut [S]) -> bool {
        let mut d = Data::new(data);
        let (s_p, s_q) = (d.pair(), d.pair());
        let (neg_stiffness, damping) = (-d.next(), d.next());
        let actuator = self.actuator.value_data(x, v, t, &mut d, params);
        let free_length = self.free_length_data(d.all(), s_p, s_q);
        self.law(x, v, SpringNumbers { s_p, s_q, neg_stiffness, damping, free_length, actuator }, out);
        true
    }
    /// `k (l - l0)^2 / 2` with the points, the stiffness and the free length from `data`.
    fn potential_data<S: Scalar>(&self, x: &[S], data: &[S], _params: &[S]) -> Option<S> {
        let mut d = Data::new(data);
        let (s_p, s_q) = (d.pair(), d.pair());
        let stiffness = d.next();
        let (_, l, _, _) = SpringDamper::geometry(self.i.pose(x), self.j.pose(x), s_p, s_q);
        let e = l - self.free_length_data(d.all(), s_p, s_q);
        Some(S::constant(0.5) * stiffness * e * e)
    }
}

impl SpringDamper {
    /// The free length over the numbers `data` ([`ForceLaw::data`]) with the points `s_p`,
    /// `s_q` among them: the file's, or the points' distance at the held initial poses.
    fn free_length_data<S: Scalar>(&self, data: &[S], s_p: [S; 2], s_q: [S; 2]) -> S {
        self.free_length_from.value(data, |[fi, fj]| {
            SpringDamper::geometry([fi.o[0], fi.o[1], fi.phi], [fj.o[0], fj.o[1], fj.phi], s_p, s_q).1
        })
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
    /// Where `free_angle` comes from: the file (a data slot) or the initial configuration.
    free_angle_from: Source,
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
        let free_angle_from = Source::File;
        RotationalSpringDamper { i: l[0], j: l[1], stiffness, damping, free_angle, free_angle_from, actuator, columns }
    }

    /// `Q_e` at `(x, v)` with minus the stiffness, the damping, the free angle and the actuator's
    /// torque given.
    #[inline]
    fn law<S: Scalar>(&self, x: &[S], v: &[S], [neg_stiffness, damping, free_angle, actuator]: [S; 4], out: &mut [S]) {
        out.fill(S::constant(0.0));
        let theta = self.i.pose(x)[2] - self.j.pose(x)[2];
        let rate = self.i.pose(v)[2] - self.j.pose(v)[2];
        let torque = neg_stiffness * (theta - free_angle) - damping * rate + actuator;
        let zero = S::constant(0.0);
        self.i.add(out, [zero, zero, torque]);
        self.j.add(out, [zero, zero, -torque]);
    }
}

impl ForceLaw for RotationalSpringDamper {
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn load<S: Scalar>(&self, x: &[S], v: &[S], t: f64, out: &mut [S]) {
        let numbers = [-self.stiffness, self.damping, self.free_angle].map(S::constant);
        let [neg_stiffness, damping, free_angle] = numbers;
        self.law(x, v, [neg_stiffness, damping, free_angle, self.actuator.value(x, v, t)], out);
    }
    /// `stiffness`, `damping`, `actuator` when it is a number, and `free_angle` when the file
    /// gives it.
    fn data(&self) -> Vec<(&'static str, f64)> {
        let mut data = vec![("stiffness", self.stiffness), ("damping", self.damping)];
        data.extend(self.actuator.data("actuator"));
        self.free_angle_from.data(data, "free_angle", self.free_angle)
    }
    /// A free angle from the initial configuration is the bodies' relative angle at their held
    /// initial poses: a constant.
    fn load_data<S: Scalar>(&self, x: &[S], v: &[S], t: f64, data: &[S], params: &[S], out: &mut [S]) -> bool {
        let mut d = Data::new(data);
        let (neg_stiffness, damping) = (-d.next(), d.next());
        let actuator = self.actuator.value_data(x, v, t, &mut d, params);
        let free_angle = self.free_angle_from.value(d.all(), |[fi, fj]| fi.phi - fj.phi);
        self.law(x, v, [neg_stiffness, damping, free_angle, actuator], out);
        true
    }
    fn conservative(&self) -> bool {
        self.damping == 0.0 && self.actuator.is_zero()
    }
    fn potential<S: Scalar>(&self, x: &[S]) -> S {
        let e = self.i.pose(x)[2] - self.j.pose(x)[2] - S::constant(self.free_angle);
        S::constant(0.5 * self.stiffness) * e * e
    }
    /// `k (theta - theta0)^2 / 2` with the stiffness and the free angle from `data`.
    fn potential_data<S: Scalar>(&self, x: &[S], data: &[S], _params: &[S]) -> Option<S> {
        let free_angle = self.free_angle_from.value(data, |[fi, fj]| fi.phi - fj.phi);
        let e = self.i.pose(x)[2] - self.j.pose(x)[2] - free_angle;
        Some(S::constant(0.5) * data[0] * e * e)
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
    let (l0, from) = match free_length {
        Some(l) => (cx.non_negative(&format!("{path}.free_length"), *l)?, Source::File),
        None => (cx.initial_distance(ends), Source::start(i, j, cx.q0())),
    };
    let mut spring = SpringDamper::new(i.0, sp, j.0, sq, k, c, l0, act);
    spring.free_length_from = from;
    Some(Box::new(spring))
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
    let (theta0, from) = match free_angle {
        Some(a) => (cx.finite(&format!("{path}.free_angle"), *a)?, Source::File),
        None => (i.coords(cx.q0())[2] - j.coords(cx.q0())[2], Source::start(i, j, cx.q0())),
    };
    let mut spring = RotationalSpringDamper::new(i.0, j.0, k, c, theta0, act);
    spring.free_angle_from = from;
    Some(Box::new(spring))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::BodyIx;
    use crate::expr::Dual;
    use crate::forces::testing::{
        assert_data_fields, check_conservative, check_data, check_derivatives, expression, expression_with, Lcg,
    };

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

    /// The load over the data and the parameters (design sensitivities): each spring with an
    /// actuator that is an expression of a parameter, time and the state, or a number.
    #[test]
    fn load_over_data_and_parameters() {
        let params = [("c0", 1.5)];
        let act = expression_with("c0*sin(t) + 0.5*b0.vx*b1.omega", 2, &params);
        let s = SpringDamper::new(Some(0), [0.2, 0.1], Some(3), [-0.3, 0.4], 40.0, 2.5, 0.7, act.clone());
        let names = ["point_i[0]", "point_i[1]", "point_j[0]", "point_j[1]", "stiffness", "damping", "free_length"];
        assert_eq!(ForceLaw::data(&s).iter().map(|d| d.0).collect::<Vec<_>>(), names);
        check_data(&s, &[1.5], 25);
        assert_data_fields::<SpringDamperSpec>(&s);
        let g = SpringDamper::new(None, [1.0, -2.0], Some(3), [-0.3, 0.4], 40.0, 2.5, 0.7, Load::Constant(1.0));
        check_data(&g, &[1.5], 26);
        assert_data_fields::<SpringDamperSpec>(&g);
        let r = RotationalSpringDamper::new(Some(0), Some(3), 12.0, 0.8, 0.3, act);
        assert_eq!(ForceLaw::data(&r).iter().map(|d| d.0).collect::<Vec<_>>(), ["stiffness", "damping", "free_angle"]);
        check_data(&r, &[1.5], 27);
        assert_data_fields::<RotationalSpringDamperSpec>(&r);
        let rg = RotationalSpringDamper::new(Some(3), None, 12.0, 0.8, 0.3, Load::Constant(0.5));
        check_data(&rg, &[1.5], 28);
        assert_data_fields::<RotationalSpringDamperSpec>(&rg);
    }

    /// A free length the initial configuration gives is not a data slot: it is the points'
    /// distance at the held initial poses, so it follows the points as compiling again does.
    /// With body i at the origin and body j at (3, 0), both at angle 0, the points (a, 0) and
    /// (b, 0) are `3 + b - a` apart there: the load's derivative along `point_i[0]` is the central
    /// difference of springs built with `a` moved and that free length (step 1e-6, tolerance 1e-7
    /// of the load's scale, as [`check_data`]). A free angle from there is a constant.
    #[test]
    fn a_free_length_from_the_start_follows_the_points() {
        let q0 = [0.0, 0.0, 0.0, 3.0, 0.0, 0.0];
        let (i, j) = (BodyIx(Some(0)), BodyIx(Some(3)));
        let build = |a: f64| {
            let mut s =
                SpringDamper::new(i.0, [a, 0.0], j.0, [-0.25, 0.0], 40.0, 2.5, 3.0 - 0.25 - a, Load::Constant(0.0));
            s.free_length_from = Source::start(i, j, &q0);
            s
        };
        let s = build(0.5);
        assert!(ForceLaw::data(&s).iter().all(|d| d.0 != "free_length"), "no free_length slot");
        check_data(&s, &[], 29);
        let (x, v) = (Lcg::new(9).vec(6, -1.0, 1.0), Lcg::new(10).vec(6, -1.0, 1.0));
        let dual = |a: &[f64]| a.iter().map(|&a| Dual::constant(a)).collect::<Vec<_>>();
        let mut data = dual(&ForceLaw::data(&s).iter().map(|d| d.1).collect::<Vec<_>>());
        data[0].d = 1.0;
        let mut out = vec![Dual::constant(0.0); 6];
        assert!(ForceLaw::load_data(&s, &dual(&x), &dual(&v), 0.0, &data, &[], &mut out));
        let h = 1e-6;
        let (mut up, mut down) = ([0.0; 6], [0.0; 6]);
        ForceLaw::load(&build(0.5 + h), &x, &v, 0.0, &mut up);
        ForceLaw::load(&build(0.5 - h), &x, &v, 0.0, &mut down);
        let scale = 1.0 + out.iter().fold(0.0f64, |a, o| a.max(o.v.abs()));
        for r in 0..6 {
            let fd = (up[r] - down[r]) / (2.0 * h);
            assert!((out[r].d - fd).abs() < 1e-7 * scale, "Q[{r}]: {} vs {fd}", out[r].d);
        }
        let mut r = RotationalSpringDamper::new(i.0, j.0, 12.0, 0.8, 0.0, Load::Constant(0.0));
        r.free_angle_from = Source::start(i, j, &q0);
        assert!(ForceLaw::data(&r).iter().all(|d| d.0 != "free_angle"), "no free_angle slot");
        check_data(&r, &[], 30);
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
