"""A second implementation of the 3D lattice pair operator, written in Python from the step list in
cpp/include/revcol/lattice/pair3d.hpp (Python integers: no overflow, floor shifts and divisions),
and the known-answer vectors the C++ test reads.

    python3 tests/reference/lattice_pair3d_ref.py      # writes tests/data/lattice/op3.txt

Each line of op3.txt: law cell_bits sigma qx qy qz wx wy wz g X_hex, then either the refusal's name
or "ok" q2x q2y q2z w2x w2y w2z X_out_hex. The azimuth rows are found here by scanning windows
around the expected ends (the C++ searches outward from a guess): the two must agree.
"""
import bisect
import math
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import lattice_cells as LC  # noqa: E402

FX, HALF, ND, QTR = LC.FX, LC.HALF, LC.ND, LC.QTR
M48 = 1 << 48
TOT = 1 << 30          # the polar table's total
PHI_SHIFT = 2          # azimuth cells: 2^18 per turn, 4 fine cells each
PHI_MASK = (1 << 18) - 1


def cross(b, v):
    return b[0] * v[1] - b[1] * v[0]


def rotate(w, c):
    qt, p, s = c
    x, y = LC.rot90(w[0], w[1], qt)
    x += (p * y + HALF) >> FX
    y += (s * x + HALF) >> FX
    x += (p * y + HALF) >> FX
    return (x, y)


def rotate_inv(w, c):
    qt, p, s = c
    x, y = w
    x -= (p * y + HALF) >> FX
    y -= (s * x + HALF) >> FX
    x -= (p * y + HALF) >> FX
    return LC.rot90(x, y, -qt)


def isqrt_ceil(n):
    return 0 if n == 0 else math.isqrt(n - 1) + 1


# ---- faces -----------------------------------------------------------------------------------
def face_of(p):
    ax, ay, az = abs(p[0]), abs(p[1]), abs(p[2])
    if az >= ax and az >= ay:
        axis = 2
    elif ay >= ax:
        axis = 1
    else:
        axis = 0
    return 2 * axis + (1 if p[axis] < 0 else 0)


def to_face(v, f):
    r = {0: (v[1], v[2], v[0]), 1: (v[2], v[0], v[1]), 2: tuple(v)}[f >> 1]
    return (r[0], -r[1], -r[2]) if f & 1 else r


def from_face(v, f):
    r = (v[0], -v[1], -v[2]) if f & 1 else tuple(v)
    return {0: (r[2], r[0], r[1]), 1: (r[1], r[2], r[0]), 2: r}[f >> 1]


# ---- the column and its normal frame -------------------------------------------------------------
class Column:
    def __init__(self, p, sigma):
        self.face = face_of(p)
        self.xc, self.yc, self.pz = to_face(p, self.face)
        axis = self.face >> 1
        sx = 0 if axis == 2 else 1
        sy = 1 if axis == 0 else 0
        self.zmin = max(1, abs(self.xc) + sx, abs(self.yc) + sy)
        r2 = self.xc ** 2 + self.yc ** 2
        self.zin = math.isqrt(sigma * sigma - r2 - 1)
        kphi = ktheta = 0
        if r2:
            kphi = LC.dir_cell(self.xc, self.yc)
            if cross(LC.boundary(2 * kphi + 1), (self.xc, self.yc)) >= 0:
                kphi = (kphi + 1) % ND
            ktheta = QTR - LC.normal_cell(math.isqrt(r2), sigma)
        self.cphi = LC.rot_coef(kphi)
        self.ctheta = LC.rot_coef(ktheta)

    def to_normal(self, v):
        t = rotate_inv((v[0], v[1]), self.cphi)
        s = rotate_inv((v[2], t[0]), self.ctheta)
        return (s[1], t[1], s[0])

    def from_normal(self, v):
        s = rotate((v[2], v[0]), self.ctheta)
        t = rotate((s[1], v[1]), self.cphi)
        return (t[0], t[1], s[0])


def lo_pre(sigma, c, W):
    lo = c.zmin
    d = sigma * sigma - (c.xc - W[0]) ** 2 - (c.yc - W[1]) ** 2
    if d > 0:
        z = isqrt_ceil(d)
        if W[2] - z >= c.zmin:
            return None
        lo = max(lo, W[2] + z)
    return min(lo, c.zin + 1)


def lo_post(sigma, c, W):
    lo = c.zmin
    d = sigma * sigma - (c.xc + W[0]) ** 2 - (c.yc + W[1]) ** 2
    if d > 0:
        z = isqrt_ceil(d)
        if -z - W[2] >= c.zmin:
            return None
        lo = max(lo, z - W[2])
    return min(lo, c.zin + 1)


# ---- the chart -----------------------------------------------------------------------------------
def az_centre(phi):
    return LC.rot_coef((phi << PHI_SHIFT) + (1 << (PHI_SHIFT - 1)))


def az_holds(phi, v):
    b0 = LC.boundary((2 * phi) << PHI_SHIFT)
    b1 = LC.boundary((2 * phi + 2) << PHI_SHIFT)
    return cross(b0, v) >= 0 and cross(b1, v) < 0


