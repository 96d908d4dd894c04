#!/usr/bin/env python3
"""A curved pipe for the Dean-number resistance check: an open tube of circular section swept
along a helical centerline with straight ends, in mm.

Centerline (C1): a straight inlet of length Li, a helix of coil radius Rc and pitch p for
`turns` turns, then a straight outlet of length Lo along the helix's end tangent. The helix is
  h(t) = (Rc cos t, Rc sin t, c t),  c = p / (2 pi),  0 <= t <= 2 pi turns,
with arc length s = t sqrt(Rc^2 + c^2), curvature kappa = Rc / (Rc^2 + c^2) and torsion
tau = c / (Rc^2 + c^2); the inlet runs along h'(0) into h(0), the outlet along h'(end).
The sections are circles of radius a in the planes normal to the centerline, carried by a
rotation-minimizing (parallel-transport, double-reflection) frame.

Writes, into OUTDIR (default: this script's folder):
  coil.stl        a binary STL of the open tube (no caps: both end loops are open boundary
                  loops), triangles oriented with outward normals;
  centerline.yml  the flowire YAML network: one branch `coil`, a point about every
                  --dx-centerline mm from the inlet end (the first point) to the outlet end,
                  each with radius a.

  /usr/bin/python3 make_coil.py [OUTDIR] [--a 2] [--coil-radius 10] [--pitch 6] [--turns 1.5]
                                [--inlet 10] [--outlet 10] [--n-theta 64] [--dx 0.5]
                                [--dx-centerline 0.5] [--stl NAME] [--yml NAME]
"""
import argparse
import os
import struct

import numpy as np


class Centerline:
    """Arc-length parametrized centerline: inlet straight, helix, outlet straight."""

    def __init__(self, Rc, pitch, turns, Li, Lo):
        self.Rc, self.c = Rc, pitch / (2.0 * np.pi)
        self.L = np.hypot(Rc, self.c)  # ds/dt on the helix
        self.t_end = 2.0 * np.pi * turns
        self.Li, self.Lh, self.Lo = Li, self.L * self.t_end, Lo
        self.total = Li + self.Lh + Lo

    def helix(self, t):
        t = np.asarray(t, dtype=float)
        P = np.stack([self.Rc * np.cos(t), self.Rc * np.sin(t), self.c * t], axis=-1)
        T = np.stack([-self.Rc * np.sin(t), self.Rc * np.cos(t), np.full_like(t, self.c)], axis=-1) / self.L
        return P, T

    def __call__(self, s):
        """Points and unit tangents at arc lengths s (0 = inlet end)."""
        s = np.asarray(s, dtype=float)
        P = np.empty(s.shape + (3,))
        T = np.empty(s.shape + (3,))
        P0, T0 = self.helix(0.0)
        P1, T1 = self.helix(self.t_end)
        a = s < self.Li
        b = (s >= self.Li) & (s <= self.Li + self.Lh)
        c = s > self.Li + self.Lh
        P[a] = P0 + (s[a] - self.Li)[:, None] * T0
        T[a] = T0
        P[b], T[b] = self.helix((s[b] - self.Li) / self.L)
        P[c] = P1 + (s[c] - self.Li - self.Lh)[:, None] * T1
        T[c] = T1
        return P, T


def stations(cl, dx):
    """Arc-length stations about dx apart, with the straight/helix joints among them."""
    def seg(s0, s1):
        n = max(1, int(round((s1 - s0) / dx)))
        return np.linspace(s0, s1, n + 1)
    s1, s2 = cl.Li, cl.Li + cl.Lh
    return np.concatenate([seg(0.0, s1)[:-1], seg(s1, s2)[:-1], seg(s2, cl.total)])


