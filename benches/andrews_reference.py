"""Andrews' squeezing mechanism at t = 0.03 s, solved independently of Linkwork.

The Bari test set's published end state (andrews.f, `solut`: PSIDE at 1e-14) is good to about 9.6
significant digits, not the 16 it prints. This script shows it: it integrates the test set's own
equations (seven relative angles, its mass matrix, forces and six position constraints, the
`andrews` problem of Hairer and Wanner's "Solving ODEs II", VII.7) written as an ODE, the
constraints differentiated twice, with three unrelated integrators of SciPy (DOP853, Radau,
LSODA) at tolerances near the double-precision limit. They agree with one another to about 11.5
digits, and all three lie 9.6 digits from the published values (in gamma, the smallest angle).
Linkwork's `ANDREWS_END_CONVERGED` (crates/linkwork/tests/common/references.rs) is the DOP853 row.

    pip install '.[reference]' && python benches/andrews_reference.py

Prints each integrator's end state, its relative difference from the DOP853 row per angle, and
the significant digits of the published values measured against that row.
"""

from collections.abc import Callable
from typing import Any

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

# The test set's parameters (andrews.f, SI units).
m1, m2, m3, m4, m5, m6, m7 = 0.04325, 0.00365, 0.02373, 0.00706, 0.07050, 0.00706, 0.05498
i1, i2, i3, i4, i5, i6, i7 = 2.194e-6, 4.410e-7, 5.255e-6, 5.667e-7, 1.169e-5, 5.667e-7, 1.912e-5
xa, ya, xb, yb, xc, yc = -0.06934, -0.00227, -0.03635, 0.03273, 0.014, 0.072
d, da, e, ea, rr, ra = 28e-3, 115e-4, 2e-2, 1421e-5, 7e-3, 92e-5
ss, sa, sb, sc, sd = 35e-3, 1874e-5, 1043e-5, 18e-3, 2e-2
ta, tb, u, ua, ub = 2308e-5, 916e-5, 4e-2, 1228e-5, 449e-5
zf, zt, fa, mom, c0, lo = 2e-2, 4e-2, 1421e-5, 0.033, 4530.0, 0.07785

START = [-0.0617138900142764496358948458001, 0.0, 0.455279819163070380255912382449,
         0.222668390165885884674473185609, 0.487364979543842550225598953530,
         -0.222668390165885884674473185609, 1.23054744454982119249735015568]
PUBLISHED = [0.1581077119629904e2, -0.1575637105984298e2, 0.4082224013073101e-1, -0.5347301163226948,
             0.5244099658805304, 0.5347301163226948, 0.1048080741042263e1]
NAMES = ["beta", "Theta", "gamma", "Phi", "delta", "Omega", "epsilon"]


