#!/usr/bin/env python3
# Usage: python3 scripts/tin_wall_tie_points.py COLMAP_DIR RUN/tin.ply --wall NAME X0 Y0 X1 Y1 ZFOOT ZEAVE [--wall ...]
#          [--band 2.5] [--margin 0.5] [--max-error 1.0]
# Independent check of reconstructed walls against the COLMAP tie points on them (issue 9,
# boruszyn_kap; docs/EXPERIMENTS.md): the tie points within --band m (horizontally) of a wall's
# eave line, between its ends, and between ZFOOT + margin and ZEAVE - margin in height (reprojection
# error <= --max-error px). Per wall: how many; their own lean (a line fitted to their horizontal
# offset from the eave line against height, with a 3 x 1.4826 x MAD cut: the wall as the tie points
# see it); and each kept tie point's distance to the TIN (closest point on any face): median, rms.
import math, os, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tin_wall_patches import read_ply  # noqa: E402


def closest_on_triangle(p, a, b, c):
    # Ericson, Real-Time Collision Detection 5.1.5.
    sub = lambda u, v: (u[0] - v[0], u[1] - v[1], u[2] - v[2])
    dot = lambda u, v: u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
    add = lambda u, v, s: (u[0] + s * v[0], u[1] + s * v[1], u[2] + s * v[2])
    ab, ac, ap = sub(b, a), sub(c, a), sub(p, a)
    d1, d2 = dot(ab, ap), dot(ac, ap)
    if d1 <= 0 and d2 <= 0: return a
    bp = sub(p, b); d3, d4 = dot(ab, bp), dot(ac, bp)
    if d3 >= 0 and d4 <= d3: return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0: return add(a, ab, d1 / (d1 - d3))
    cp = sub(p, c); d5, d6 = dot(ab, cp), dot(ac, cp)
    if d6 >= 0 and d5 <= d6: return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0: return add(a, ac, d2 / (d2 - d6))
    va = d3 * d6 - d5 * d4
    if va <= 0 and (d4 - d3) >= 0 and (d5 - d6) >= 0:
        return add(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)))
    denom = 1.0 / (va + vb + vc)
    v, w = vb * denom, vc * denom
    return add(add(a, ab, v), ac, w)


def median(v):
    s = sorted(v); n = len(s)
    return 0.0 if n == 0 else (s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2]))


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__ if __doc__ else 'usage: see the head of this script')
    colmap, tin = args[0], args[1]
    walls, band, margin, max_error = [], 2.5, 0.5, 1.0
    i = 2
    while i < len(args):
        if args[i] == '--wall':
            walls.append((args[i + 1], *map(float, args[i + 2:i + 8]))); i += 8
        elif args[i] == '--band': band = float(args[i + 1]); i += 2
        elif args[i] == '--margin': margin = float(args[i + 1]); i += 2
        elif args[i] == '--max-error': max_error = float(args[i + 1]); i += 2
        else: sys.exit(f'unknown argument {args[i]}')
    pts, _, faces = read_ply(tin)
    tris = [(pts[a], pts[b], pts[c]) for a, b, c in faces]
    ties = []
    for l in open(os.path.join(colmap, 'points3D.txt')):
        if l.startswith('#') or not l.strip(): continue
        t = l.split()
        ties.append((float(t[1]), float(t[2]), float(t[3]), float(t[7])))
    for name, x0, y0, x1, y1, zf, ze in walls:
        dx, dy = x1 - x0, y1 - y0
        length = math.hypot(dx, dy); ux, uy = dx / length, dy / length
        nx, ny = uy, -ux  # a normal of the line; the sign is only a convention of the offsets
        sel = []
        for x, y, z, err in ties:
            if err > max_error or not (zf + margin <= z <= ze - margin): continue
            s = (x - x0) * ux + (y - y0) * uy
            d = (x - x0) * nx + (y - y0) * ny
            if -1.0 <= s <= length + 1.0 and abs(d) <= band: sel.append((x, y, z, d))
        lean, kept = float('nan'), sel
        for _ in range(3):
            if len(kept) < 5: break
            zm = sum(p[2] for p in kept) / len(kept); dm = sum(p[3] for p in kept) / len(kept)
            szz = sum((p[2] - zm) ** 2 for p in kept)
            slope = sum((p[2] - zm) * (p[3] - dm) for p in kept) / szz if szz > 0 else 0.0
            res = [p[3] - dm - slope * (p[2] - zm) for p in kept]
            cut = 3 * 1.4826 * median([abs(r) for r in res])
            lean = math.degrees(math.atan(slope))
            new = [p for p, r in zip(kept, res) if abs(r) <= max(cut, 1e-9)]
            if len(new) == len(kept): break
            kept = new
        dist = []
        bbox = lambda t: (min(v[0] for v in t), max(v[0] for v in t), min(v[1] for v in t), max(v[1] for v in t))
        boxes = [bbox(t) for t in tris]
        for x, y, z, _ in kept:
            best = float('inf')
            for t, (bx0, bx1, by0, by1) in zip(tris, boxes):
                if x < bx0 - 3 or x > bx1 + 3 or y < by0 - 3 or y > by1 + 3: continue
                q = closest_on_triangle((x, y, z), *t)
                best = min(best, math.dist(q, (x, y, z)))
            if best < float('inf'): dist.append(best)
        rms = math.sqrt(sum(d * d for d in dist) / len(dist)) if dist else float('nan')
        print(f'{name}: {len(sel)} tie points in the band, {len(kept)} kept; their lean from vertical '
              f'{lean:.1f} deg; distance to the TIN median {median(dist):.3f} m, rms {rms:.3f} m, '
              f'within 0.25 m {sum(d <= 0.25 for d in dist)} of {len(dist)}')


if __name__ == '__main__':
    main()
