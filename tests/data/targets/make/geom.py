"""Construction geometry for the target corpus: exact lengths, ends and turning of base shapes.

Pure Python + numpy (runs under /usr/bin/python3, freecadcmd and the project venv).
A shape is a list of primitives in a y-UP millimetre "design frame":
  ("L", p0, p1)                       straight segment
  ("A", c, r, a0, sweep)              circular arc, start angle a0 (rad), signed sweep (+ = CCW)
  ("C", p0, p1, p2, p3)               cubic Bezier
The expected numbers in manifest.json come from these formulas (R*phi, segment sums, Gauss-Legendre
quadrature of cubic Beziers), never from a file reader.
"""
from __future__ import annotations

import math

import numpy as np

_GX, _GW = np.polynomial.legendre.leggauss(48)


def P(x, y):
    return np.array([float(x), float(y)])


# ----------------------------------------------------------------------------- primitives
def prim_start(p):
    if p[0] == "L":
        return p[1]
    if p[0] == "A":
        _, c, r, a0, sw = p
        return c + r * np.array([math.cos(a0), math.sin(a0)])
    return p[1]


def prim_end(p):
    if p[0] == "L":
        return p[2]
    if p[0] == "A":
        _, c, r, a0, sw = p
        return c + r * np.array([math.cos(a0 + sw), math.sin(a0 + sw)])
    return p[4]


def _cubic_d(p, t):
    _, p0, p1, p2, p3 = p
    t = np.asarray(t)[:, None]
    return 3 * (1 - t) ** 2 * (p1 - p0) + 6 * (1 - t) * t * (p2 - p1) + 3 * t ** 2 * (p3 - p2)


def cubic_point(p, t):
    _, p0, p1, p2, p3 = p
    t = np.asarray(t)[:, None]
    return (1 - t) ** 3 * p0 + 3 * (1 - t) ** 2 * t * p1 + 3 * (1 - t) * t ** 2 * p2 + t ** 3 * p3


def prim_length(p):
    if p[0] == "L":
        return float(np.hypot(*(p[2] - p[1])))
    if p[0] == "A":
        return abs(p[2] * p[4])
    # Gauss-Legendre on 16 sub-intervals
    total = 0.0
    for k in range(16):
        a, b = k / 16, (k + 1) / 16
        t = 0.5 * (b - a) * _GX + 0.5 * (a + b)
        total += 0.5 * (b - a) * float(np.sum(_GW * np.hypot(*_cubic_d(p, t).T)))
    return total


def prim_dir0(p):
    if p[0] == "L":
        d = p[2] - p[1]
    elif p[0] == "A":
        a = p[3]
        d = np.array([-math.sin(a), math.cos(a)]) * math.copysign(1, p[4])
    else:
        d = _cubic_d(p, [0.0])[0]
        if np.hypot(*d) < 1e-12:
            d = p[3] - p[1]
    return d / np.hypot(*d)


def prim_dir1(p):
    if p[0] == "L":
        d = p[2] - p[1]
    elif p[0] == "A":
        a = p[3] + p[4]
        d = np.array([-math.sin(a), math.cos(a)]) * math.copysign(1, p[4])
    else:
        d = _cubic_d(p, [1.0])[0]
        if np.hypot(*d) < 1e-12:
            d = p[4] - p[2]
    return d / np.hypot(*d)


def prim_turn(p):
    """Signed turning of the tangent inside the primitive (rad, + = CCW in the frame)."""
    if p[0] == "L":
        return 0.0
    if p[0] == "A":
        return p[4]
    t = np.linspace(0, 1, 4001)
    d = _cubic_d(p, t)
    ang = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    return float(ang[-1] - ang[0])


def _angle_between(d0, d1):
    return math.atan2(d0[0] * d1[1] - d0[1] * d1[0], d0[0] * d1[0] + d0[1] * d1[1])


# ----------------------------------------------------------------------------- shapes
def length(shape):
    return sum(prim_length(p) for p in shape)


def start(shape):
    return prim_start(shape[0])


def end(shape):
    return prim_end(shape[-1])


