"""Closed-form motions of the paper's examples, evaluated with hyper-dual numbers
(value, first and second time derivative carried through the arithmetic), so that
velocities and accelerations are exact too and owe nothing to FEKAP: Example 1's
four-bar (decks/fourbar.deck) and Example 5's quick-return mechanism
(decks/quick-return.deck)."""

from __future__ import annotations

import math


class Dual:
    """f(t) with exact f' and f'' (a hyper-dual number in t)."""

    def __init__(self, f: float, d: float = 0.0, dd: float = 0.0):
        self.f, self.d, self.dd = f, d, dd

    @staticmethod
    def lift(x) -> Dual:
        return x if isinstance(x, Dual) else Dual(float(x))

    def __add__(self, o):
        o = Dual.lift(o)
        return Dual(self.f + o.f, self.d + o.d, self.dd + o.dd)

    __radd__ = __add__

    def __neg__(self):
        return Dual(-self.f, -self.d, -self.dd)

    def __sub__(self, o):
        return self + (-Dual.lift(o))

    def __rsub__(self, o):
        return Dual.lift(o) - self

    def __mul__(self, o):
        o = Dual.lift(o)
        return Dual(self.f * o.f, self.d * o.f + self.f * o.d,
                    self.dd * o.f + 2 * self.d * o.d + self.f * o.dd)

    __rmul__ = __mul__

    def __truediv__(self, o):
        return self * Dual.lift(o).inverse()

    def __rtruediv__(self, o):
        return Dual.lift(o) * self.inverse()

    def inverse(self) -> Dual:
        return self.apply(1 / self.f, -1 / self.f**2, 2 / self.f**3)

    def apply(self, g: float, dg: float, ddg: float) -> Dual:
        """g(self) given g, g', g'' at self.f (chain rule to second order)."""
        return Dual(g, dg * self.d, ddg * self.d**2 + dg * self.dd)


def sqrt(x: Dual) -> Dual:
    r = math.sqrt(x.f)
    return x.apply(r, 0.5 / r, -0.25 / r**3)


def sin(x: Dual) -> Dual:
    return x.apply(math.sin(x.f), math.cos(x.f), -math.sin(x.f))


def cos(x: Dual) -> Dual:
    return x.apply(math.cos(x.f), -math.sin(x.f), -math.cos(x.f))


def angle(t: float, start: float, rate: float) -> Dual:
    return Dual(start + rate * t, rate, 0.0)


def fourbar_exact(t: float):
    """Example 1: B and C (upper branch) for crank angle 2*pi*t."""
    th = angle(t, 0.0, 2 * math.pi)
    b = (2 * cos(th), 2 * sin(th))
    dx, dy = 4 - b[0], 0 - b[1]
    dist = sqrt(dx * dx + dy * dy)
    ex, ey = dx / dist, dy / dist
    along = dist / 2                      # (l2^2 - l3^2 + d^2) / (2 d) with l2 = l3
    h = sqrt(16 - along * along)
    c = (b[0] + along * ex - h * ey, b[1] + along * ey + h * ex)
    return b, c


def quick_return_exact(t):
    """Example 5: P from the crank angle by the geometry of the slotted lever."""
    th = angle(t, math.atan2(-1, 3), 2 * math.pi)
    cx, cy = 100 * cos(th), 100 * math.sqrt(10) + 100 * sin(th)
    r = sqrt(cx * cx + cy * cy)
    bx, by = 150 * math.sqrt(10) * cx / r, 150 * math.sqrt(10) * cy / r
    return (bx - sqrt(25000 - (500 - by) * (500 - by)), Dual(500.0))
