//! Belt or chain drive: two pulleys (or sprockets) of radii `r_i` and `r_j` coupled by a belt
//! that does not slip, on a carrier body `c` whose frame the pulleys turn in (ground by default;
//! a moving arm for a drive on a turning frame). One row, as Adams' COUPLER of two revolute
//! joints.
//!
//! ```text
//! sigma  = -1 open belt (the pulleys turn the same way), +1 crossed (opposite ways)
//! Phi    = r_i (phi_i - phi_c) + sigma r_j (phi_j - phi_c) - c0      (c0 from the initial configuration)
//! Phi_q  = [ 0 0 r_i   0 0 sigma r_j   0 0 -(r_i + sigma r_j) ]     (bodies i, j, c)
//! nu     = 0,   gamma = 0                                            (Phi is linear in q)
//! ```
//! Relative to the carrier the speed ratio `omega_j / omega_i` is `r_i / r_j` open and
//! `-r_i / r_j` crossed. The belt's generalised force on pulley `b` is `-Phi_q,b^T lambda`: the
//! torques `-r_i lambda` on pulley i and `-sigma r_j lambda` on pulley j, the pull of the belt's
//! tight side less its slack side, `F_tight - F_slack = -lambda`, at each radius. The pulleys'
//! centres are kept by other joints (usually revolute joints on the carrier).

use super::schema::JointContext;
use super::{phi_tri_generic, At, GenericPhi};
use super::{Anchor, BodyIx, CompiledJoint, Config, Constraint};
use crate::expr::Scalar;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Two pulleys coupled by a belt or chain that does not slip, turning in the frame of a carrier.
#[derive(Debug, Clone)]
pub struct Belt {
    /// Pulley i, pulley j and the carrier.
    bodies: [BodyIx; 3],
    /// `Phi_q` on each body's angle: `r_i`, `sigma r_j`, `-(r_i + sigma r_j)`.
    coefficients: [f64; 3],
    /// `c0`.
    c0: f64,
    /// The coordinates of the bodies that move, three a body.
    columns: Vec<usize>,
    /// `sigma`.
    sigma: f64,
    /// The bodies' angles in the initial configuration, which fixes `c0` (held: not data).
    start: [f64; 3],
}

impl Belt {
    /// The belt from pulley `i` (radius `r_i`) to pulley `j` (radius `r_j`), `crossed` or open,
    /// turning in the frame of `carrier`; it holds at the initial configuration `q0`.
    pub fn new(i: BodyIx, r_i: f64, j: BodyIx, r_j: f64, crossed: bool, carrier: BodyIx, q0: &[f64]) -> Belt {
        let sigma = if crossed { 1.0 } else { -1.0 };
        let coefficients = [r_i, sigma * r_j, -(r_i + sigma * r_j)];
        let bodies = [i, j, carrier];
        let columns = bodies.iter().filter_map(|b| b.0).flat_map(|k| [k, k + 1, k + 2]).collect();
        let start = bodies.map(|b| b.coords(q0)[2]);
        let mut belt = Belt { bodies, coefficients, c0: 0.0, columns, sigma, start };
        belt.c0 = belt.value(q0);
        belt
    }

    /// `r_i (phi_i - phi_c) + sigma r_j (phi_j - phi_c)` over any [`Scalar`] at the bodies'
    /// `angles`, with the radii `data`.
    fn value_of<S: Scalar>(&self, angles: [S; 3], data: &[S]) -> S {
        let (r_i, r_j) = (data[0], S::constant(self.sigma) * data[1]);
        r_i * angles[0] + r_j * angles[1] + -(r_i + r_j) * angles[2]
    }

    /// `r_i (phi_i - phi_c) + sigma r_j (phi_j - phi_c)` at `q`.
    #[inline]
    fn value(&self, q: &[f64]) -> f64 {
        self.bodies.iter().zip(self.coefficients).map(|(b, k)| k * b.coords(q)[2]).sum()
    }
}

impl Constraint for Belt {
    fn anchor(&self) -> Anchor {
        Anchor { i: self.bodies[0], j: self.bodies[1], point: [0.0; 2] }
    }
    fn row_names(&self) -> &[&'static str] {
        &["belt"]
    }
    fn columns(&self) -> &[usize] {
        &self.columns
    }
    fn phi(&self, q: &Config<'_>, _t: f64, out: &mut [f64]) {
        out[0] = self.value(q) - self.c0;
    }
    fn jacobian(&self, _q: &Config<'_>, _t: f64, out: &mut [f64]) {
        let moving = self.bodies.iter().zip(self.coefficients).filter(|(b, _)| b.0.is_some());
        for (block, (_, k)) in out.chunks_exact_mut(3).zip(moving) {
            block.copy_from_slice(&[0.0, 0.0, k]);
        }
    }
    fn gamma(&self, _q: &Config<'_>, _qdot: &[f64], _t: f64, out: &mut [f64]) {
        out[0] = 0.0;
    }
    /// `radius_i`, `radius_j` (`c0` follows them; the initial angles that fix it are held).
    fn data(&self) -> Vec<(&'static str, f64)> {
        vec![("radius_i", self.coefficients[0]), ("radius_j", self.sigma * self.coefficients[1])]
    }
    phi_tri_generic!();
}