def turn(shape):
    """Total signed turning (rad): inside primitives plus corners between them."""
    tot = 0.0
    for i, p in enumerate(shape):
        tot += prim_turn(p)
        if i + 1 < len(shape):
            tot += _angle_between(prim_dir1(p), prim_dir0(shape[i + 1]))
    return tot


def min_radius(shape):
    r = math.inf
    for p in shape:
        if p[0] == "A":
            r = min(r, p[2])
        elif p[0] == "C":
            t = np.linspace(0, 1, 2001)
            _, p0, p1, p2, p3 = p
            d1 = _cubic_d(p, t)
            tt = t[:, None]
            d2 = 6 * (1 - tt) * (p2 - 2 * p1 + p0) + 6 * tt * (p3 - 2 * p2 + p1)
            cross = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
            sp = np.hypot(d1[:, 0], d1[:, 1])
            with np.errstate(divide="ignore"):
                rr = sp ** 3 / cross
            r = min(r, float(np.min(rr)))
    return r


def corners(shape):
    """Largest tangent jump between primitives (deg); 0 for a smooth (G1) chain."""
    m = 0.0
    for a, b in zip(shape, shape[1:]):
        m = max(m, abs(math.degrees(_angle_between(prim_dir1(a), prim_dir0(b)))))
    return m


def sample(shape, step=0.5):
    """Dense points along the shape (for polylines written into files)."""
    out = [start(shape)]
    for p in shape:
        n = max(2, int(math.ceil(prim_length(p) / step)))
        t = np.linspace(0, 1, n + 1)[1:]
        if p[0] == "L":
            pts = p[1] + t[:, None] * (p[2] - p[1])
        elif p[0] == "A":
            a = p[3] + t * p[4]
            pts = p[1] + p[2] * np.c_[np.cos(a), np.sin(a)]
        else:
            pts = cubic_point(p, t)
        out.extend(pts)
    return np.array(out)


def polyline_length(pts):
    pts = np.asarray(pts, float)
    return float(np.sum(np.hypot(*np.diff(pts, axis=0).T)))


def polyline_turn(pts):
    d = np.diff(np.asarray(pts, float), axis=0)
    a = np.arctan2(d[:, 1], d[:, 0])
    da = np.diff(a)
    da = (da + np.pi) % (2 * np.pi) - np.pi
    return float(np.sum(da))


def reverse(shape):
    out = []
    for p in reversed(shape):
        if p[0] == "L":
            out.append(("L", p[2], p[1]))
        elif p[0] == "A":
            out.append(("A", p[1], p[2], p[3] + p[4], -p[4]))
        else:
            out.append(("C", p[4], p[3], p[2], p[1]))
    return out


# ----------------------------------------------------------------------------- affine maps
def M(a, b, c, d, e, f):
    """SVG matrix(a,b,c,d,e,f) as a 3x3 numpy array."""
    return np.array([[a, c, e], [b, d, f], [0.0, 0.0, 1.0]], float)


I = M(1, 0, 0, 1, 0, 0)


def translate(tx, ty=0.0):
    return M(1, 0, 0, 1, tx, ty)


def scale(sx, sy=None):
    return M(sx, 0, 0, sx if sy is None else sy, 0, 0)


def rotate(deg, cx=0.0, cy=0.0):
    a = math.radians(deg)
    R = M(math.cos(a), math.sin(a), -math.sin(a), math.cos(a), 0, 0)
    return translate(cx, cy) @ R @ translate(-cx, -cy)


def apply(T, p):
    return (T @ np.array([p[0], p[1], 1.0]))[:2]


def similarity_factor(T):
    """(uniform scale, det sign) of the linear part, or (None, sign) if not a similarity."""
    A = T[:2, :2]
    det = float(np.linalg.det(A))
    s = math.sqrt(abs(det))
    ok = np.allclose(A.T @ A, s * s * np.eye(2), rtol=1e-9, atol=1e-9)
    return (s if ok else None), (1 if det > 0 else -1)


