"""Write the IFToMM A02 N-four-bar deck for dynamics (decks/dynamics/a02-n<N>.deck).

N + 1 vertical cranks (1 m, 1 kg) on pivots 1 m apart, N horizontal couplers
(1 m, 1 kg) between their tips, g = 9.81 along -y, the crank tips starting at
1 m/s along x (VELOcities), 20 s. With stiff bars the chain is one pendulum:
its energy integral gives the first crank's angle and rate exactly
(test/app/test_dynamics.py).

    scripts/python -m fekap.models.a02 N [DT] > decks/dynamics/a02-n<N>.deck
"""
import sys


def deck(n, dt=2e-3, t_end=20.0):
    lines = [
        f"* IFToMM A02 N-four-bar in dynamics, N = {n} (written by fekap.models.a02 {n} {dt:g}):",
        f"* {n + 1} vertical cranks and {n} horizontal couplers, uniform 1 m / 1 kg stiff bars,",
        "* g = 9.81 along -y, crank tips starting at 1 m/s along x; the chain passes the",
        "* horizontal change points (all bars flat on the x axis) by its inertia. Exact:",
        f"* one pendulum of inertia I = (N+1)/3 + N = {(n + 1) / 3 + n:.10g} kg m^2 about the pivots",
        f"* and gravity moment G cos(theta), G = ((N+1)/2 + N) m g L = {((n + 1) / 2 + n) * 9.81:.10g} N m.",
        f"TITLe   A02 N-four-bar, N = {n}, dynamics",
        "PARAmeters",
        f"  t_end = {t_end:g}     ! the run's end (fekap --set t_end=...)",
        f"  dt = {dt:g}",
        "SECTions",
        "  bar  EA=1e10  kGA=1e10  EI=1e8  rhoA=1     ! 1 kg per 1 m bar; stiff",
        "NODEs",
    ]
    for i in range(n + 1):
        lines.append(f"  P{i}  {i}  0")
        lines.append(f"  T{i}  {i}  1")
    lines.append("LINKs")
    for i in range(n + 1):
        lines.append(f"  C{i}  P{i}  T{i}  bar  1")
    for i in range(1, n + 1):
        lines.append(f"  K{i}  T{i - 1}  T{i}  bar  1")
    lines.append("SUPPorts")
    for i in range(n + 1):
        lines.append(f"  P{i}  pin")
    lines.append("VELOcities")
    lines.append("  ! link  vx vy (first node)  omega: crank tips at 1 m/s along x")
    for i in range(n + 1):
        lines.append(f"  C{i}  0  0  -1")
    for i in range(1, n + 1):
        lines.append(f"  K{i}  1  0  0")
    lines += [
        "GRAVity  0  -9.81",
        "ANALysis",
        "  ! type auto: masses on a scene without drives give dynamics",
        "  time 0 t_end dt",
        "OUTPut",
        "  units length=m time=s",
        "  track T0",
        "  angles C0",
        "END",
    ]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    n = int(sys.argv[1])
    dt = float(sys.argv[2]) if len(sys.argv) > 2 else 2e-3
    sys.stdout.write(deck(n, dt))
