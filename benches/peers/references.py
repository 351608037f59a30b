"""Reference solutions against which benches/peers measures both engines (numpy only).

Each is the Python twin of one in crates/linkwork/tests/common/references.rs:

- `pendulum_a01`: the IFToMM A01 pendulum released at 90 degrees, exactly, in Jacobi's `sn`.
- `OneDof`: a one-degree-of-freedom mechanism turned by its crank with no gravity (the coasting
  or torque-loaded quick-return, the coasting slider-crank), by quadrature of its energy
  equation `I(theta) theta'^2 / 2 = E0 + T (theta - theta0)`. Its generalised inertia `I(theta)`
  and the body positions as functions of the crank angle come from the model's kinematic
  analysis (Linkwork's position solver at its 1e-12 tolerance: no integrator is involved).
- `nfourbar_psi`: the IFToMM A02 N-four-bar as the one degree of freedom it has (every rocker at
  the angle psi), its Lagrange equation integrated by classical RK4 at 1e-4 s.
- `ANDREWS_END`: Andrews' end state at t = 0.03 s from the test set's own equations solved by
  SciPy's DOP853 (benches/andrews_reference.py), good to about 11.5 significant digits.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import linkwork

G = 9.81


def elliptic_k(k: float) -> float:
    """Complete elliptic integral of the first kind, `pi / (2 AGM(1, sqrt(1 - k^2)))`."""
    a, b = 1.0, math.sqrt(1.0 - k * k)
    for _ in range(10):
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return math.pi / (2.0 * a)


def sn(u: np.ndarray, k: float) -> np.ndarray:
    """Jacobi's `sn(u | k)` by the AGM and descending Landen transformation (Abramowitz and
    Stegun 16.4), `u` reduced modulo the period `4 K(k)`."""
    a, b = 1.0, math.sqrt(1.0 - k * k)
    c, aa = [k], [1.0]
    while abs(c[-1]) > 1e-17 and len(c) < 40:
        an, bn = 0.5 * (a + b), math.sqrt(a * b)
        c.append(0.5 * (a - b))
        aa.append(an)
        a, b = an, bn
    quarter = math.pi / (2.0 * a)
    u = np.mod(u, 4.0 * quarter)
    levels = len(c) - 1
    phi = 2.0**levels * a * u
    for n in range(levels, 0, -1):
        phi = 0.5 * (phi + np.arcsin(c[n] / aa[n] * np.sin(phi)))
    return np.asarray(np.sin(phi))


def pendulum_a01(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The A01 mass's exact position `(x, y)` at times `t` (length 1 m, released from rest at
    (-1, 0)): `sin(theta / 2) = k sn(K - w t | k)`, `k = sin 45 deg`, `w = sqrt(g / L)`."""
    k = math.sin(math.pi / 4.0)
    theta = 2.0 * np.arcsin(k * sn(elliptic_k(k) - math.sqrt(G) * t, k))
    return -np.sin(theta), -np.cos(theta)