def transform(shape, T):
    """Apply an affine map. Arcs need a similarity; lines/cubics take any affine map."""
    s, sgn = similarity_factor(T)
    out = []
    for p in shape:
        if p[0] == "L":
            out.append(("L", apply(T, p[1]), apply(T, p[2])))
        elif p[0] == "C":
            out.append(("C",) + tuple(apply(T, q) for q in p[1:]))
        else:
            if s is None:
                raise ValueError("arc under a non-similarity map")
            _, c, r, a0, sw = p
            q0 = apply(T, c + r * np.array([math.cos(a0), math.sin(a0)])) - apply(T, c)
            out.append(("A", apply(T, c), r * s, math.atan2(q0[1], q0[0]), sw * sgn))
    return out


# ----------------------------------------------------------------------------- SVG path data
def fmt(v):
    s = f"{v:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def svg_d(shape, style="abs"):
    """Path data (absolute M/L/A/C) for a shape given in SVG user coordinates."""
    parts = []
    cur = None
    for p in shape:
        s0 = prim_start(p)
        if cur is None or np.hypot(*(s0 - cur)) > 1e-9:
            parts.append(f"M {fmt(s0[0])},{fmt(s0[1])}")
        e = prim_end(p)
        if p[0] == "L":
            parts.append(f"L {fmt(e[0])},{fmt(e[1])}")
        elif p[0] == "A":
            _, c, r, a0, sw = p
            large = 1 if abs(sw) > math.pi else 0
            sweep = 1 if sw > 0 else 0
            parts.append(f"A {fmt(r)},{fmt(r)} 0 {large} {sweep} {fmt(e[0])},{fmt(e[1])}")
        else:
            parts.append("C " + " ".join(f"{fmt(q[0])},{fmt(q[1])}" for q in p[2:]))
        cur = e
    return " ".join(parts)


# ----------------------------------------------------------------------------- DXF helpers
def bulge_vertices(shape):
    """[(x, y, bulge)] for an LWPOLYLINE made of lines and arcs (bulge = tan(sweep/4))."""
    out = []
    for p in shape:
        s = prim_start(p)
        b = math.tan(p[4] / 4) if p[0] == "A" else 0.0
        out.append((float(s[0]), float(s[1]), b))
    e = end(shape)
    out.append((float(e[0]), float(e[1]), 0.0))
    return out


# ----------------------------------------------------------------------------- base shapes (mm, y up)
def arc_shape(R, deg, a0_deg=-90.0, c=None):
    """Arc of radius R through `deg` (signed); by default it starts at the origin heading +x."""
    if c is None:
        c = (0.0, R if deg > 0 else -R)
        a0_deg = -90.0 if deg > 0 else 90.0
    return [("A", P(*c), float(R), math.radians(a0_deg), math.radians(deg))]


def fillet_polyline(points, radius):
    """Polyline with every inner corner rounded by a tangent arc of `radius`."""
    pts = [P(*p) for p in points]
    shape = []
    cur = pts[0]
    for i in range(1, len(pts) - 1):
        a, b, c = pts[i - 1], pts[i], pts[i + 1]
        u = (b - a) / np.hypot(*(b - a))
        v = (c - b) / np.hypot(*(c - b))
        th = _angle_between(u, v)  # signed deflection
        t = radius * math.tan(abs(th) / 2)
        p1 = b - u * t
        p2 = b + v * t
        nrm = np.array([-u[1], u[0]]) * math.copysign(1, th)
        cen = p1 + nrm * radius
        a0 = math.atan2(p1[1] - cen[1], p1[0] - cen[0])
        shape.append(("L", cur, p1))
        shape.append(("A", cen, float(radius), a0, th))
        cur = p2
    shape.append(("L", cur, pts[-1]))
    return shape


def sine_bezier(amp, wavelength, n_waves, n_per_wave=8):
    """Sine y = amp*sin(2*pi*x/wavelength) as a C1 cubic Bezier chain (Hermite through samples).
    The Bezier chain itself is the construction (its length is integrated exactly)."""
    n = n_per_wave * n_waves
    xs = np.linspace(0, wavelength * n_waves, n + 1)
    k = 2 * math.pi / wavelength
    ys = amp * np.sin(k * xs)
    dy = amp * k * np.cos(k * xs)
    shape = []
    for i in range(n):
        h = xs[i + 1] - xs[i]
        p0 = P(xs[i], ys[i]); p3 = P(xs[i + 1], ys[i + 1])
        p1 = p0 + np.array([h / 3, dy[i] * h / 3])
        p2 = p3 - np.array([h / 3, dy[i + 1] * h / 3])
        shape.append(("C", p0, p1, p2, p3))
    return shape


