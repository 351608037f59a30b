//! Coulomb friction in revolute and translational joints, as Adams' joint `FRICTION`: a force
//! opposing the joints' relative motion, proportional to the load the joint carries, which is its
//! reaction ([`super::reaction`], from the multipliers). docs/model-format.md, "Joint friction".
//!
//! ```text
//! coefficient    mu_e(v) = mu tanh(v / v_s)              v_s: the transition velocity
//! revolute       v = r (omega_i - omega_j)               sliding speed on the pin's surface
//!                N = |F|                                 F: the reaction force
//!                T = -mu_e(v) r N        on body i;  -T on body j
//! translational  v = u . d' + omega_i n . d = d(u . d)/dt    sliding velocity of Q (body j) on body i
//!                N = |F| + |M_Q| / L                     F: the reaction force (normal to the axis),
//!                                                        M_Q: its moment about Q, L: the block length
//!                f = mu_e(v) N           on body i along u, at Q;  -f on body j along u, at Q
//! ```
//! with `u = A_i u'` the unit axis, `n = R90 u`, `d = r_Q - r_P`. Both dissipate: their power is
//! `-mu_e(v) N v <= 0` (`N r` in place of `N` for the pin).
//!
//! The smooth coefficient (`tanh`, C-infinity and odd) replaces the jump of the sign function at
//! zero velocity, so that the equations of motion stay smooth for the integrators' Newton
//! iterations. Its price is creep: a joint below its sticking limit does not stick but slides at
//! the velocity where `mu_e(v)` balances the load, `v = v_s atanh(mu_needed / mu)`, which is below
//! `v_s` while the load asks for less than `0.76 mu` (`tanh 1`), and grows only as the load nears
//! the limit.
//!
//! The bending moment's share `|M_Q| / L` is Adams' (its `FRICTION` statement: "the joint's bending
//! moment is divided by [the] overlap to compute the bending moment's contribution to frictional
//! forces"): a block of length `L` carries a couple `M` by two opposite contact forces `M / L` at
//! its ends. It is taken about `Q`, the sliding body's point, which is the block's centre.

use super::{difference, dot, perp, reaction_about, unit, vector, Anchor, BodyIx, Config, Frame, Pose};
use super::{AXIS_I, POINT_I, POINT_J};
use crate::expr::{Dual, Scalar};

/// The friction law of a joint: its coefficient and transition velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionLaw {
    /// Coefficient of friction, `>= 0`.
    pub mu: f64,
    /// Transition velocity `v_s`, m/s, `> 0`.
    pub transition_velocity: f64,
}

/// Where and how a joint's friction acts.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Contact {
    /// A pin of `radius` (m); its reaction is taken about the joint's anchor.
    Pin { anchor: Anchor, radius: f64 },
    /// A block of `length` (m) centred at `s_q` of body j, sliding on body i's line through `s_p`
    /// along `axis` (body i frame, as given) whose unit is `u`.
    Slide { i: BodyIx, s_p: [f64; 2], axis: [f64; 2], u: [f64; 2], j: BodyIx, s_q: [f64; 2], length: f64 },
}

/// The friction of one revolute or translational joint (built by [`super::Revolute::friction`]
/// and [`super::Translational::friction`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Friction {
    law: FrictionLaw,
    contact: Contact,
}

/// The numbers a friction's law reads, over any [`Scalar`]: its coefficient, transition velocity
/// and size (the pin's radius, the block's length), and a slider's line (`s_p`, the unit axis
/// `u`, body i frame) and block centre (`s_q`, body j frame); the pin reads no point.
struct Numbers<S> {
    mu: S,
    v_s: S,
    size: S,
    line: [[S; 2]; 3],
}

/// The data name of a friction's coefficient (its own numbers come after a slider's points and
/// axis).
const FRICTION_MU: &str = "friction.mu";
/// The data name of a friction's transition velocity.
const FRICTION_VS: &str = "friction.transition_velocity";