def row(phi, xa):
    """[lo, hi] of the y whose aligned point (xa, y) turned back lies in cell phi (windows of 40
    around the expected ends), or None."""
    phi &= PHI_MASK
    if xa < 0:
        return None
    if xa == 0:
        return (0, 0) if phi == 0 else None
    c = az_centre(phi)
    est = math.floor(xa * math.tan(math.pi / (1 << 18)))
    hi_members = [y for y in range(est - 40, est + 41) if az_holds(phi, rotate((xa, y), c))]
    lo_members = [y for y in range(-est - 40, -est + 41) if az_holds(phi, rotate((xa, y), c))]
    if not hi_members or not lo_members:
        return None
    lo, hi = min(lo_members), max(hi_members)
    return (lo, hi) if lo <= hi else None


def polar_cell(uz, xa, shift):
    fine = LC.dir_cell(uz, xa)
    h = 2 * fine + (1 if cross(LC.boundary(2 * fine + 1), (uz, xa)) >= 0 else 0)
    return (h + (1 << shift)) >> (shift + 1)


def in_polar_cell(v, j, shift):
    if v[0] <= 0 or v[1] < 0:
        return False
    return (j == 0 or cross(LC.boundary((2 * j - 1) << shift), v) >= 0) and cross(LC.boundary((2 * j + 1) << shift), v) < 0


def chart(u, shift):
    """(refusal or None, phi, xa, y, uz, cell)."""
    if u[0] == 0 and u[1] == 0:
        phi, xa, y = 0, 0, 0
    else:
        phi = LC.dir_cell(u[0], u[1]) >> PHI_SHIFT
        xa, y = rotate_inv((u[0], u[1]), az_centre(phi))
    if u[2] <= 0:
        return "not_approaching", phi, xa, y, u[2], 0
    if xa < 0:
        return "out_of_domain", phi, xa, y, u[2], 0
    return None, phi, xa, y, u[2], polar_cell(u[2], xa, shift)


# ---- the polar table -----------------------------------------------------------------------------
class Table:
    """The polar law's table: cell b starts at (b - 1/2) cells (centred cells), total 2^30."""

    def __init__(self, law, cell_bits):
        self.law = law
        self.shift = 20 - cell_bits
        self.Q = 1 << (cell_bits - 2)
        self.cums = [self.cum(b) for b in range(self.Q + 2)]

    def cum(self, b):
        if b <= 0:
            return 0
        if b > self.Q:
            return TOT
        scale = TOT - (self.Q + 1)
        h = (2 * b - 1) << self.shift
        if self.law == "flux":
            y = LC.boundary(h)[1]
            q = (y * y) >> FX
        else:
            q = (1 << FX) - LC.boundary(h)[0]
        return b + ((scale * q + HALF) >> FX)

    def decode(self, s):
        b = bisect.bisect_right(self.cums, s) - 1
        return b, self.cums[b], self.cums[b + 1] - self.cums[b]


# ---- the bits-back integer -----------------------------------------------------------------------
def push_uniform(X, idx, m):
    return X * m + idx


def pop_uniform(X, m):
    return X // m, X % m