def base_shapes():
    """Named base shapes, each starting at the origin (design frame, mm, y up)."""
    S = {}
    S["arc90"] = arc_shape(125, 90)                       # R125 through 90 deg: 196.350 mm
    S["s2arc"] = (arc_shape(100, 90, -90, (0, 100))       # S: two R100 quarter arcs, CCW then CW
                  + arc_shape(100, -90, 180, (200, 100)))
    S["hook"] = [("L", P(0, 0), P(150, 0))] + arc_shape(60, 180, -90, (150, 60))
    S["c270"] = arc_shape(80, 270, -90, (0, 80))          # C: R80 through 270 deg
    S["sine"] = sine_bezier(15, 200, 2)                   # A15, lambda 200, two waves
    S["mround"] = fillet_polyline([(0, 0), (80, 100), (160, 40), (240, 100), (320, 0)], 50)
    S["bezier"] = [("C", P(0, 0), P(80, 120), P(220, 120), P(300, 0))]
    S["line"] = [("L", P(0, 0), P(200, 0))]
    S["arc_tiny"] = arc_shape(12.35, 45)                  # 9.70 mm long: too short
    return S


def summary(shape):
    return dict(length=length(shape), start=start(shape), end=end(shape),
                turn_deg=math.degrees(turn(shape)), min_radius=min_radius(shape),
                corner_deg=corners(shape))


if __name__ == "__main__":
    for k, s in base_shapes().items():
        d = summary(s)
        print(f"{k:9s} L={d['length']:9.3f} turn={d['turn_deg']:8.2f} Rmin={d['min_radius']:8.1f} "
              f"corner={d['corner_deg']:.2g} start={np.round(d['start'],3)} end={np.round(d['end'],3)}")


def ellipse_arc_length(a, b, t0, t1, n=4000):
    """Length of x = a cos t, y = b sin t for t in [t0, t1] (Gauss-Legendre, 64 panels)."""
    total = 0.0
    edges = np.linspace(t0, t1, 65)
    for lo, hi in zip(edges[:-1], edges[1:]):
        t = 0.5 * (hi - lo) * _GX + 0.5 * (hi + lo)
        total += 0.5 * (hi - lo) * float(np.sum(_GW * np.hypot(a * np.sin(t), b * np.cos(t))))
    return total


def heading_deg(shape):
    """Direction of the tangent at the start (deg, CCW from +x, in the shape's own frame)."""
    d = prim_dir0(shape[0])
    return math.degrees(math.atan2(d[1], d[0]))


def polyline_heading_deg(pts):
    d = np.asarray(pts[1], float) - np.asarray(pts[0], float)
    return math.degrees(math.atan2(d[1], d[0]))


def shape_from_bulges(verts):
    """Lines/arcs of an open LWPOLYLINE given as [(x, y, bulge)] (bulge of the last vertex ignored)."""
    out = []
    for (x0, y0, b), (x1, y1, _) in zip(verts[:-1], verts[1:]):
        p0, p1 = P(x0, y0), P(x1, y1)
        if abs(b) < 1e-12:
            out.append(("L", p0, p1))
            continue
        sw = 4 * math.atan(b)
        ch = p1 - p0
        c_len = float(np.hypot(*ch))
        R = c_len / (2 * math.sin(abs(sw) / 2))
        mid = (p0 + p1) / 2
        nrm = np.array([-ch[1], ch[0]]) / c_len
        h = R * math.cos(abs(sw) / 2)
        # centre on the left of the chord for a CCW arc of less than 180 deg
        cen = mid + nrm * h * (1 if (sw > 0) == (abs(sw) < math.pi) else -1)
        a0 = math.atan2(p0[1] - cen[1], p0[0] - cen[0])
        out.append(("A", cen, R, a0, sw))
    return out