impl Friction {
    /// Friction in a pin of `radius` whose reaction is reported at `anchor`.
    pub(crate) fn pin(law: FrictionLaw, anchor: Anchor, radius: f64) -> Friction {
        Friction { law, contact: Contact::Pin { anchor, radius } }
    }

    /// Friction in a slider: the block of `length` centred at `s_q` of body j on the line of body i
    /// through `s_p` along `axis` (not zero; its unit is taken).
    pub(crate) fn slide(
        law: FrictionLaw,
        (i, s_p, axis): (BodyIx, [f64; 2], [f64; 2]),
        (j, s_q): (BodyIx, [f64; 2]),
        length: f64,
    ) -> Friction {
        Friction { law, contact: Contact::Slide { i, s_p, axis, u: unit(axis), j, s_q, length } }
    }

    /// The numbers of this friction that a parameter can move, each named as its field in the
    /// joint's entry (design sensitivities, docs/sensitivities.md): a slider's `point_i`,
    /// `point_j` and `axis_i` (its line and block centre, the joint's own numbers), then
    /// `friction.mu`, `friction.transition_velocity` and `friction.radius` (a pin) or
    /// `friction.length` (a slider). The order [`Friction::load_data`] reads them in.
    pub fn data(&self) -> Vec<(&'static str, f64)> {
        let law = [(FRICTION_MU, self.law.mu), (FRICTION_VS, self.law.transition_velocity)];
        match self.contact {
            Contact::Pin { radius, .. } => [law.as_slice(), &[("friction.radius", radius)]].concat(),
            Contact::Slide { s_p, axis, s_q, length, .. } => {
                let line = [vector(POINT_I, s_p), vector(POINT_J, s_q), vector(AXIS_I, axis)].concat();
                [line.as_slice(), &law, &[("friction.length", length)]].concat()
            }
        }
    }

    /// `(q, qdot, lambda) => (Q_f, value)`: the generalised friction force on the joint's `columns`
    /// (`out: (columns)`, body i's `(x, y, phi)` then body j's, ground left out) and the friction
    /// on body i (the torque of a pin, N m; the force along the axis of a slider, N). `block`: the
    /// joint's Jacobian at `q` (`rows x columns`); `v`: `qdot` on `columns`; `lambda`: the joint's
    /// multipliers. [`Friction::load_data`] with the friction's own numbers and `q` held.
    pub fn load<S: Scalar>(
        &self,
        q: &Config<'_>,
        columns: &[usize],
        block: &[f64],
        v: &[S],
        lambda: &[S],
        out: &mut [S],
    ) -> S {
        let c = S::constant;
        let (i, j, line) = match self.contact {
            Contact::Pin { anchor, .. } => (anchor.i, anchor.j, [[0.0; 2]; 3]),
            Contact::Slide { i, s_p, u, j, s_q, .. } => (i, j, [s_p, u, s_q]),
        };
        let poses = [Pose::frame(&Frame::of(i, q)), Pose::frame(&Frame::of(j, q))];
        let numbers = Numbers {
            mu: c(self.law.mu),
            v_s: c(self.law.transition_velocity),
            size: c(self.size()),
            line: line.map(|p| p.map(c)),
        };
        self.law(poses, columns, |k| c(block[k]), v, lambda, numbers, out)
    }

    /// [`Friction::load`] over any [`Scalar`] in everything it reads (design sensitivities):
    /// all coordinates `q (n)`, `block(k)` the `k`-th entry of the joint's Jacobian block
    /// (row-major), `v` and `lambda` as there, and the friction's numbers `data` in the order of
    /// [`Friction::data`] (a slider's axis is normalised here, so that the derivative with
    /// respect to its raw components is right).
    #[allow(clippy::too_many_arguments)]
    pub fn load_data<S: Scalar>(
        &self,
        q: &[S],
        columns: &[usize],
        block: impl Fn(usize) -> S,
        v: &[S],
        lambda: &[S],
        data: &[S],
        out: &mut [S],
    ) -> S {
        let zero = [S::constant(0.0); 2];
        let (i, j, line, law) = match self.contact {
            Contact::Pin { anchor, .. } => (anchor.i, anchor.j, [zero; 3], data),
            Contact::Slide { i, j, .. } => {
                let at = |k: usize| [data[k], data[k + 1]];
                (i, j, [at(0), unit(at(4)), at(2)], &data[6..])
            }
        };
        let numbers = Numbers { mu: law[0], v_s: law[1], size: law[2], line };
        self.law([Pose::of(i, q), Pose::of(j, q)], columns, block, v, lambda, numbers, out)
    }