def push_rans(X, c, f):
    return (X // f) * M48 + (X % f) + c


def pop_rans(X, c, f):
    s = X % M48
    assert c <= s < c + f
    return f * (X // M48) + s - c


def add_low48(X, g):
    s = X % M48
    return X - s + (s + g) % M48


# ---- the operator --------------------------------------------------------------------------------
def forward(sigma, table, q, w, g, X):
    """(refusal, None, None, X) or ("ok", q2, w2, X_out)."""
    p = tuple(q[k] + w[k] for k in range(3))
    assert sum(v * v for v in q) >= sigma * sigma > sum(v * v for v in p)
    if p == (0, 0, 0):
        return "out_of_domain", None, None, X
    col = Column(p, sigma)
    W = to_face(w, col.face)
    lo = lo_pre(sigma, col, W)
    if lo is None:
        return "out_of_domain", None, None, X
    m = col.zin - lo + 1
    un = col.to_normal(W)
    why, phi, xa, y, uz, a = chart((-un[0], -un[1], -un[2]), table.shift)
    if why:
        return why, None, None, X
    rw = row(phi, xa)
    if rw is None or not rw[0] <= y <= rw[1]:
        return "out_of_domain", None, None, X
    Y = push_uniform(X, col.pz - lo, m)
    Y = push_uniform(Y, y - rw[0], rw[1] - rw[0] + 1)
    Y = push_rans(Y, (phi << 30) + table.cums[a], table.cums[a + 1] - table.cums[a])
    Y = add_low48(Y, g)
    s = Y % M48
    phi2 = s >> 30
    b, cb, fb = table.decode(s & (TOT - 1))
    Y = pop_rans(Y, (phi2 << 30) + cb, fb)
    t2 = rotate((uz, xa), LC.rot_coef((b - a) << table.shift))
    if not in_polar_cell(t2, b, table.shift):
        return "cell_readback", None, None, X
    rw2 = row(phi2, t2[1])
    if rw2 is None:
        return "empty_post", None, None, X
    Y, idx = pop_uniform(Y, rw2[1] - rw2[0] + 1)
    y2 = rw2[0] + idx
    uxy = rotate((t2[1], y2), az_centre(phi2))
    if uxy == (0, 0):
        if phi2 != 0:
            return "cell_readback", None, None, X
    elif not az_holds(phi2, uxy):
        return "cell_readback", None, None, X
    W2 = col.from_normal((uxy[0], uxy[1], t2[0]))
    if any(abs(v) >= 1 << 61 for v in W2):
        return "out_of_domain", None, None, X
    lo2 = lo_post(sigma, col, W2)
    if lo2 is None:
        return "out_of_domain", None, None, X
    m2 = col.zin - lo2 + 1
    if m2 <= 0:
        return "empty_post", None, None, X
    Y, idx2 = pop_uniform(Y, m2)
    qf = (col.xc + W2[0], col.yc + W2[1], lo2 + idx2 + W2[2])
    if any(abs(v) >= 1 << 61 for v in qf):
        return "out_of_domain", None, None, X
    return "ok", from_face(qf, col.face), from_face(W2, col.face), Y


def make_pre(rnd, sigma, speed):
    """A random pre state near contact (flux-law incidence), or None after rounding."""
    ct = 2 * rnd.random() - 1
    st = math.sqrt(1 - ct * ct)
    ph = 2 * math.pi * rnd.random()
    n = (st * math.cos(ph), st * math.sin(ph), ct)
    a = (1.0, 0.0, 0.0) if abs(n[0]) < 0.6 else (0.0, 1.0, 0.0)
    d = sum(a[k] * n[k] for k in range(3))
    e1 = [a[k] - d * n[k] for k in range(3)]
    ln = math.sqrt(sum(v * v for v in e1))
    e1 = [v / ln for v in e1]
    e2 = (n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2], n[0] * e1[1] - n[1] * e1[0])
    si = math.sqrt(rnd.random()) * (1.0 if rnd.random() < 0.95 else 1.02)
    si = min(si, 1.0)
    ci = math.sqrt(1 - si * si)
    az = 2 * math.pi * rnd.random()
    frac = rnd.random()
    w = tuple(int(-speed * (ci * n[k] + si * (math.cos(az) * e1[k] + math.sin(az) * e2[k]))) for k in range(3))
    q = tuple(int(sigma * n[k]) - int(w[k] * frac) for k in range(3))
    p = tuple(q[k] + w[k] for k in range(3))
    if sum(v * v for v in q) >= sigma * sigma > sum(v * v for v in p):
        return q, w
    return None


def main():
    rnd = random.Random(20261124)
    out = os.path.join(os.path.dirname(os.path.dirname(HERE)), "tests", "data", "lattice", "op3.txt")
    lines = ["# law cell_bits sigma qx qy qz wx wy wz g X_hex | refusal | ok q2x q2y q2z w2x w2y w2z X_out_hex",
             "# made by tests/reference/lattice_pair3d_ref.py (a Python implementation from pair3d.hpp's text)"]
    tables = {}
    counts = {}
    cases = []
    # the pole along each axis, both signs
    for axis in range(3):
        for sgn in (1, -1):
            q = [0, 0, 0]
            w = [0, 0, 0]
            q[axis] = sgn * ((1 << 50) + (1 << 28))
            w[axis] = -sgn * (1 << 30)
            cases.append(("flux", 16, 1 << 50, tuple(q), tuple(w)))
    while len(cases) < 400:
        law = "flux" if rnd.random() < 0.7 else "uniform"
        cb = rnd.choice((12, 16, 16, 20))
        S = rnd.randint(24, 60)
        sigma = (1 << S) - (rnd.randint(0, 999) if rnd.random() < 0.5 else 0)
        e = rnd.randint(min(14, S - 8), min(40, S - 4))
        pre = make_pre(rnd, sigma, (1 + rnd.random()) * 2.0 ** e)
        if pre:
            cases.append((law, cb, sigma) + pre)
    for law, cb, sigma, q, w in cases:
        key = (law, cb)
        if key not in tables:
            tables[key] = Table(law, cb)
        g = rnd.getrandbits(48)
        X = rnd.getrandbits(256) | (1 << 255)
        why, q2, w2, Y = forward(sigma, tables[key], q, w, g, X)
        counts[why] = counts.get(why, 0) + 1
        head = f"{law} {cb} {sigma} {q[0]} {q[1]} {q[2]} {w[0]} {w[1]} {w[2]} {g} {X:#x}"
        if why == "ok":
            lines.append(head + f" ok {q2[0]} {q2[1]} {q2[2]} {w2[0]} {w2[1]} {w2[2]} {Y:#x}")
        else:
            lines.append(head + " " + why)
    with open(out + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(out + ".tmp", out)
    print(f"wrote {out}: {len(cases)} cases, {counts}")


if __name__ == "__main__":
    main()