def equations() -> list[Callable[..., Any]]:
    """Mass matrix, forces, constraint Jacobian and the constraints' acceleration term, as
    numerical functions of the angles q and rates v."""
    q = sp.symbols("be th ga ph de om ep")
    v = sp.symbols("bep thp gap php dep omp epp")
    be, th, ga, ph, de, om, ep = q
    bep, thp, gap, php, dep, omp, epp = v
    cos, sin = sp.cos, sp.sin
    g = sp.Matrix([
        rr * cos(be) - d * cos(be + th) - ss * sin(ga) - xb,
        rr * sin(be) - d * sin(be + th) + ss * cos(ga) - yb,
        rr * cos(be) - d * cos(be + th) - e * sin(ph + de) - zt * cos(de) - xa,
        rr * sin(be) - d * sin(be + th) + e * cos(ph + de) - zt * sin(de) - ya,
        rr * cos(be) - d * cos(be + th) - zf * cos(om + ep) - u * sin(ep) - xa,
        rr * sin(be) - d * sin(be + th) - zf * sin(om + ep) + u * cos(ep) - ya,
    ])
    jac = g.jacobian(q)
    # g'' = G q'' + (G v)_q v = 0, so G q'' = -(G v)_q v.
    gamma = -(jac * sp.Matrix(v)).jacobian(q) * sp.Matrix(v)
    m = sp.zeros(7, 7)
    m[0, 0] = m1 * ra**2 + m2 * (rr**2 - 2 * da * rr * cos(th) + da**2) + i1 + i2
    m[1, 0] = m[0, 1] = m2 * (da**2 - da * rr * cos(th)) + i2
    m[1, 1] = m2 * da**2 + i2
    m[2, 2] = m3 * (sa**2 + sb**2) + i3
    m[3, 3] = m4 * (e - ea) ** 2 + i4
    m[4, 3] = m[3, 4] = m4 * ((e - ea) ** 2 + zt * (e - ea) * sin(ph)) + i4
    m[4, 4] = m4 * (zt**2 + 2 * zt * (e - ea) * sin(ph) + (e - ea) ** 2) + m5 * (ta**2 + tb**2) + i4 + i5
    m[5, 5] = m6 * (zf - fa) ** 2 + i6
    m[6, 5] = m[5, 6] = m6 * ((zf - fa) ** 2 - u * (zf - fa) * sin(om)) + i6
    m[6, 6] = m6 * ((zf - fa) ** 2 - 2 * u * (zf - fa) * sin(om) + u**2) + m7 * (ua**2 + ub**2) + i6 + i7
    xd, yd = sd * cos(ga) + sc * sin(ga) + xb, sd * sin(ga) - sc * cos(ga) + yb
    length = sp.sqrt((xd - xc) ** 2 + (yd - yc) ** 2)
    force = -c0 * (length - lo) / length
    fx, fy = force * (xd - xc), force * (yd - yc)
    f = sp.Matrix([
        mom - m2 * da * rr * thp * (thp + 2 * bep) * sin(th),
        m2 * da * rr * bep**2 * sin(th),
        fx * (sc * cos(ga) - sd * sin(ga)) + fy * (sd * cos(ga) + sc * sin(ga)),
        m4 * zt * (e - ea) * dep**2 * cos(ph),
        -m4 * zt * (e - ea) * php * (php + 2 * dep) * cos(ph),
        -m6 * u * (zf - fa) * epp**2 * cos(om),
        m6 * u * (zf - fa) * omp * (omp + 2 * epp) * cos(om),
    ])
    return [sp.lambdify(args, expr, "numpy") for args, expr in [([q], m), ([q, v], f), ([q], jac), ([q, v], gamma)]]


def main() -> None:
    mass, force, jacobian, gamma = equations()

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        q, v = y[:7], y[7:]
        jac = np.array(jacobian(q), float)
        kkt = np.zeros((13, 13))
        kkt[:7, :7], kkt[:7, 7:], kkt[7:, :7] = mass(q), jac.T, jac
        b = np.concatenate([np.array(force(q, v), float).ravel(), np.array(gamma(q, v), float).ravel()])
        return np.concatenate([v, np.linalg.solve(kkt, b)[:7]])

    y0 = np.array(START + [0.0] * 7)
    # Each at its rtol floor or just above it (DOP853: 100 eps, 2.2e-14; Radau: 1000 eps; LSODA has none), and
    # DOP853 once more at 1e-13 to show it has converged; atol far below every angle.
    runs = [("DOP853", 3e-14), ("DOP853", 1e-13), ("Radau", 3e-13), ("LSODA", 1e-13)]
    ends: dict[tuple[str, float], np.ndarray] = {}
    for method, tol in runs:
        sol = solve_ivp(rhs, (0.0, 0.03), y0, method=method, rtol=tol, atol=1e-18)
        ends[(method, tol)] = sol.y[:7, -1]
        print(f"{method} rtol {tol:g} ({sol.nfev} evaluations): " + ", ".join(repr(float(x)) for x in sol.y[:7, -1]))
    best = ends[runs[0]]
    print("\nrelative difference from DOP853 at 3e-14, per angle (" + ", ".join(NAMES) + "):")
    for key, end in ends.items():
        print(f"  {key[0]} {key[1]:g}: " + " ".join(f"{x:.1e}" for x in np.abs((end - best) / best)))
    digits = -np.log10(np.abs((np.array(PUBLISHED) - best) / best))
    print("significant digits of the published values: " + " ".join(f"{n} {x:.2f}" for n, x in zip(NAMES, digits)))


if __name__ == "__main__":
    main()