    /// The pin's radius or the block's length.
    fn size(&self) -> f64 {
        match self.contact {
            Contact::Pin { radius, .. } => radius,
            Contact::Slide { length, .. } => length,
        }
    }

    /// The law of [`Friction::load`] with body i's and body j's frames `poses` and the numbers
    /// `k`, everything over `S`.
    #[allow(clippy::too_many_arguments)]
    fn law<S: Scalar>(
        &self,
        [fi, fj]: [Pose<S>; 2],
        columns: &[usize],
        block: impl Fn(usize) -> S,
        v: &[S],
        lambda: &[S],
        k: Numbers<S>,
        out: &mut [S],
    ) -> S {
        let zero = S::constant(0.0);
        let coefficient = |speed: S| k.mu * (speed / k.v_s).tanh();
        let (i, j) = match self.contact {
            Contact::Pin { anchor, .. } => (anchor.i, anchor.j),
            Contact::Slide { i, j, .. } => (i, j),
        };
        // Body i's velocities at 0 when it moves; body j's after them.
        let at_j = if i.0.is_some() { 3 } else { 0 };
        let rates = |b: BodyIx, at: usize| if b.0.is_some() { [v[at], v[at + 1], v[at + 2]] } else { [zero; 3] };
        let (vi, vj) = (rates(i, 0), rates(j, at_j));
        let (on_i, on_j, value) = match self.contact {
            Contact::Pin { anchor, .. } => {
                // The force alone: its moment, about any point, is not read.
                let (f, _) = reaction_about(anchor, columns, block, lambda, [zero; 2]);
                let r = k.size;
                let torque = -coefficient(r * (vi[2] - vj[2])) * r * magnitude(f);
                ([zero, zero, torque], [zero, zero, -torque], torque)
            }
            Contact::Slide { .. } => {
                let [s_p, u, s_q] = k.line;
                let (u, a_p, a_q) = (fi.rotate(u), fi.rotate(s_p), fj.rotate(s_q));
                let d = difference(fi.o, a_p, fj.o, a_q);
                let n = perp(u);
                let r_q = [fj.o[0] + a_q[0], fj.o[1] + a_q[1]];
                // d' = r_j' + omega_j R90 A_j s'_Q - r_i' - omega_i R90 A_i s'_P.
                let (bp, bq) = (perp(a_p), perp(a_q));
                let rate = |k: usize| vj[k] + bq[k] * vj[2] - vi[k] - bp[k] * vi[2];
                let speed = u[0] * rate(0) + u[1] * rate(1) + vi[2] * dot(n, d);
                // The reaction's moment about Q, the lever from body i's centre (or from Q to
                // body j's centre when body i is ground) through Q seen in body i's frame.
                let anchor = Anchor { i, j, point: [0.0; 2] };
                let point = fi.local(r_q);
                let lever = match i.0 {
                    Some(_) => fi.rotate(point),
                    None => [fj.o[0] - point[0], fj.o[1] - point[1]],
                };
                let (f, moment) = reaction_about(anchor, columns, block, lambda, lever);
                let load = magnitude(f) + moment.abs() / k.size;
                let force = coefficient(speed) * load;
                let (fu, arm_i) = ([force * u[0], force * u[1]], [r_q[0] - fi.o[0], r_q[1] - fi.o[1]]);
                let cross = |a: [S; 2]| a[0] * fu[1] - a[1] * fu[0];
                ([fu[0], fu[1], cross(arm_i)], [-fu[0], -fu[1], -cross(a_q)], force)
            }
        };
        let mut k = 0;
        for (body, g) in [(i, on_i), (j, on_j)] {
            if body.0.is_some() {
                out[k..k + 3].copy_from_slice(&g);
                k += 3;
            }
        }
        value
    }

