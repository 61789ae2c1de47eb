#!/usr/bin/env python3
# Usage: python3 scripts/snap_to_truth.py RUN/tin.ply SCENE/truth.ply OUT.ply [--bands STEP]
# The oracle start of docs/EXPERIMENTS.md (walls, session 8): every vertex of a run's TIN
# moved to its closest point on the rendered truth mesh, same triangles, written as a
# PLY that `facets reconstruct --start-mesh OUT.ply --levels 1` takes. It tells how well
# the finest level holds a surface that starts right, apart from how the multigrid gets
# there. Prints how far the vertices moved (wall-like: |nz| < 0.5; views < 2 / >= 2).
# OUT.ply "-": nothing written (only the distances). --bands STEP: the wall-like
# vertices' distances per height band of STEP m (where a level loses its walls: eaves and
# feet or all over, docs/EXPERIMENTS.md session 11). Works on the levels/level_K.ply of
# `--keep-levels` too (they carry no views).
# Needs numpy (Debian: python3-numpy, run with /usr/bin/python3).
import sys, numpy as np
band_step = None
if '--bands' in sys.argv:
    k = sys.argv.index('--bands'); band_step = float(sys.argv[k + 1]); del sys.argv[k:k + 2]
def read_ply(path):
    f = open(path, 'rb'); props = []; elems = []
    while True:
        l = f.readline().decode().strip()
        if l.startswith('element'):
            _, n, c = l.split(); elems.append((n, int(c), []))
        elif l.startswith('property'):
            elems[-1][2].append(l.split()[1:])
        elif l == 'end_header': break
    hdr_end = f.tell(); data = f.read()
    return elems, hdr_end, data
tmap = {'double': 'f8', 'float': 'f4', 'int': 'i4', 'uchar': 'u1'}
def vertices(elems, data):
    n, c, props = elems[0]
    dt = np.dtype([(p[1], '<' + tmap[p[0]]) for p in props])
    v = np.frombuffer(data, dtype=dt, count=c)
    return v, c * dt.itemsize
def faces_tri(data, off, count, extra):
    # list uchar int + extra int fields
    dt = np.dtype([('n', 'u1'), ('i', '<i4', 3)] + [(e, '<i4') for e in extra])
    return np.frombuffer(data, dtype=dt, count=count, offset=off)
elems, h, data = read_ply(sys.argv[2])
tv, off = vertices(elems, data)
tf = faces_tri(data, off, elems[1][1], [p[1] for p in elems[1][2][1:]])
P = np.stack([tv['x'], tv['y'], tv['z']], 1); F = tf['i']
A, B, C = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
elems2, h2, data2 = read_ply(sys.argv[1])
v, _ = vertices(elems2, data2)
Q = np.stack([v['x'], v['y'], v['z']], 1)
lo = Q.min(0) - 2; hi = Q.max(0) + 2
keep = np.all((np.minimum(np.minimum(A, B), C) <= hi) & (np.maximum(np.maximum(A, B), C) >= lo), 1)
A, B, C = A[keep], B[keep], C[keep]
print('truth triangles near the TIN:', len(A), file=sys.stderr)
def closest(p):
    # Ericson, vectorised over triangles
    ab = B - A; ac = C - A; ap = p - A
    d1 = (ab * ap).sum(1); d2 = (ac * ap).sum(1)
    bp = p - B; d3 = (ab * bp).sum(1); d4 = (ac * bp).sum(1)
    cp = p - C; d5 = (ab * cp).sum(1); d6 = (ac * cp).sum(1)
    vc = d1 * d4 - d3 * d2; vb = d5 * d2 - d1 * d6; va = d3 * d6 - d5 * d4
    denom = va + vb + vc; denom[denom == 0] = 1e-300
    v_ = vb / denom; w_ = vc / denom
    res = A + ab * v_[:, None] + ac * w_[:, None]
    def setm(m, val):
        res[m] = val[m]
    with np.errstate(divide='ignore', invalid='ignore'):
        m = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6)); setm(m, B + (C - B) * w[:, None])
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0); w = d2 / (d2 - d6); setm(m, A + ac * w[:, None])
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0); v2 = d1 / (d1 - d3); setm(m, A + ab * v2[:, None])
        setm((d6 >= 0) & (d5 <= d6), C); setm((d3 >= 0) & (d4 <= d3), B); setm((d1 <= 0) & (d2 <= 0), A)
    dist = ((res - p) ** 2).sum(1); i = np.argmin(dist)
    return res[i], np.sqrt(dist[i])
out = Q.copy(); ds = []
for k in range(len(Q)):
    out[k], d = closest(Q[k]); ds.append(d)
ds = np.array(ds)
print('moved: median %.3f p90 %.3f max %.3f m' % (np.median(ds), np.percentile(ds, 90), ds.max()), file=sys.stderr)
v2 = v.copy(); v2['x'] = out[:, 0]; v2['y'] = out[:, 1]; v2['z'] = out[:, 2]
if sys.argv[3] != '-':
    with open(sys.argv[3], 'wb') as f:
        f.write(open(sys.argv[1], 'rb').read(h2)); f.write(v2.tobytes()); f.write(data2[v.nbytes:])
nz = np.abs(v['nz']); wall = nz < 0.5
for name, m in [('wall-like', wall), ('flat', ~wall)]:
    d = ds[m]
    if len(d): print('%s: %d vertices, median %.3f p75 %.3f p90 %.3f, >0.12 m %.1f %%, >0.5 m %.1f %%' % (name, len(d), np.median(d), np.percentile(d, 75), np.percentile(d, 90), 100*np.mean(d > 0.12), 100*np.mean(d > 0.5)), file=sys.stderr)
if 'views' in v.dtype.names:
    vw = v['views']
    for name, m in [('views<2', vw < 2), ('views>=2', vw >= 2)]:
        d = ds[m]
        if len(d): print('%s: %d, median %.3f p90 %.3f' % (name, len(d), np.median(d), np.percentile(d, 90)), file=sys.stderr)
if band_step:
    z = Q[:, 2]
    for lo in np.arange(np.floor(z[wall].min() / band_step) * band_step, z[wall].max() + 1e-9, band_step):
        m = wall & (z >= lo) & (z < lo + band_step)
        if m.sum():
            d = ds[m]
            print('wall-like z %6.1f..%6.1f m: %4d vertices, median %.3f p75 %.3f p90 %.3f m, >0.12 m %3.0f %%' % (
                lo, lo + band_step, m.sum(), np.median(d), np.percentile(d, 75), np.percentile(d, 90), 100 * np.mean(d > 0.12)), file=sys.stderr)