impl GenericPhi for Belt {
    fn parameters(&self) -> &[usize] {
        &[]
    }
    fn phi_generic<S: Scalar>(&self, at: &At<'_, S>, data: &[S], out: &mut [S]) {
        let angles = self.bodies.map(|b| b.pose(at.q)[2]);
        out[0] = self.value_of(angles, data) - self.value_of(self.start.map(S::constant), data);
    }
}

/// Belt or chain drive: the pulleys `body_i` (radius `radius_i`) and `body_j` (radius
/// `radius_j`) turn in the frame of `carrier` as a belt that does not slip couples them,
/// `radius_i (phi_i - phi_c) -/+ radius_j (phi_j - phi_c)` constant (`-` open, `+` crossed).
/// The pulleys' centres must be kept by other joints. 1 equation.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BeltJoint {
    /// The first pulley (its reaction is reported: the belt's torque on it).
    pub body_i: String,
    /// Pitch radius of the first pulley, m.
    pub radius_i: f64,
    /// The second pulley.
    pub body_j: String,
    /// Pitch radius of the second pulley, m.
    pub radius_j: f64,
    /// True for a crossed belt, the pulleys turning opposite ways. Default: false, an open belt
    /// (or a chain), the pulleys turning the same way.
    #[serde(default)]
    pub crossed: bool,
    /// The body the pulleys turn in, whose angle their rotations are measured from. Default:
    /// ground.
    #[serde(default)]
    pub carrier: Option<String>,
}

/// A belt joint at `path` compiled in `cx`.
pub(crate) fn compile(spec: &BeltJoint, cx: &mut impl JointContext, path: &str) -> Option<CompiledJoint> {
    let BeltJoint { body_i, radius_i, body_j, radius_j, crossed, carrier } = spec;
    let i = cx.body(&format!("{path}.body_i"), body_i);
    let j = cx.body(&format!("{path}.body_j"), body_j);
    let carrier = carrier.as_deref().unwrap_or("ground");
    let c = cx.body(&format!("{path}.carrier"), carrier);
    let r_i = cx.positive(&format!("{path}.radius_i"), *radius_i);
    let r_j = cx.positive(&format!("{path}.radius_j"), *radius_j);
    if body_i == body_j {
        cx.problem(format!("{path}.body_j"), format!("a joint needs two different bodies, found '{body_i}' twice"));
        return None;
    }
    if carrier == body_i || carrier == body_j {
        let message = format!("the carrier '{carrier}' is a pulley; expected the body both pulleys turn in");
        cx.problem(format!("{path}.carrier"), message);
        return None;
    }
    let belt = Belt::new(i?, r_i?, j?, r_j?, *crossed, c?, cx.q0());
    Some((Box::new(belt), None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::testing::{
        assert_data_fields, check_fd_random, check_generic_random, check_rebuilt, evaluate, Lcg,
    };

    #[test]
    fn derivatives_match_finite_differences() {
        let q0 = Lcg::new(2).vec(9, -2.0, 2.0);
        for (seed, crossed) in [false, true].into_iter().enumerate() {
            let seed = seed as u64;
            let (i, j, c) = (BodyIx(Some(0)), BodyIx(Some(3)), BodyIx(Some(6)));
            let moving = Belt::new(i, 0.2, j, 0.5, crossed, c, &q0);
            check_fd_random(&moving, 3, seed);
            check_generic_random(&moving, 3, seed);
            check_rebuilt(&moving, &|d| Belt::new(i, d[0], j, d[1], crossed, c, &q0), 3, seed);
            assert_data_fields::<BeltJoint>(&moving);
            let fixed = Belt::new(BodyIx(Some(3)), 0.2, BodyIx(Some(0)), 0.5, crossed, BodyIx::GROUND, &q0[..6]);
            check_fd_random(&fixed, 2, seed);
            check_generic_random(&fixed, 2, seed);
        }
    }

    /// Hand-derived: open belt, r_i = 0.2, r_j = 0.5, carrier at 0.1 rad; at q0 the pulleys are at
    /// 0.3 and -0.4 rad: c0 = 0.2 (0.3 - 0.1) - 0.5 (-0.4 - 0.1) = 0.04 + 0.25 = 0.29. Turning
    /// pulley i by 0.5 rad gives Phi = 0.2 * 0.5 = 0.1; the Jacobian on the angles is
    /// (0.2, -0.5, 0.3).
    #[test]
    fn hand_derived_open_belt_on_a_carrier() {
        let q0 = [0.0, 0.0, 0.3, 1.0, 0.0, -0.4, 0.5, 0.5, 0.1];
        let belt = Belt::new(BodyIx(Some(0)), 0.2, BodyIx(Some(3)), 0.5, false, BodyIx(Some(6)), &q0);
        assert!((belt.c0 - 0.29).abs() < 1e-15, "{}", belt.c0);
        let mut q = q0;
        q[2] += 0.5;
        let (phi, jac, gamma) = evaluate(&belt, &q, &[1.0; 9]);
        assert!((phi[0] - 0.1).abs() < 1e-15, "{phi:?}");
        let want = [0.0, 0.0, 0.2, 0.0, 0.0, -0.5, 0.0, 0.0, 0.3];
        assert!(jac.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-15), "{jac:?}");
        assert_eq!(gamma, [0.0]);
    }
}
