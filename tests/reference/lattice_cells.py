"""The integer direction cells, flux table and lifting coefficients of the C++ lattice operator
(cpp/include/revcol/lattice/cells.hpp), re-implemented in Python from that header's text.

Used by make_lattice_vectors.py to patch the prototype (../shared/reference/exactgas/exact.py),
whose own cell index (atan2), table (numpy floats) and coefficients (tan, sin) are floating point,
so that the prototype's C_fwd / pair_fwd produce whole-operator vectors the C++ must match bit for bit.
"""
import math

FX = 62
ONE = 1 << FX
HALF = 1 << (FX - 1)
ND = 1 << 20
QTR = ND >> 2
OCT = 1 << 18       # pi/4 at half-cell resolution (2^21 per turn)
QUAD = 1 << 19
FINE = 1 << 9


def _atan_inv(x, one):
    s, t, n, sign, x2 = 0, one // x, 1, 1, x * x
    while t:
        s += sign * (t // n)
        t //= x2
        n += 2
        sign = -sign
    return s


def two_pi_fx100():
    """round(2*pi * 2^100) from Machin's formula with 300 bits."""
    P = 300
    one = 1 << P
    pi = 16 * _atan_inv(5, one) - 4 * _atan_inv(239, one)
    return (2 * pi + (1 << (P - 101))) >> (P - 100)


TWO_PI_FX100 = two_pi_fx100()
assert TWO_PI_FX100 == 0x6487ed5110b4611a62633145c0


def angle_fx(h):
    return (h * TWO_PI_FX100 + (1 << 58)) >> 59


def sincos_fx(a):
    x2 = (a * a + HALF) >> FX
    c, s, tc, ts, n = ONE, a, ONE, a, 1
    while tc or ts:
        dc = (2 * n - 1) * (2 * n)
        ds = (2 * n) * (2 * n + 1)
        tc = (((tc * x2 + HALF) >> FX) + dc // 2) // dc
        ts = (((ts * x2 + HALF) >> FX) + ds // 2) // ds
        if n & 1:
            c, s = c - tc, s - ts
        else:
            c, s = c + tc, s + ts
        n += 1
    return c, s


_D = math.isqrt(1 << (2 * FX - 1))
COARSE = [sincos_fx(angle_fx(i * FINE)) for i in range(OCT // FINE)] + [(_D, _D)]
FINE_T = [sincos_fx(angle_fx(j)) for j in range(FINE)]


def rot90(x, y, k):
    k &= 3
    return [(x, y), (-y, x), (-x, -y), (y, -x)][k]


def boundary_octant(h):
    a = COARSE[h >> 9]
    j = h & (FINE - 1)
    if j == 0:
        return a
    b = FINE_T[j]
    return ((a[0] * b[0] - a[1] * b[1] + HALF) >> FX, (a[1] * b[0] + a[0] * b[1] + HALF) >> FX)


def boundary(h):
    h &= (1 << 21) - 1
    r = h & (QUAD - 1)
    if r <= OCT:
        b = boundary_octant(r)
    else:
        m = boundary_octant(QUAD - r)
        b = (m[1], m[0])
    return rot90(b[0], b[1], h >> 19)


def _cross(b, wx, wy):
    return b[0] * wy - b[1] * wx


def dir_cell(wx, wy):
    k = math.floor(math.atan2(wy, wx) / (2 * math.pi) * ND) % ND
    while _cross(boundary(2 * k), wx, wy) < 0:
        k = (k - 1) % ND
    while _cross(boundary(2 * k + 2), wx, wy) >= 0:
        k = (k + 1) % ND
    return k


def normal_cell(xc, sigma):
    k = round(math.acos(xc / sigma) / (2 * math.pi) * ND)
    lhs = xc << FX
    while lhs > sigma * boundary(2 * k - 1)[0]:
        k -= 1
    while lhs <= sigma * boundary(2 * k + 1)[0]:
        k += 1
    return k


def rot_coef(k):
    k %= ND
    qt = (k + ND // 8) >> 18
    r = k - qt * QTR
    bx, by = boundary(2 * r)
    den = ONE + bx
    mag = ((abs(by) << FX) + den // 2) // den
    return qt & 3, (-mag if by >= 0 else mag), by


def flux_cum(a):
    return (1 << 47) + ((boundary(2 * (a - QTR))[1] + (1 << 14)) >> 15)


def flux_table():
    cum = [flux_cum(a) for a in range(2 * QTR + 1)]
    freq = [cum[a + 1] - cum[a] for a in range(2 * QTR)]
    return freq, cum


def uniform_table():
    f = 1 << (48 - 19)
    return [f] * (2 * QTR), [a * f for a in range(2 * QTR + 1)]
