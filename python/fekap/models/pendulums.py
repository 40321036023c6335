"""Dynamics decks of rigid-link mechanisms built of stiff beams, each placed at
a state of its motion (angles and angular rates), so that a run can start
anywhere on it: the A01 pendulum, a uniform rod pendulum, the double pendulum
of point masses or of uniform rods, and the free slider-crank with a flywheel.
The tests and studies that compare them with rigid answers found without
FEKAP (fekap.exact.pendulums; test_stiff_links, test_error_estimate,
studies/accuracy) write their decks here.

A deck is `deck(title, ea, geometry, analysis, output)`: the section of axial
stiffness EA (kGA = EA / 2.5, EI = EA / 100, A = 1e-3, so that the rigid
motion's loads deflect the links by less than about 1e-8 m at EA >= 1e11),
the mechanism's geometry at its state, the ANALysis lines after `type
dynamics` and the OUTPut lines."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Geometry:
    """A mechanism at a state: the deck's lines of each block (each line ends
    with a newline), and the section's mass properties."""
    nodes: str
    links: str
    rho: str = ""
    masses: str = ""
    velocities: str = ""
    supports: str = "  A pin\n"
    slides: str = ""


def section(ea: float, rho: str = "") -> str:
    """The `rod` section of axial stiffness EA, kGA = EA / 2.5 and EI = EA / 100 (A = 1e-3)."""
    e = ea * 1e3
    return f"  rod  E={e:g}  G={e / 2.5:g}  A=1e-3  I=1e-5  {rho}"


def deck(title: str, ea: float, geometry: Geometry, analysis: str, output: str) -> str:
    """The dynamics deck of `geometry` with the `rod` section of EA; `analysis`
    and `output` are the lines of those blocks (after `type dynamics`)."""
    g = geometry
    slides = f"SLIDelines\n{g.slides}" if g.slides else ""
    masses = f"MASSes\n{g.masses}" if g.masses else ""
    velocities = f"VELOcities\n{g.velocities}" if g.velocities else ""
    return f"""TITLe {title}
SECTions
{section(ea, g.rho)}
NODEs
{g.nodes}LINKs
{g.links}SUPPorts
{g.supports}{slides}{masses}GRAVity 0 -9.81
{velocities}ANALysis
  type dynamics
{analysis}OUTPut
{output}END
"""


def point_mass_pendulum(s=(0.0, 0.0)) -> Geometry:
    """A01: a 1 kg point mass B on a massless 1 m link pinned at A; s = (th, th'),
    th the angle below the horizontal (B = (cos th, -sin th))."""
    th, w = (float(x) for x in s)
    b = (math.cos(th), -math.sin(th))
    return Geometry(nodes=f"  A 0 0\n  B {b[0]!r} {b[1]!r}\n", links="  AB A B rod 1\n", masses="  B 1\n",
                    velocities=f"  AB 0 0 {-w!r}\n" if w else "")


def rod_pendulum(s=(math.pi / 6, 0.0)) -> Geometry:
    """A uniform rod (1 kg/m, rotary inertia 1e-6 per length, 1 m, 4 elements)
    pinned at A; s = (th, th'), th the angle above the horizontal."""
    th, w = (float(x) for x in s)
    b = (math.cos(th), math.sin(th))
    return Geometry(nodes=f"  A 0 0\n  B {b[0]!r} {b[1]!r}\n", links="  AB A B rod 4\n", rho="rhoA=1  rhoI=1e-6",
                    velocities=f"  AB 0 0 {w!r}\n" if w else "")


def double_pendulum(s=(math.pi / 2, math.pi / 2, 0.0, 0.0), rods: bool = False) -> Geometry:
    """Two 1 m links AB, BC pinned at A, s = (a, b, a', b') with the angles from
    the downward vertical: 1 kg point masses at B and C on massless links, or
    (rods) two uniform 1 kg rods of 4 elements each."""
    a, b, wa, wb = (float(x) for x in s)
    pb = (math.sin(a), -math.cos(a))
    pc = (pb[0] + math.sin(b), pb[1] - math.cos(b))
    vb = (math.cos(a) * wa, math.sin(a) * wa)
    velocities = f"  AB 0 0 {wa!r}\n  BC {vb[0]!r} {vb[1]!r} {wb!r}\n" if wa or wb else ""
    elements = 4 if rods else 1
    return Geometry(nodes=f"  A 0 0\n  B {pb[0]!r} {pb[1]!r}\n  C {pc[0]!r} {pc[1]!r}\n",
                    links=f"  AB A B rod {elements}\n  BC B C rod {elements}\n",
                    rho="rhoA=1  rhoI=0" if rods else "", masses="" if rods else "  B 1\n  C 1\n",
                    velocities=velocities)


def slider_crank_points(theta: float, r: float = 1.0, length: float = 2.0) -> tuple[tuple[float, float], float]:
    """The crank tip A and the slider's x at crank angle theta."""
    a = (r * math.cos(theta), r * math.sin(theta))
    return a, a[0] + math.sqrt(length**2 - a[1] ** 2)


def slider_crank(s=(math.pi / 3, 0.0)) -> Geometry:
    """The free slider-crank: crank OA 1 m and rod AB 2 m (uniform, 1 kg/m), a 2 kg
    slider at B on a guide along x, a 0.05 kg m^2 flywheel keyed to the crank;
    s = (th, th'), the crank's angle and rate."""
    th, w1 = (float(x) for x in s)
    a, bx = slider_crank_points(th)
    va, w2 = (-w1 * a[1], w1 * a[0]), -w1 * a[0] / (bx - a[0])
    return Geometry(nodes=f"  O 0 0\n  A {a[0]!r} {a[1]!r}\n  B {bx!r} 0\n", links="  OA O A rod 2\n  AB A B rod 4\n",
                    rho="rhoA=1  rhoI=0", supports="  O pin\n", slides="  slider B guide -5 0 5 0 pin\n",
                    masses="  B 2\n  O 0 0.05 OA\n",
                    velocities=f"  OA 0 0 {w1!r}\n  AB {va[0]!r} {va[1]!r} {w2!r}\n" if w1 else "")
