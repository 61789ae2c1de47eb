#!/usr/bin/env python3
# Usage: python3 scripts/tin_compare.py [--border-rings N] [--box X0 Y0 Z0 X1 Y1 Z1] [--max-distance D] A/tin.ply B/tin.ply
# Repeatability of two reconstructions of the same surface (e.g. from disjoint image sets,
# docs/EXPERIMENTS.md, fountain): for each vertex of A (inside the box, not within N edge
# rings of A's border, seen by >= 2 images, with a sigma) the distance d along its normal to
# the TIN of B (nearest hit within D, default 0.1 m), against s = sqrt(sigma_A^2 + sigma_B^2),
# sigma_B interpolated at the hit. With honest, independent sigmas d / s has rms 1 and
# 99.7 % of |d / s| lie within 3 (median |d / s| 0.67).
import collections, math, os, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tin_plane_fit import read, border_rings, smallest_eigvec, sub, dot, cross, ray_triangle  # noqa: E402


def main(argv):
    rings, box, dmax, paths = 0, None, 0.1, []
    it = iter(argv)
    for a in it:
        if a == '--border-rings': rings = int(next(it))
        elif a == '--box': box = [float(next(it)) for _ in range(6)]
        elif a == '--max-distance': dmax = float(next(it))
        else: paths.append(a)
    if len(paths) != 2: sys.exit('usage: tin_compare.py [options] A/tin.ply B/tin.ply')
    va, fa = read(paths[0])
    vb, fb = read(paths[1])
    ring = border_rings(len(va), fa) if rings > 0 else [1 << 30] * len(va)
    inside = lambda v: box is None or all(box[i] <= v[k] <= box[i + 3] for i, k in enumerate('xyz'))
    sel = [i for i, v in enumerate(va) if ring[i] >= rings and inside(v) and v.get('views', 2) >= 2 and v.get('sigma', 0) > 0]
    if not sel: sys.exit(f'{paths[0]}: no vertex selected')
    # Plane of the selection for a 2D grid of B's faces.
    P = [(va[i]['x'], va[i]['y'], va[i]['z']) for i in sel]
    m = [sum(p[k] for p in P) / len(P) for k in range(3)]
    C = [[sum((p[r]-m[r])*(p[c]-m[c]) for p in P) / len(P) for c in range(3)] for r in range(3)]
    n = smallest_eigvec(C)
    e1 = cross(n, [1, 0, 0]) if abs(n[0]) < 0.9 else cross(n, [0, 1, 0])
    l = math.sqrt(dot(e1, e1)); e1 = [x / l for x in e1]; e2 = cross(n, e1)
    uv = lambda p: (dot(sub(p, m), e1), dot(sub(p, m), e2))
    cell = max(2 * dmax, 0.05)
    grid = collections.defaultdict(list)
    PB = [(v['x'], v['y'], v['z']) for v in vb]
    for k, f in enumerate(fb):
        us = [uv(PB[i]) for i in f]
        for gu in range(math.floor(min(u for u, _ in us) / cell), math.floor(max(u for u, _ in us) / cell) + 1):
            for gv in range(math.floor(min(v for _, v in us) / cell), math.floor(max(v for _, v in us) / cell) + 1):
                grid[(gu, gv)].append(k)
    ds, ratios = [], []
    for i in sel:
        v = va[i]
        o = [v['x'], v['y'], v['z']]
        nv = [v['nx'], v['ny'], v['nz']]
        u0, v0 = uv(o)
        best = None
        for k in grid.get((math.floor(u0 / cell), math.floor(v0 / cell)), []):
            hit = ray_triangle(o, nv, *(PB[j] for j in fb[k]))
            if hit is None: continue
            t, bu, bw = hit
            if abs(t) <= dmax and (best is None or abs(t) < abs(best[0])):
                sb = (1 - bu - bw) * vb[fb[k][0]].get('sigma', 0) + bu * vb[fb[k][1]].get('sigma', 0) + bw * vb[fb[k][2]].get('sigma', 0)
                best = (t, sb)
        if best is None: continue
        d, sb = best
        ds.append(d)
        ratios.append(d / math.sqrt(v['sigma'] ** 2 + sb ** 2))
    if not ds: sys.exit('no vertex of A meets B within the distance')
    ad = sorted(abs(x) for x in ds)
    ar = sorted(abs(x) for x in ratios)
    nn = len(ds)
    print(f'{paths[0]} -> {paths[1]}: {nn} of {len(sel)} selected vertices meet B within {1000*dmax:.0f} mm; '
          f'|d| rms {1000*math.sqrt(sum(x*x for x in ds)/nn):.1f} mm, median {1000*ad[nn//2]:.1f} mm, p90 {1000*ad[int(0.9*nn)]:.1f} mm; '
          f'd/s rms {math.sqrt(sum(x*x for x in ratios)/nn):.2f}, median |d/s| {ar[nn//2]:.2f}, within 3 s {100*sum(1 for x in ar if x <= 3)/nn:.1f} %')


if __name__ == '__main__':
    main(sys.argv[1:])
