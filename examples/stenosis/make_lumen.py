#!/usr/bin/env python3
"""An axisymmetric smooth stenosis (Young & Tsai 1973; Varghese et al. 2007) as an open tube.

r(x) = r0 [1 - (delta/2)(1 + cos(pi x / z0))] for |x| <= z0, r0 elsewhere, about the x axis, in mm.
Writes, into OUTDIR (default: this script's folder):
  stenosis.stl    a binary STL of the open tube (no caps: both end loops are open boundary
                  loops), triangles oriented with outward normals;
  centerline.yml  the flowire YAML network: one branch `stenosed` along the x axis with the
                  radius r(x) at every point.

  /usr/bin/python3 make_lumen.py [OUTDIR] [--delta 0.5] [--r0 2] [--z0 4] [--upstream 20]
                                 [--downstream 60] [--n-theta 64] [--dx-stenosis 0.25]
                                 [--dx-far 1.0] [--dx-centerline 0.5] [--stl NAME] [--yml NAME]
"""
import argparse
import os
import struct

import numpy as np


def radius(x, r0, z0, delta):
    x = np.asarray(x, dtype=float)
    r = np.full_like(x, r0)
    inside = np.abs(x) <= z0
    r[inside] = r0 * (1.0 - 0.5 * delta * (1.0 + np.cos(np.pi * x[inside] / z0)))
    return r


def stations(x0, x1, z0, dx_sten, dx_far):
    """Axial stations: spacing dx_sten over |x| <= z0, growing geometrically (x1.15 per ring) to
    at most dx_far away from it."""
    pts = set()
    a, b = max(x0, -z0), min(x1, z0)
    if b > a:
        n = max(1, int(np.ceil((b - a) / dx_sten - 1e-9)))
        pts.update(np.linspace(a, b, n + 1).round(12))

    def grow(start, end, sign):
        # steps dx_sten * 1.15^k capped at dx_far until they cover the length, then all
        # scaled down by the overshoot (so none exceeds dx_far)
        L = abs(end - start)
        steps, k = [], 1
        while sum(steps) < L - 1e-12:
            steps.append(min(dx_sten * 1.15 ** k, dx_far))
            k += 1
        steps = np.array(steps) * (L / sum(steps))
        return list(start + sign * np.cumsum(steps))

    if x1 > z0:
        pts.update(np.round(grow(max(z0, x0), x1, +1), 12))
    if x0 < -z0:
        pts.update(np.round(grow(min(-z0, x1), x0, -1), 12))
    pts.update([round(x0, 12), round(x1, 12)])
    return np.array(sorted(pts))


def tube_triangles(xs, rs, n_theta):
    th = 2.0 * np.pi * np.arange(n_theta) / n_theta
    # vertices: ring i, angle j  ->  (x_i, r_i cos th_j, r_i sin th_j)
    V = np.empty((len(xs), n_theta, 3))
    V[:, :, 0] = xs[:, None]
    V[:, :, 1] = rs[:, None] * np.cos(th)[None, :]
    V[:, :, 2] = rs[:, None] * np.sin(th)[None, :]
    tris = []
    for i in range(len(xs) - 1):
        for j in range(n_theta):
            k = (j + 1) % n_theta
            a, b, c, d = V[i, j], V[i + 1, j], V[i + 1, k], V[i, k]
            # outward normal: (d - a) x (b - a) ~ e_theta x e_x = e_r
            tris.append((a, d, c))
            tris.append((a, c, b))
    T = np.array(tris)  # (n, 3 vertices, 3)
    N = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    N /= np.linalg.norm(N, axis=1)[:, None]
    # check orientation: the normal points away from the axis
    cen = T.mean(axis=1)
    radial = cen.copy()
    radial[:, 0] = 0.0
    assert np.all(np.einsum("ij,ij->i", N, radial) > 0), "inward facet"
    return T, N


def write_stl(path, T, N, name):
    with open(path, "wb") as f:
        header = ("flowire stenosis " + name).encode()[:80].ljust(80, b" ")
        f.write(header)
        f.write(struct.pack("<I", len(T)))
        rec = np.zeros(len(T), dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]))
        rec["n"] = N
        rec["v"] = T
        f.write(rec.tobytes())


def write_yaml(path, xs, rs, args):
    with open(path, "w") as f:
        f.write(
            "# Axisymmetric smooth stenosis (written by make_lumen.py): r(x) = r0 [1 - (delta/2)\n"
            "# (1 + cos(pi x / z0))] for |x| <= z0, r0 elsewhere; r0 = %g mm, z0 = %g mm, delta = %g\n"
            "# (area reduction %.1f%%), from x = %g to %g mm.\n"
            % (args.r0, args.z0, args.delta, 100 * (1 - (1 - args.delta) ** 2), -args.upstream, args.downstream)
        )
        f.write("length_unit: mm\nbranches:\n  - name: stenosed\n    points:\n")
        for x, r in zip(xs, rs):
            f.write("      - [%.4f, 0.0, 0.0, %.5f]\n" % (x, r))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("outdir", nargs="?", default=here)
    p.add_argument("--delta", type=float, default=0.5, help="stenosis severity: throat radius r0 (1 - delta) (default 0.5)")
    p.add_argument("--r0", type=float, default=2.0, help="unobstructed radius, mm (default 2)")
    p.add_argument("--z0", type=float, default=4.0, help="stenosis half-length, mm (default 4)")
    p.add_argument("--upstream", type=float, default=20.0, help="tube length before the throat, mm (default 20)")
    p.add_argument("--downstream", type=float, default=60.0, help="tube length after the throat, mm (default 60)")
    p.add_argument("--n-theta", type=int, default=64, help="facets around (default 64)")
    p.add_argument("--dx-stenosis", type=float, default=0.25, help="axial spacing in the stenosis, mm (default 0.25)")
    p.add_argument("--dx-far", type=float, default=1.0, help="largest axial spacing away from it, mm (default 1)")
    p.add_argument("--dx-centerline", type=float, default=0.5, help="centerline point spacing, mm (default 0.5)")
    p.add_argument("--stl", default="stenosis.stl", help="STL file name (default stenosis.stl)")
    p.add_argument("--yml", default="centerline.yml", help="centerline file name (default centerline.yml)")
    args = p.parse_args()
    if not 0.0 <= args.delta < 1.0:
        p.error("--delta must be in [0, 1)")

    x0, x1 = -args.upstream, args.downstream
    xs = stations(x0, x1, args.z0, args.dx_stenosis, args.dx_far)
    rs = radius(xs, args.r0, args.z0, args.delta)
    T, N = tube_triangles(xs, rs, args.n_theta)

    n_c = int(round((x1 - x0) / args.dx_centerline))
    xc = np.linspace(x0, x1, n_c + 1)
    rc = radius(xc, args.r0, args.z0, args.delta)

    os.makedirs(args.outdir, exist_ok=True)
    stl = os.path.join(args.outdir, args.stl)
    yml = os.path.join(args.outdir, args.yml)
    write_stl(stl, T, N, "delta=%g" % args.delta)
    write_yaml(yml, xc, rc, args)
    print("%s: %d triangles, %d rings (dx %.3g..%.3g mm), throat radius %.4g mm" % (
        stl, len(T), len(xs), np.diff(xs).min(), np.diff(xs).max(), rs.min()))
    print("%s: %d points" % (yml, len(xc)))


if __name__ == "__main__":
    main()