def rmf(P, T):
    """Rotation-minimizing frame (Wang, Juettler, Zheng, Liu 2008, double reflection): returns
    the normal U and binormal V = T x U at every station."""
    n = len(P)
    U = np.empty_like(P)
    # the first normal: any unit vector normal to T[0]
    e = np.array([0.0, 0.0, 1.0])
    if abs(np.dot(e, T[0])) > 0.9:
        e = np.array([1.0, 0.0, 0.0])
    u = e - np.dot(e, T[0]) * T[0]
    U[0] = u / np.linalg.norm(u)
    for i in range(n - 1):
        v1 = P[i + 1] - P[i]
        c1 = np.dot(v1, v1)
        rL = U[i] - (2.0 / c1) * np.dot(v1, U[i]) * v1
        tL = T[i] - (2.0 / c1) * np.dot(v1, T[i]) * v1
        v2 = T[i + 1] - tL
        c2 = np.dot(v2, v2)
        u = rL - (2.0 / c2) * np.dot(v2, rL) * v2 if c2 > 1e-30 else rL
        u -= np.dot(u, T[i + 1]) * T[i + 1]
        U[i + 1] = u / np.linalg.norm(u)
    V = np.cross(T, U)
    return U, V


def tube_triangles(P, T, a, n_theta):
    U, V = rmf(P, T)
    th = 2.0 * np.pi * np.arange(n_theta) / n_theta
    # ring i, angle j: P_i + a (cos th_j U_i + sin th_j V_i); (U, V, T) right-handed, so
    # increasing th turns counter-clockwise about T
    R = np.cos(th)[None, :, None] * U[:, None, :] + np.sin(th)[None, :, None] * V[:, None, :]
    X = P[:, None, :] + a * R
    ni = len(P)
    i, j = np.meshgrid(np.arange(ni - 1), np.arange(n_theta), indexing="ij")
    i, j = i.ravel(), j.ravel()
    k = (j + 1) % n_theta
    A, B, C, D = X[i, j], X[i + 1, j], X[i + 1, k], X[i, k]
    # outward: (D - A) x (B - A) ~ e_theta x e_t = e_r
    Tri = np.concatenate([np.stack([A, D, C], axis=1), np.stack([A, C, B], axis=1)])
    N = np.cross(Tri[:, 1] - Tri[:, 0], Tri[:, 2] - Tri[:, 0])
    N /= np.linalg.norm(N, axis=1)[:, None]
    # check orientation: each facet's normal points away from its section's centre
    cen_ring = np.concatenate([0.5 * (P[i] + P[i + 1])] * 2)
    radial = Tri.mean(axis=1) - cen_ring
    assert np.all(np.einsum("ij,ij->i", N, radial) > 0), "inward facet"
    return Tri, N, X


def write_stl(path, Tri, N, name):
    with open(path, "wb") as f:
        f.write(("flowire coil " + name).encode()[:80].ljust(80, b" "))
        f.write(struct.pack("<I", len(Tri)))
        rec = np.zeros(len(Tri), dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]))
        rec["n"] = N
        rec["v"] = Tri
        f.write(rec.tobytes())