    /// The exact derivatives of [`Friction::load`] by the multipliers and the velocities (dual
    /// numbers, one pass per multiplier and per velocity): `by_lambda (columns x rows)` and
    /// `by_v (columns x columns)`, row-major, entry `[c * rows + r]` the derivative of `Q_f[c]`
    /// by `lambda[r]`. `work: (3 columns + rows)` dual scratch.
    #[allow(clippy::too_many_arguments)]
    pub fn derivatives(
        &self,
        q: &Config<'_>,
        columns: &[usize],
        block: &[f64],
        v: &[f64],
        lambda: &[f64],
        by_lambda: &mut [f64],
        by_v: &mut [f64],
        work: &mut [Dual],
    ) {
        let (w, rows) = (columns.len(), lambda.len());
        let (vd, rest) = work.split_at_mut(w);
        let (ld, rest) = rest.split_at_mut(rows);
        let out = &mut rest[..w];
        for (d, &x) in vd.iter_mut().zip(v) {
            *d = Dual::new(x, 0.0);
        }
        for (d, &x) in ld.iter_mut().zip(lambda) {
            *d = Dual::new(x, 0.0);
        }
        for r in 0..rows {
            ld[r].d = 1.0;
            self.load(q, columns, block, vd, ld, out);
            ld[r].d = 0.0;
            for c in 0..w {
                by_lambda[c * rows + r] = out[c].d;
            }
        }
        for k in 0..w {
            vd[k].d = 1.0;
            self.load(q, columns, block, vd, ld, out);
            vd[k].d = 0.0;
            for c in 0..w {
                by_v[c * w + k] = out[c].d;
            }
        }
    }
}

