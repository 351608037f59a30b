"""Write the model of IFToMM benchmark A02, the N-four-bar mechanism, for any N.

    python examples/nfourbar.py 40 > examples/iftomm_a02_nfourbar.yaml

IFToMM Technical Committee for Multibody Dynamics, Library of Computational Benchmark Problems,
problem A02 (www.iftomm-multibody.org): N + 1 vertical rockers, 1 m long, hinged to ground at
x = 0, 1, ..., N, and N horizontal couplers, 1 m long, joining their tops; every bar a uniform
1 kg rod (I = m L^2 / 12 about its centre). Gravity 9.81 m/s^2 in -y. The top of the first rocker,
B0, starts with velocity 1 m/s in +x: every rocker turns at -1 rad/s about its base and every
coupler translates at 1 m/s. The chain is a row of parallelograms with one degree of freedom; it
passes through singular positions when it lies flat (B0_y = 0). Standard library only.
"""

import sys

HEADER = """\
# IFToMM multibody benchmark A02, the N-four-bar mechanism, N = {n} (IFToMM Technical Committee
# for Multibody Dynamics, Library of Computational Benchmark Problems, problem A02;
# www.iftomm-multibody.org). Written by `python examples/nfourbar.py {n}`; edit the generator,
# not this file.
#
# N + 1 = {n1} vertical rockers r0..r{n}, 1 m long, hinged to ground at A_k = (k, 0); N = {n}
# horizontal couplers c1..c{n}, 1 m long, coupler c_k joining the tops B_(k-1) and B_k of rockers
# r(k-1) and r_k. Every bar is a uniform 1 kg rod (inertia 1/12 kg m^2 about its centre), its
# frame's x-axis along the bar. Gravity 9.81 m/s^2 in -y. B0 starts with velocity 1 m/s in +x:
# the rockers turn at -1 rad/s about their bases, the couplers translate at 1 m/s. One degree of
# freedom; the chain lies flat (a singular position, B0_y = 0) twice per revolution.
name: IFToMM A02 N-four-bar (N = {n})
gravity: [0, -9.81]
"""

INERTIA = 1.0 / 12.0


def model(n: int) -> str:
    """The model file's text for `n` four-bar loops."""
    lines = [HEADER.format(n=n, n1=n + 1).rstrip("\n"), "bodies:"]
    for k in range(n + 1):
        lines.append(
            f"  r{k}: {{mass: 1, inertia: {INERTIA!r}, position: [{k}, 0.5], angle: 1.5707963267948966, "
            f"velocity: [0.5, 0], omega: -1, points: {{A: [-0.5, 0], B: [0.5, 0]}}"
            + (", given: [phi, omega]}" if k == 0 else "}")
        )
    for k in range(1, n + 1):
        lines.append(
            f"  c{k}: {{mass: 1, inertia: {INERTIA!r}, position: [{k - 0.5}, 1], angle: 0, "
            f"velocity: [1, 0], points: {{L: [-0.5, 0], R: [0.5, 0]}}}}"
        )
    lines.append("joints:")
    for k in range(n + 1):
        lines.append(f"  A{k}: {{type: revolute, body_i: r{k}, point_i: A, body_j: ground, point_j: [{k}, 0]}}")
    for k in range(1, n + 1):
        lines.append(f"  L{k}: {{type: revolute, body_i: c{k}, point_i: L, body_j: r{k - 1}, point_j: B}}")
        lines.append(f"  R{k}: {{type: revolute, body_i: c{k}, point_i: R, body_j: r{k}, point_j: B}}")
    lines += [
        "measures:",
        "  B0_x: {body: r0, point: B, component: x}",
        "  B0_y: {body: r0, point: B, component: y}",
        "analyses:",
        "  # The benchmark's 20 s.",
        "  dynamics: {type: dynamic, t_end: 20, step: 0.01}",
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> int:
    if len(argv) != 2 or not argv[1].isdigit() or int(argv[1]) < 1:
        print("usage: python examples/nfourbar.py N   (N >= 1 four-bar loops)", file=sys.stderr)
        return 2
    sys.stdout.write(model(int(argv[1])))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