def write_yaml(path, P, a, cl, args, kappa, tau):
    with open(path, "w") as f:
        f.write(
            "# Helical curved pipe (written by make_coil.py): radius a = %g mm; straight inlet %g mm,\n"
            "# helix of coil radius %g mm, pitch %g mm, %g turns (arc length %.4f mm; curvature\n"
            "# %.8f /mm, radius of curvature %.6f mm; torsion %.8f /mm), straight outlet %g mm.\n"
            "# The first point is the inlet end.\n"
            % (a, args.inlet, args.coil_radius, args.pitch, args.turns, cl.Lh, kappa, 1.0 / kappa, tau, args.outlet)
        )
        f.write("length_unit: mm\nbranches:\n  - name: coil\n    points:\n")
        for p in P:
            f.write("      - [%.5f, %.5f, %.5f, %.5f]\n" % (p[0], p[1], p[2], a))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("outdir", nargs="?", default=here)
    p.add_argument("--a", type=float, default=2.0, help="tube radius, mm (default 2)")
    p.add_argument("--coil-radius", type=float, default=10.0, help="helix (coil) radius Rc, mm (default 10)")
    p.add_argument("--pitch", type=float, default=6.0, help="helix pitch, mm per turn (default 6)")
    p.add_argument("--turns", type=float, default=1.5, help="helix turns (default 1.5)")
    p.add_argument("--inlet", type=float, default=10.0, help="straight inlet length, mm (default 10)")
    p.add_argument("--outlet", type=float, default=10.0, help="straight outlet length, mm (default 10)")
    p.add_argument("--n-theta", type=int, default=64, help="facets around (default 64)")
    p.add_argument("--dx", type=float, default=0.5, help="axial spacing of the rings, mm (default 0.5)")
    p.add_argument("--dx-centerline", type=float, default=0.5, help="centerline point spacing, mm (default 0.5)")
    p.add_argument("--stl", default="coil.stl", help="STL file name (default coil.stl)")
    p.add_argument("--yml", default="centerline.yml", help="centerline file name (default centerline.yml)")
    args = p.parse_args()
    if args.pitch <= 2.0 * args.a and args.turns > 1.0:
        p.error("--pitch must exceed the tube diameter 2 a, or the turns touch")
    if args.coil_radius <= args.a:
        p.error("--coil-radius must exceed --a")

    cl = Centerline(args.coil_radius, args.pitch, args.turns, args.inlet, args.outlet)
    Rc, c = cl.Rc, cl.c
    kappa = Rc / (Rc ** 2 + c ** 2)
    tau = c / (Rc ** 2 + c ** 2)

    s = stations(cl, args.dx)
    P, T = cl(s)
    Tri, N, X = tube_triangles(P, T, args.a, args.n_theta)

    n_c = int(round(cl.total / args.dx_centerline))
    sc = np.linspace(0.0, cl.total, n_c + 1)
    Pc, _ = cl(sc)

    os.makedirs(args.outdir, exist_ok=True)
    stl = os.path.join(args.outdir, args.stl)
    yml = os.path.join(args.outdir, args.yml)
    write_stl(stl, Tri, N, "a=%g Rc=%g pitch=%g turns=%g" % (args.a, Rc, args.pitch, args.turns))
    write_yaml(yml, Pc, args.a, cl, args, kappa, tau)

    ds = np.diff(s)
    print("%s: %d triangles, %d rings (dx %.4g..%.4g mm), %d around" % (
        stl, len(Tri), len(s), ds.min(), ds.max(), args.n_theta))
    print("%s: %d points, spacing %.5f mm, from %s (inlet end, node 0) to %s" % (
        yml, len(sc), cl.total / n_c, np.round(Pc[0], 4).tolist(), np.round(Pc[-1], 4).tolist()))
    print("centerline: inlet 0 .. %.4f mm, helix %.4f .. %.4f mm (length %.4f), outlet .. %.4f mm" % (
        cl.Li, cl.Li, cl.Li + cl.Lh, cl.Lh, cl.total))
    print("helix: c = pitch/(2 pi) = %.8f mm; curvature kappa = Rc/(Rc^2 + c^2) = %.8f /mm "
          "(radius of curvature %.6f mm, a kappa = %.6f); torsion c/(Rc^2 + c^2) = %.8f /mm" % (
              c, kappa, 1.0 / kappa, args.a * kappa, tau))
    # clearance between turns: nearest centerline points more than half a turn apart along s
    Q = P[::4]
    sQ = s[::4]
    d = np.linalg.norm(Q[:, None, :] - Q[None, :, :], axis=2)
    far = np.abs(sQ[:, None] - sQ[None, :]) > np.pi * cl.L
    if np.any(far):
        print("smallest centerline distance between points more than half a turn apart: %.4f mm "
              "(wall clearance %.4f mm)" % (d[far].min(), d[far].min() - 2 * args.a))


if __name__ == "__main__":
    main()