/// `|f|`, with derivative zero where `f = 0` (one of its one-sided choices; `sqrt`'s is infinite).
fn magnitude<S: Scalar>(f: [S; 2]) -> S {
    let squared = f[0] * f[0] + f[1] * f[1];
    if squared.value() > 0.0 {
        squared.sqrt()
    } else {
        S::constant(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::Lcg;
    use crate::constraints::{ConfigBuf, Constraint, Revolute, Translational};

    fn law() -> FrictionLaw {
        FrictionLaw { mu: 0.3, transition_velocity: 0.05 }
    }

    /// The joint's friction at a random state, with the inputs it needs.
    struct Case {
        q: Vec<f64>,
        v: Vec<f64>,
        lambda: Vec<f64>,
        columns: Vec<usize>,
        block: Vec<f64>,
    }

    fn case(c: &dyn Constraint, rng: &mut Lcg, n: usize) -> Case {
        let q = rng.vec(n, -1.0, 1.0);
        let qdot = rng.vec(n, -1.0, 1.0);
        let columns = c.columns().to_vec();
        let mut block = vec![0.0; c.rows() * columns.len()];
        c.jacobian(&ConfigBuf::new(&q).view(), 0.0, &mut block);
        let v = columns.iter().map(|&k| qdot[k]).collect();
        Case { q, v, lambda: rng.vec(c.rows(), -50.0, 50.0), columns, block }
    }

    /// Central differences of `load` by each multiplier and velocity against [`Friction::derivatives`]:
    /// the step `1e-6` (relative to inputs of order 1 and 50) leaves a truncation error of
    /// `~1e-12` of the third derivative and a round-off of `~1e-16 / 1e-6 = 1e-10` of the values
    /// (forces of order 10), so `1e-6` absolute plus `1e-6` relative holds with a margin of 100
    /// while a wrong term (a missing chain factor) errs by its whole size.
    fn check(friction: &Friction, c: &Case) {
        let config = ConfigBuf::new(&c.q);
        let (w, rows) = (c.columns.len(), c.lambda.len());
        let (mut by_l, mut by_v) = (vec![0.0; w * rows], vec![0.0; w * w]);
        let mut work = vec![Dual::new(0.0, 0.0); 2 * w + rows];
        friction.derivatives(&config.view(), &c.columns, &c.block, &c.v, &c.lambda, &mut by_l, &mut by_v, &mut work);
        let eval = |v: &[f64], l: &[f64]| {
            let mut out = vec![0.0; w];
            friction.load(&config.view(), &c.columns, &c.block, v, l, &mut out);
            out
        };
        let h = 1e-6;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 + 1e-6 * b.abs();
        for r in 0..rows {
            let (mut lp, mut lm) = (c.lambda.clone(), c.lambda.clone());
            lp[r] += h;
            lm[r] -= h;
            let (p, m) = (eval(&c.v, &lp), eval(&c.v, &lm));
            for k in 0..w {
                let fd = (p[k] - m[k]) / (2.0 * h);
                assert!(close(by_l[k * rows + r], fd), "d Q[{k}] / d lambda[{r}]: {} vs {fd}", by_l[k * rows + r]);
            }
        }
        for col in 0..w {
            let (mut vp, mut vm) = (c.v.clone(), c.v.clone());
            vp[col] += h;
            vm[col] -= h;
            let (p, m) = (eval(&vp, &c.lambda), eval(&vm, &c.lambda));
            for k in 0..w {
                let fd = (p[k] - m[k]) / (2.0 * h);
                assert!(close(by_v[k * w + col], fd), "d Q[{k}] / d v[{col}]: {} vs {fd}", by_v[k * w + col]);
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let mut rng = Lcg::new(41);
        for _ in 0..20 {
            let pin = Revolute::new(BodyIx(Some(0)), [0.3, -0.2], BodyIx(Some(3)), [-0.4, 0.1]);
            check(&pin.friction(law(), 0.02), &case(&pin, &mut rng, 6));
            let grounded = Revolute::new(BodyIx::GROUND, [0.5, -0.2], BodyIx(Some(0)), [-0.4, 0.1]);
            check(&grounded.friction(law(), 0.02), &case(&grounded, &mut rng, 3));
            let slide =
                Translational::new(BodyIx(Some(0)), [0.3, -0.2], [1.0, 2.0], BodyIx(Some(3)), [-0.4, 0.1], [0.0, -3.0]);
            check(&slide.friction(law(), 0.1), &case(&slide, &mut rng, 6));
            let guide =
                Translational::new(BodyIx::GROUND, [0.5, -2.0], [2.0, 1.0], BodyIx(Some(0)), [0.7, 0.1], [1.0, 1.0]);
            check(&guide.friction(law(), 0.1), &case(&guide, &mut rng, 3));
        }
    }

    /// [`Friction::load_data`] over its own data is [`Friction::load`] (to 1e-14 of the load: it
    /// normalises the axis and computes the rotations again, each to round-off), and its
    /// [`Dual`] derivative along each datum and each coordinate (the Jacobian block held, as the
    /// law reads it) against central differences of its `f64` values, step `1e-6` of the input's
    /// size (truncation `~1e-12`, round-off `~1e-10` of loads of order 10; `1e-6` absolute plus
    /// relative, as [`check`]). Returns, for each datum, whether it moved the load here: a datum
    /// the law does not read (its constant used instead) moves nothing anywhere.
    fn check_data(friction: &Friction, c: &Case) -> Vec<bool> {
        let data: Vec<f64> = friction.data().iter().map(|&(_, v)| v).collect();
        let w = c.columns.len();
        let eval = |q: &[f64], d: &[f64]| {
            let mut out = vec![0.0; w];
            let value = friction.load_data(q, &c.columns, |k| c.block[k], &c.v, &c.lambda, d, &mut out);
            out.push(value);
            out
        };
        let mut plain = vec![0.0; w];
        let value = friction.load(&ConfigBuf::new(&c.q).view(), &c.columns, &c.block, &c.v, &c.lambda, &mut plain);
        plain.push(value);
        let scale = plain.iter().fold(1e-3f64, |m, x| m.max(x.abs()));
        for (a, b) in eval(&c.q, &data).iter().zip(&plain) {
            assert!((a - b).abs() <= 1e-14 * scale, "load_data {a} against load {b}");
        }
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 + 1e-6 * b.abs();
        let dual = |x: &[f64], k: Option<usize>| -> Vec<Dual> {
            x.iter().enumerate().map(|(i, &v)| Dual::new(v, f64::from(u8::from(Some(i) == k)))).collect()
        };
        let derivative = |qk: Option<usize>, dk: Option<usize>| {
            let (q, d) = (dual(&c.q, qk), dual(&data, dk));
            let (v, l): (Vec<Dual>, Vec<Dual>) = (
                c.v.iter().map(|&x| Dual::constant(x)).collect(),
                c.lambda.iter().map(|&x| Dual::constant(x)).collect(),
            );
            let mut out = vec![Dual::constant(0.0); w];
            let value = friction.load_data(&q, &c.columns, |k| Dual::constant(c.block[k]), &v, &l, &d, &mut out);
            out.iter().chain([&value]).map(|x| x.d).collect::<Vec<f64>>()
        };
        let moved = |x: &[f64], k: usize, by: f64| {
            let mut x = x.to_vec();
            x[k] += by;
            x
        };
        let mut moves = vec![false; data.len()];
        for k in 0..data.len() {
            let h = 1e-6 * data[k].abs().max(1e-3);
            let (up, down) = (eval(&c.q, &moved(&data, k, h)), eval(&c.q, &moved(&data, k, -h)));
            for (i, exact) in derivative(None, Some(k)).iter().enumerate() {
                let fd = (up[i] - down[i]) / (2.0 * h);
                assert!(close(*exact, fd), "d out[{i}] / d {}: {exact} vs {fd}", friction.data()[k].0);
                moves[k] |= *exact != 0.0;
            }
        }
        for k in 0..c.q.len() {
            let h = 1e-6;
            let (up, down) = (eval(&moved(&c.q, k, h), &data), eval(&moved(&c.q, k, -h), &data));
            for (i, exact) in derivative(Some(k), None).iter().enumerate() {
                let fd = (up[i] - down[i]) / (2.0 * h);
                assert!(close(*exact, fd), "d out[{i}] / d q[{k}]: {exact} vs {fd}");
            }
        }
        moves
    }

    #[test]
    fn load_data_is_the_load_with_its_derivatives_along_the_data_and_coordinates() {
        let mut rng = Lcg::new(43);
        let names = |f: &Friction| f.data().iter().map(|&(n, _)| n).collect::<Vec<_>>();
        let mut moved = [vec![false; 3], vec![false; 3], vec![false; 9], vec![false; 9]];
        let mut note = |k: usize, moves: Vec<bool>| moved[k].iter_mut().zip(moves).for_each(|(m, x)| *m |= x);
        for _ in 0..20 {
            let pin = Revolute::new(BodyIx(Some(0)), [0.3, -0.2], BodyIx(Some(3)), [-0.4, 0.1]);
            note(0, check_data(&pin.friction(law(), 0.02), &case(&pin, &mut rng, 6)));
            let grounded = Revolute::new(BodyIx::GROUND, [0.5, -0.2], BodyIx(Some(0)), [-0.4, 0.1]);
            note(1, check_data(&grounded.friction(law(), 0.02), &case(&grounded, &mut rng, 3)));
            let slide =
                Translational::new(BodyIx(Some(0)), [0.3, -0.2], [1.0, 2.0], BodyIx(Some(3)), [-0.4, 0.1], [0.0, -3.0]);
            note(2, check_data(&slide.friction(law(), 0.1), &case(&slide, &mut rng, 6)));
            let guide =
                Translational::new(BodyIx::GROUND, [0.5, -2.0], [2.0, 1.0], BodyIx(Some(0)), [0.7, 0.1], [1.0, 1.0]);
            note(3, check_data(&guide.friction(law(), 0.1), &case(&guide, &mut rng, 3)));
        }
        // Every datum moves the load, but a ground guide's `point_i`: the block's speed along a
        // line that does not turn is that of its centre, wherever the line passes.
        let still = |k: usize, d: usize| k == 3 && d < 2;
        for (k, moves) in moved.iter().enumerate() {
            for (d, &m) in moves.iter().enumerate() {
                assert_eq!(m, !still(k, d), "case {k}, datum {d}: {moved:?}");
            }
        }
        let pin = Revolute::new(BodyIx::GROUND, [0.5, -0.2], BodyIx(Some(0)), [-0.4, 0.1]).friction(law(), 0.02);
        assert_eq!(names(&pin), ["friction.mu", "friction.transition_velocity", "friction.radius"]);
        let guide =
            Translational::new(BodyIx::GROUND, [0.5, -2.0], [2.0, 1.0], BodyIx(Some(0)), [0.7, 0.1], [1.0, 1.0]);
        assert_eq!(
            names(&guide.friction(law(), 0.1)),
            [
                "point_i[0]",
                "point_i[1]",
                "point_j[0]",
                "point_j[1]",
                "axis_i[0]",
                "axis_i[1]",
                "friction.mu",
                "friction.transition_velocity",
                "friction.length"
            ]
        );
    }

    /// Hand-derived: a pin between ground and a wheel turning at 2 rad/s, radius 0.01, reaction
    /// (3, 4) N on the ground (|F| = 5): torque on ground `-0.3 tanh(0.01 (0 - 2) / 0.05) 0.01 5`.
    /// A block on a ground guide along x, at `x = 0.4`, sliding at +0.2 m/s under a normal
    /// reaction of 10 N and a moment of 1 N m about its centre, length 0.5: load `10 + 2` N, force
    /// on the guide `+0.3 tanh(4) 12` along x (the guide is dragged along), on the block its opposite,
    /// with moment `-(0, 0) x ..` about its centre, which is the block's own.
    #[test]
    fn hand_derived() {
        let pin = Revolute::new(BodyIx::GROUND, [0.0, 0.0], BodyIx(Some(0)), [0.0, 0.0]);
        let q = [0.0, 0.0, 0.0];
        let config = ConfigBuf::new(&q);
        let mut block = vec![0.0; 6];
        pin.jacobian(&config.view(), 0.0, &mut block);
        // The reaction on ground is the opposite of that on the wheel, -Phi_q,j^T lambda = lambda
        // (Phi_q,j = -I): lambda = (-3, -4) puts (3, 4) on ground.
        let mut out = [0.0; 3];
        let t = pin.friction(law(), 0.01).load(
            &config.view(),
            pin.columns(),
            &block,
            &[0.0, 0.0, 2.0],
            &[-3.0, -4.0],
            &mut out,
        );
        let expect = -0.3 * (0.01f64 * -2.0 / 0.05).tanh() * 0.01 * 5.0;
        assert!((t - expect).abs() < 1e-15 && out[2] == -t && out[0] == 0.0, "{t} {out:?}");

        let guide = Translational::new(BodyIx::GROUND, [0.0, 0.0], [1.0, 0.0], BodyIx(Some(0)), [0.0, 0.0], [1.0, 0.0]);
        let q = [0.4, 0.0, 0.0];
        let config = ConfigBuf::new(&q);
        guide.jacobian(&config.view(), 0.0, &mut block);
        // Rows: line n . d = y_Q (gradient (0, 1, 0) on the block), angle -phi_j (0, 0, -1).
        // On the block g = -Phi_q^T lambda = (0, -l0, l1), a force through its centre Q and a
        // couple: on ground F = (0, l0), M_Q = -l1. lambda = (-10, 1): |F| = 10, M_Q = -1.
        let mut out = [0.0; 3];
        let f = guide.friction(law(), 0.5).load(
            &config.view(),
            guide.columns(),
            &block,
            &[0.2, 0.0, 0.0],
            &[-10.0, 1.0],
            &mut out,
        );
        let expect = 0.3 * 4f64.tanh() * 12.0;
        assert!((f - expect).abs() < 1e-13, "{f} vs {expect}");
        assert!((out[0] + expect).abs() < 1e-13 && out[1] == 0.0 && out[2].abs() < 1e-15, "{out:?}");
    }
}
