#!/usr/bin/env python3
# Usage: python3 scripts/tin_plane_fit.py [--border-rings N] [--min-views V] [--box X0 Y0 Z0 X1 Y1 Z1] RUN/tin.ply ...
# Total-least-squares plane through the tin.ply vertices, residuals against the per-vertex
# sigma (docs/EXPERIMENTS.md, fountain wall).
#   --border-rings N  leave out the vertices within N edge rings of the TIN's border (the
#                     ROI border strip, where the surface frays: its vertices see the
#                     surface beyond the ROI cut off); 0 = keep all (default)
#   --min-views V     leave out flagged vertices: seen by fewer than V images (the engine's
#                     min_views, default 2) or without a sigma (fixed, not estimated)
#   --box ...         fit only the vertices inside this box (local coordinates of tin.ply,
#                     e.g. one flat wall area of a whole-facade run); the border rings are
#                     still those of the whole TIN
import collections, struct, sys, math


# Small vector helpers and a ray-triangle test, shared with tin_compare.py and tin_tie_points.py.
def sub(a, b): return [a[i] - b[i] for i in range(3)]
def dot(a, b): return sum(a[i] * b[i] for i in range(3))
def cross(a, b): return [a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0]]


def ray_triangle(o, d, a, b, c):
    """Moeller-Trumbore: (t, u, w) of the line o + t d through triangle abc (t of either
    sign; the hit is (1-u-w) a + u b + w c), or None when the line misses it."""
    e1, e2 = sub(b, a), sub(c, a)
    h = cross(d, e2); det = dot(e1, h)
    if abs(det) < 1e-15: return None
    s = sub(o, a); u = dot(s, h) / det
    if u < 0 or u > 1: return None
    q = cross(s, e1); w = dot(d, q) / det
    if w < 0 or u + w > 1: return None
    return dot(e2, q) / det, u, w

def read(path):
    data = open(path, 'rb').read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    header = data[:end].decode()
    props = [l.split()[2] for l in header.splitlines() if l.startswith('property') and 'list' not in l]
    nv = int([l for l in header.splitlines() if l.startswith('element vertex')][0].split()[2])
    faces_line = [l for l in header.splitlines() if l.startswith('element face')]
    nf = int(faces_line[0].split()[2]) if faces_line else 0
    types = {'x': 'd', 'y': 'd', 'z': 'd', 'nx': 'f', 'ny': 'f', 'nz': 'f', 'sigma': 'f', 'views': 'i'}
    fmt = '<' + ''.join(types[p] for p in props)
    size = struct.calcsize(fmt)
    vs = [dict(zip(props, struct.unpack_from(fmt, data, end + i * size))) for i in range(nv)]
    faces, off = [], end + nv * size
    for _ in range(nf):
        n = data[off]
        faces.append(struct.unpack_from('<%di' % n, data, off + 1))
        off += 1 + 4 * n
    return vs, faces


def border_rings(nv, faces):
    # Edge-ring distance of every vertex from the TIN's border (edges used by one face).
    uses = collections.Counter()
    for f in faces:
        for i in range(len(f)):
            a, b = f[i], f[(i + 1) % len(f)]
            uses[(min(a, b), max(a, b))] += 1
    nbr = collections.defaultdict(set)
    for a, b in uses:
        nbr[a].add(b)
        nbr[b].add(a)
    ring = {v: 0 for e, c in uses.items() if c == 1 for v in e}
    queue = collections.deque(ring)
    while queue:
        v = queue.popleft()
        for w in nbr[v]:
            if w not in ring:
                ring[w] = ring[v] + 1
                queue.append(w)
    return [ring.get(i, 1 << 30) for i in range(nv)]


def smallest_eigvec(C):
    # Jacobi rotations on a symmetric 3x3
    A = [row[:] for row in C]; V = [[1.0 if i==j else 0.0 for j in range(3)] for i in range(3)]
    for _ in range(50):
        p, q = max(((i,j) for i in range(3) for j in range(i+1,3)), key=lambda t: abs(A[t[0]][t[1]]))
        if abs(A[p][q]) < 1e-18: break
        th = 0.5*math.atan2(2*A[p][q], A[q][q]-A[p][p]); c, s = math.cos(th), math.sin(th)
        for k in range(3):
            akp, akq = A[k][p], A[k][q]; A[k][p] = c*akp - s*akq; A[k][q] = s*akp + c*akq
        for k in range(3):
            apk, aqk = A[p][k], A[q][k]; A[p][k] = c*apk - s*aqk; A[q][k] = s*apk + c*aqk
        for k in range(3):
            vkp, vkq = V[k][p], V[k][q]; V[k][p] = c*vkp - s*vkq; V[k][q] = s*vkp + c*vkq
    i = min(range(3), key=lambda i: A[i][i]); return [V[k][i] for k in range(3)]


def main(argv):
    rings, min_views, paths, box = 0, 0, [], None
    it = iter(argv)
    for a in it:
        if a == '--border-rings': rings = int(next(it))
        elif a == '--min-views': min_views = int(next(it))
        elif a == '--box': box = [float(next(it)) for _ in range(6)]
        else: paths.append(a)
    for path in paths:
        vs, faces = read(path)
        ring = border_rings(len(vs), faces) if rings > 0 else [1 << 30] * len(vs)
        inside = lambda v: box is None or all(box[i] <= v[k] <= box[i + 3] for i, k in enumerate('xyz'))
        keep = [v for v, r in zip(vs, ring) if r >= rings and inside(v) and
                (min_views <= 0 or (v.get('views', min_views) >= min_views and v.get('sigma', 1.0) > 0.0))]
        n = len(keep)
        if n < 3:
            sys.exit(f'{path}: only {n} vertices left after the exclusions')
        P = [(v['x'], v['y'], v['z']) for v in keep]
        m = [sum(p[i] for p in P)/n for i in range(3)]
        C = [[sum((p[i]-m[i])*(p[j]-m[j]) for p in P)/n for j in range(3)] for i in range(3)]
        nrm = smallest_eigvec(C)
        res = [sum((p[i]-m[i])*nrm[i] for i in range(3)) for p in P]
        r = sorted(abs(x) for x in res)
        rms = math.sqrt(sum(x*x for x in r)/n)
        sig = sorted(v['sigma'] for v in keep if 'sigma' in v)
        within = sum(1 for v, x in zip(keep, res) if abs(x) <= 3*v.get('sigma', 0.0)) / n * 100
        what = f'{n} of {len(vs)} vertices' + ('' if box is None else ' in the box')
        if rings > 0: what += f' (border strip of {rings} rings left out'
        if min_views > 0: what += (', ' if rings > 0 else ' (') + f'flagged: < {min_views} views or no sigma, left out'
        if rings > 0 or min_views > 0: what += ')'
        print(f'{path}: {what}, plane residual RMS {1000*rms:.1f} mm, median {1000*r[n//2]:.1f} mm, p90 {1000*r[int(0.9*n)]:.1f} mm; '
              f'vertex sigma median {1000*sig[len(sig)//2]:.2f} mm, p90 {1000*sig[int(0.9*len(sig))]:.2f} mm; '
              f'RMS / median sigma {rms/max(sig[len(sig)//2], 1e-30):.1f}; share of |r| <= 3 sigma_i: {within:.1f} %')


if __name__ == '__main__':
    main(sys.argv[1:])