class Fourier:
    """A real trigonometric series through equally spaced samples of one period (the discrete
    Fourier transform, exact for harmonics below half the samples)."""

    def __init__(self, samples: np.ndarray) -> None:
        n = len(samples)
        spectrum = np.fft.rfft(samples) / n
        self.harmonics = np.arange(1, n // 2)
        self.a0 = spectrum[0].real
        self.a = 2.0 * spectrum[1 : n // 2].real
        self.b = -2.0 * spectrum[1 : n // 2].imag

    def __call__(self, psi: np.ndarray) -> np.ndarray:
        angles = np.multiply.outer(psi, self.harmonics)
        return np.asarray(self.a0 + np.cos(angles) @ self.a + np.sin(angles) @ self.b)


class OneDof:
    """A one-degree-of-freedom mechanism with no gravity, turned by a constant torque `torque`
    (0: coasting) on its crank, which starts at the given speed `omega0`.

    `kinematics` is the model's kinematic analysis driving the crank at 2 pi rad/s from the
    dynamic analysis' initial crank angle; it is run at `samples` points of one turn."""

    # Gauss-Legendre panels per turn for `t(psi) = int sqrt(I / 2 KE)`, and nodes per panel:
    # the integrand is analytic, so the quadrature reaches rounding.
    PANELS = 512
    NODES = 12

    def __init__(
        self,
        model: linkwork.Model,
        kinematics: str,
        crank: str,
        masses: dict[str, tuple[float, float]],
        omega0: float,
        torque: float = 0.0,
        samples: int = 512,
    ) -> None:
        r = model.run(kinematics, t_end=1.0, step=1.0 / samples)
        speed = np.asarray(r[f"{crank}.omega"])
        if not np.allclose(speed, 2.0 * math.pi, rtol=1e-9):
            raise ValueError(f"{kinematics} must turn {crank} at 2 pi rad/s")
        self.theta0 = float(r[f"{crank}.phi"][0])
        inertia = sum(
            m * (np.asarray(r[f"{b}.vx"]) ** 2 + np.asarray(r[f"{b}.vy"]) ** 2) + j * np.asarray(r[f"{b}.omega"]) ** 2
            for b, (m, j) in masses.items()
        )[:samples] / (2.0 * math.pi) ** 2
        self.inertia = Fourier(inertia)
        self.energy = 0.5 * inertia[0] * omega0**2
        self.torque = torque
        self.columns: dict[str, tuple[Fourier, float]] = {}
        for b in masses:
            for c in ("x", "y", "phi"):
                y = np.asarray(r[f"{b}.{c}"])
                growth = y[samples] - y[0]
                periodic = y[:samples] - growth * np.arange(samples) / samples
                self.columns[f"{b}.{c}"] = (Fourier(periodic), growth)
        self.nodes, self.weights = np.polynomial.legendre.leggauss(self.NODES)

    def rate(self, psi: np.ndarray) -> np.ndarray:
        """`dt/dpsi` at crank angle `psi` from the start."""
        return np.asarray(np.sqrt(self.inertia(psi) / (2.0 * (self.energy + self.torque * psi))))

    def integral(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """`int_a^b rate` for each pair, by Gauss-Legendre on `[a, b]` (short intervals)."""
        half = 0.5 * (b - a)
        psi = (0.5 * (a + b))[..., None] + half[..., None] * self.nodes
        return np.asarray(half * (self.rate(psi) @ self.weights))

    def crank_angle(self, times: np.ndarray) -> np.ndarray:
        """The crank angle from the start at each time, by Newton on `t(psi) = t` inside the
        panel that holds it."""
        width = 2.0 * math.pi / self.PANELS
        ends = [0.0]
        while ends[-1] < times.max():
            start = width * np.arange(len(ends) - 1, len(ends) - 1 + self.PANELS)
            steps = self.integral(start, start + width)
            ends.extend(ends[-1] + np.cumsum(steps))
        edges = np.asarray(ends)
        panel = np.clip(np.searchsorted(edges, times, side="right") - 1, 0, len(edges) - 2)
        start = panel * width
        psi = start + width * (times - edges[panel]) / (edges[panel + 1] - edges[panel])
        for _ in range(50):
            step = (edges[panel] + self.integral(start, psi) - times) / self.rate(psi)
            psi = psi - step
            if np.max(np.abs(step)) < 1e-15 * max(1.0, float(np.max(np.abs(psi)))):
                break
        return np.asarray(psi)

    def error(self, time: np.ndarray, columns: dict[str, np.ndarray]) -> float:
        """The largest error of every body's x, y (m) and phi (rad) over the output times."""
        psi = self.crank_angle(time)
        worst = 0.0
        for name, (series, growth) in self.columns.items():
            exact = series(psi) + growth * psi / (2.0 * math.pi)
            worst = max(worst, float(np.max(np.abs(columns[name] - exact))))
        return worst


def nfourbar_psi(n: int, times: np.ndarray) -> np.ndarray:
    """The rockers' angle psi (from +x) of the `n`-bar A02 chain at `times`: Lagrange's equation
    `I psi'' = -g c cos psi`, `I = (n + 1)/3 + n`, `c = (n + 1)/2 + n` (rockers about their bases,
    couplers translating with the tops), from psi = pi/2, psi' = -1, by RK4 at 1e-4 s."""
    inertia, c = (n + 1) / 3.0 + n, (n + 1) / 2.0 + n
    w = G * c / inertia
    y0, y1, t, h = math.pi / 2.0, -1.0, 0.0, 1e-4
    out = np.empty(len(times))
    for k, to in enumerate(times):
        while t < to - 1e-12:
            hs = min(h, to - t)
            k1 = (y1, -w * math.cos(y0))
            k2 = (y1 + 0.5 * hs * k1[1], -w * math.cos(y0 + 0.5 * hs * k1[0]))
            k3 = (y1 + 0.5 * hs * k2[1], -w * math.cos(y0 + 0.5 * hs * k2[0]))
            k4 = (y1 + hs * k3[1], -w * math.cos(y0 + hs * k3[0]))
            y0 += hs / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
            y1 += hs / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
            t += hs
        out[k] = y0
    return out


# Andrews' test-set coordinates from the bodies' angles, and the converged end state at 0.03 s
# (crates/linkwork/tests/common/references.rs, ANDREWS_END_CONVERGED).
ANDREWS_ANGLES = {
    "beta": ("body1", None),
    "Theta": ("body2", "body1"),
    "gamma": ("body3", None),
    "Phi": ("body4", "body5"),
    "delta": ("body5", None),
    "Omega": ("body6", "body7"),
    "epsilon": ("body7", None),
}
ANDREWS_END = {
    "beta": 15.810771195153082,
    "Theta": -15.75637105841101,
    "gamma": 0.040822240119633035,
    "Phi": -0.5347301163421009,
    "delta": 0.5244099658799518,
    "Omega": 0.5347301163421023,
    "epsilon": 1.0480807410419404,
}
