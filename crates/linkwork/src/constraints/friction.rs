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

use super::{dot, perp, reaction, Anchor, BodyIx, Config, Frame, Separation};
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
    /// along the unit `u` (body i frame).
    Slide { i: BodyIx, s_p: [f64; 2], u: [f64; 2], j: BodyIx, s_q: [f64; 2], length: f64 },
}

/// The friction of one revolute or translational joint (built by [`super::Revolute::friction`]
/// and [`super::Translational::friction`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Friction {
    law: FrictionLaw,
    contact: Contact,
}

impl Friction {
    /// Friction in a pin of `radius` whose reaction is reported at `anchor`.
    pub(crate) fn pin(law: FrictionLaw, anchor: Anchor, radius: f64) -> Friction {
        Friction { law, contact: Contact::Pin { anchor, radius } }
    }

    /// Friction in a slider: the block of `length` centred at `s_q` of body j on the line of body i
    /// through `s_p` along `u` (unit).
    pub(crate) fn slide(
        law: FrictionLaw,
        (i, s_p, u): (BodyIx, [f64; 2], [f64; 2]),
        (j, s_q): (BodyIx, [f64; 2]),
        length: f64,
    ) -> Friction {
        Friction { law, contact: Contact::Slide { i, s_p, u, j, s_q, length } }
    }

    /// `(q, qdot, lambda) => (Q_f, value)`: the generalised friction force on the joint's `columns`
    /// (`out: (columns)`, body i's `(x, y, phi)` then body j's, ground left out) and the friction
    /// on body i (the torque of a pin, N m; the force along the axis of a slider, N). `block`: the
    /// joint's Jacobian at `q` (`rows x columns`); `v`: `qdot` on `columns`; `lambda`: the joint's
    /// multipliers.
    pub fn load<S: Scalar>(
        &self,
        q: &Config<'_>,
        columns: &[usize],
        block: &[f64],
        v: &[S],
        lambda: &[S],
        out: &mut [S],
    ) -> S {
        let zero = S::constant(0.0);
        let mu = S::constant(self.law.mu);
        let coefficient = |speed: S| mu * (speed / S::constant(self.law.transition_velocity)).tanh();
        let (i, j) = match self.contact {
            Contact::Pin { anchor, .. } => (anchor.i, anchor.j),
            Contact::Slide { i, j, .. } => (i, j),
        };
        // Body i's velocities at 0 when it moves; body j's after them.
        let at_j = if i.0.is_some() { 3 } else { 0 };
        let rates = |b: BodyIx, at: usize| if b.0.is_some() { [v[at], v[at + 1], v[at + 2]] } else { [zero; 3] };
        let (vi, vj) = (rates(i, 0), rates(j, at_j));
        let (on_i, on_j, value) = match self.contact {
            Contact::Pin { anchor, radius } => {
                let (f, _) = reaction(anchor, columns, block, lambda, q);
                let r = S::constant(radius);
                let torque = -coefficient(r * (vi[2] - vj[2])) * r * magnitude(f);
                ([zero, zero, torque], [zero, zero, -torque], torque)
            }
            Contact::Slide { s_p, u, s_q, length, .. } => {
                let (fi, fj) = (Frame::of(i, q), Frame::of(j, q));
                let (u, sep) = (fi.rotate(u), Separation::of(i, s_p, j, s_q, q));
                let n = perp(u);
                let r_q = fj.point(s_q);
                // d' = r_j' + omega_j R90 A_j s'_Q - r_i' - omega_i R90 A_i s'_P.
                let (bp, bq) = (perp(sep.a_p), perp(sep.a_q));
                let rate = |k: usize| vj[k] + S::constant(bq[k]) * vj[2] - vi[k] - S::constant(bp[k]) * vi[2];
                let speed =
                    S::constant(u[0]) * rate(0) + S::constant(u[1]) * rate(1) + vi[2] * S::constant(dot(n, sep.d));
                let anchor = Anchor { i, j, point: fi.local(r_q) };
                let (f, moment) = reaction(anchor, columns, block, lambda, q);
                let load = magnitude(f) + moment.abs() / S::constant(length);
                let force = coefficient(speed) * load;
                let (fu, arm_i) =
                    ([force * S::constant(u[0]), force * S::constant(u[1])], [r_q[0] - fi.x, r_q[1] - fi.y]);
                let cross = |a: [f64; 2]| S::constant(a[0]) * fu[1] - S::constant(a[1]) * fu[0];
                ([fu[0], fu[1], cross(arm_i)], [-fu[0], -fu[1], -cross(sep.a_q)], force)
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
