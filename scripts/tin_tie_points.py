#!/usr/bin/env python3
# Usage: python3 scripts/tin_tie_points.py COLMAP_DIR RUN/tin.ply XMIN YMIN ZMIN XMAX YMAX ZMAX
# Independent check of a (nearly planar) reconstructed wall against the COLMAP tie points in
# the ROI box (docs/EXPERIMENTS.md, fountain wall):
#  - total-least-squares plane through the tie points (3 x 1.4826 x MAD cut), their scatter;
#  - each tie point's own standard deviation along the plane normal: covariance of its
#    triangulation from its track (pinhole cameras; image sigma = the point's reprojection
#    error, scaled by sqrt(2n / (2n - 3)) for n images);
#  - the distance from each kept tie point along the plane normal to the TIN.
import math, os, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tin_plane_fit import read, smallest_eigvec, sub, dot, cross, ray_triangle  # noqa: E402


def read_colmap(folder):
    lines = lambda name: [l for l in open(os.path.join(folder, name)) if l.strip() and not l.startswith('#')]
    cameras = {}
    for l in lines('cameras.txt'):
        t = l.split()
        p = list(map(float, t[4:]))
        if t[1] == 'PINHOLE': cameras[int(t[0])] = (p[0], p[1])
        elif t[1] in ('SIMPLE_PINHOLE', 'SIMPLE_RADIAL', 'RADIAL'): cameras[int(t[0])] = (p[0], p[0])
        else: cameras[int(t[0])] = (p[0], p[1])  # OPENCV: fx fy first; distortion ignored here
    images = {}
    rows = lines('images.txt')
    for l in rows[0::2]:
        t = l.split()
        qw, qx, qy, qz, tx, ty, tz = map(float, t[1:8])
        R = [[1-2*(qy*qy+qz*qz), 2*(qx*qy-qz*qw), 2*(qx*qz+qy*qw)],
             [2*(qx*qy+qz*qw), 1-2*(qx*qx+qz*qz), 2*(qy*qz-qx*qw)],
             [2*(qx*qz-qy*qw), 2*(qy*qz+qx*qw), 1-2*(qx*qx+qy*qy)]]
        images[int(t[0])] = (R, (tx, ty, tz), cameras[int(t[8])])
    points = []
    for l in lines('points3D.txt'):
        t = l.split()
        track = sorted({int(t[8 + 2 * k]) for k in range((len(t) - 8) // 2)})
        points.append((list(map(float, t[1:4])), float(t[7]), track))
    return images, points


def normal_sigma(X, err, track, images, n):
    N = [[0.0] * 3 for _ in range(3)]
    for k in track:
        R, t, (fx, fy) = images[k]
        c = [dot(R[i], X) + t[i] for i in range(3)]
        for row, f in ((0, fx), (1, fy)):
            J = [f / c[2] * (R[row][j] - c[row] / c[2] * R[2][j]) for j in range(3)]
            for i in range(3):
                for j in range(3): N[i][j] += J[i] * J[j]
    a, b, c_ = N[0]; d, e, f = N[1]; g, h, i = N[2]
    det = a*(e*i-f*h) - b*(d*i-f*g) + c_*(d*h-e*g)
    if abs(det) < 1e-30: return None
    C = [[(e*i-f*h)/det, (c_*h-b*i)/det, (b*f-c_*e)/det], [(f*g-d*i)/det, (a*i-c_*g)/det, (c_*d-a*f)/det],
         [(d*h-e*g)/det, (b*g-a*h)/det, (a*e-b*d)/det]]
    m = len(track)
    image_sigma = err * math.sqrt(2 * m / max(2 * m - 3, 1))
    return image_sigma * math.sqrt(max(sum(n[r] * C[r][s] * n[s] for r in range(3) for s in range(3)), 0.0))


def main(argv):
    if len(argv) != 8:
        sys.exit(__doc__ or 'usage: tin_tie_points.py COLMAP_DIR RUN/tin.ply XMIN YMIN ZMIN XMAX YMAX ZMAX')
    folder, tin = argv[0], argv[1]
    roi = list(map(float, argv[2:8]))
    images, points = read_colmap(folder)
    pts = [p for p in points if all(roi[i] <= p[0][i] <= roi[i + 3] for i in range(3))]
    if len(pts) < 3: sys.exit(f'{folder}: only {len(pts)} tie points in the ROI')
    n = len(pts)
    m = [sum(p[0][i] for p in pts) / n for i in range(3)]
    C = [[sum((p[0][i]-m[i])*(p[0][j]-m[j]) for p in pts) / n for j in range(3)] for i in range(3)]
    nrm = smallest_eigvec(C)
    res = [dot(sub(p[0], m), nrm) for p in pts]
    mad = sorted(abs(r) for r in res)[n // 2]
    keep = [k for k in range(n) if abs(res[k]) <= 3 * 1.4826 * mad]
    scatter = math.sqrt(sum(res[k] ** 2 for k in keep) / len(keep))
    own = [s for s in (normal_sigma(pts[k][0], pts[k][1], pts[k][2], images, nrm) for k in keep) if s is not None]
    own_rms = math.sqrt(sum(s * s for s in own) / len(own))
    relief = math.sqrt(max(scatter ** 2 - own_rms ** 2, 0.0))
    vs, faces = read(tin)
    P = [(v['x'], v['y'], v['z']) for v in vs]
    # Only the faces near the box (a whole-facade TIN has tens of thousands): a vertex
    # within 0.5 m of it.
    near = lambda p: all(roi[i] - 0.5 <= p[i] <= roi[i + 3] + 0.5 for i in range(3))
    faces = [f for f in faces if any(near(P[i]) for i in f)]
    dist, plane_of_tin = [], []
    for k in keep:
        o = pts[k][0]
        best = None
        for f in faces:
            hit = ray_triangle(o, nrm, P[f[0]], P[f[1]], P[f[2]])
            if hit is None: continue
            t = hit[0]
            if best is None or abs(t) < abs(best): best = t
        if best is not None:
            dist.append(best)
            plane_of_tin.append(res[k] + best)
    print(f'{tin}: {n} tie points in the ROI, {len(keep)} kept; their scatter about their plane {1000*scatter:.1f} mm rms, '
          f'their own sigma along its normal {1000*own_rms:.1f} mm rms (median {1000*sorted(own)[len(own)//2]:.1f}), '
          f'relief sqrt(scatter^2 - own^2) {1000*relief:.1f} mm rms')
    if dist:
        d = sorted(abs(x) for x in dist)
        print(f'  {len(dist)} kept tie points meet the TIN along the normal: distance rms {1000*math.sqrt(sum(x*x for x in dist)/len(dist)):.1f} mm, '
              f'median {1000*d[len(d)//2]:.1f} mm; the TIN there lies {1000*math.sqrt(sum(x*x for x in plane_of_tin)/len(plane_of_tin)):.1f} mm rms off the tie points\' plane')


if __name__ == '__main__':
    main(sys.argv[1:])
