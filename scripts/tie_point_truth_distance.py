#!/usr/bin/env python3
"""Usage: python3 scripts/tie_point_truth_distance.py POINTS3D.txt TRUTH.ply [--outlier 0.5]

How far a COLMAP text model's 3D points lie from a rendered scene's truth surface
(truth.ply as `facets render` writes it: binary PLY, triangles with a label per face).
Prints the point count, the median, the 90th percentile and the maximum distance (m), the
share of points farther than --outlier metres, and per label of the nearest truth triangle
(ground, roof, wall, object) the count and the median distance: where the tie points sit.
numpy required (/usr/bin/python3 on Debian).
"""
import sys

import numpy as np

LABELS = {0: 'ground', 1: 'roof', 2: 'wall', 3: 'object'}
PLY_TYPES = {'double': 'f8', 'float': 'f4', 'int': 'i4', 'uchar': 'u1', 'uint': 'u4'}


def read_truth(path):
    with open(path, 'rb') as f:
        header = []
        while True:
            line = f.readline()
            if not line:
                sys.exit(f'{path}: no end_header')
            line = line.decode('ascii', 'replace').strip()
            header.append(line)
            if line == 'end_header':
                break
        if 'format binary_little_endian 1.0' not in header:
            sys.exit(f'{path}: not a binary little-endian PLY')
        elements, current = [], None
        for line in header:
            r = line.split()
            if r[0] == 'element':
                current = [r[1], int(r[2]), []]
                elements.append(current)
            elif r[0] == 'property' and r[1] == 'list':
                current[2].append(('count', 'u1'))
                current[2] += [(f'v{i}', PLY_TYPES[r[3]]) for i in range(3)]
            elif r[0] == 'property':
                current[2].append((r[2], PLY_TYPES[r[1]]))
        data = {}
        for name, count, fields in elements:
            data[name] = np.frombuffer(f.read(count * np.dtype(fields).itemsize), dtype=np.dtype(fields), count=count)
    v, fc = data['vertex'], data['face']
    if np.any(fc['count'] != 3):
        sys.exit(f'{path}: faces other than triangles')
    xyz = np.stack([v['x'], v['y'], v['z']], axis=1).astype(float)
    tri = xyz[np.stack([fc['v0'], fc['v1'], fc['v2']], axis=1)]
    labels = fc['label'] if 'label' in fc.dtype.names else np.full(len(fc), -1)
    return tri, labels


def read_points(path):
    rows = [line.split() for line in open(path) if line.strip() and not line.startswith('#')]
    if not rows:
        sys.exit(f'{path}: no points')
    return np.array([[float(r[1]), float(r[2]), float(r[3])] for r in rows])


def point_triangle_distance(p, a, b, c):
    """Distance from point p to each triangle (a, b, c) (arrays n x 3), Ericson's regions."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum('ij,ij->i', ab, ap), np.einsum('ij,ij->i', ac, ap)
    bp, cp = p - b, p - c
    d3, d4 = np.einsum('ij,ij->i', ab, bp), np.einsum('ij,ij->i', ac, bp)
    d5, d6 = np.einsum('ij,ij->i', ab, cp), np.einsum('ij,ij->i', ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide='ignore', invalid='ignore'):
        denom = va + vb + vc
        v = np.where(denom != 0, vb / denom, 0.0)
        w = np.where(denom != 0, vc / denom, 0.0)
        closest = a + ab * v[:, None] + ac * w[:, None]  # inside the face
        t_ab = np.clip(d1 / (d1 - d3), 0, 1)
        t_ac = np.clip(d2 / (d2 - d6), 0, 1)
        t_bc = np.clip((d4 - d3) / ((d4 - d3) + (d5 - d6)), 0, 1)
    edge_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    edge_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    edge_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    closest = np.where(edge_bc[:, None], b + (c - b) * np.nan_to_num(t_bc)[:, None], closest)
    closest = np.where(edge_ac[:, None], a + ac * np.nan_to_num(t_ac)[:, None], closest)
    closest = np.where(edge_ab[:, None], a + ab * np.nan_to_num(t_ab)[:, None], closest)
    closest = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, closest)
    closest = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, closest)
    closest = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, closest)
    return np.linalg.norm(p - closest, axis=1)


def nearest(points, tri):
    """Distance to the truth surface and index of the nearest triangle, for each point."""
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    dist, which = np.empty(len(points)), np.empty(len(points), dtype=int)
    for i, p in enumerate(points):
        gap = np.linalg.norm(np.maximum(0, np.maximum(lo - p, p - hi)), axis=1)
        for radius in (0.6, 3.0, 20.0, np.inf):
            cand = np.nonzero(gap <= radius)[0]
            if len(cand) == 0:
                continue
            d = point_triangle_distance(p, tri[cand, 0], tri[cand, 1], tri[cand, 2])
            k = np.argmin(d)
            if d[k] <= radius:
                dist[i], which[i] = d[k], cand[k]
                break
    return dist, which


def main():
    args = sys.argv[1:]
    outlier = 0.5
    if '--outlier' in args:
        k = args.index('--outlier')
        outlier = float(args[k + 1])
        del args[k:k + 2]
    if len(args) != 2:
        sys.exit(__doc__)
    points = read_points(args[0])
    tri, labels = read_truth(args[1])
    dist, which = nearest(points, tri)
    print(f'{args[0]}: {len(points)} points; distance to the truth surface: median {np.median(dist):.3f} m, '
          f'p90 {np.percentile(dist, 90):.3f} m, max {dist.max():.2f} m; '
          f'{100 * np.mean(dist > outlier):.1f} % ({np.sum(dist > outlier)}) farther than {outlier} m')
    for label in np.unique(labels):
        m = labels[which] == label
        if m.any():
            print(f'  nearest {LABELS.get(int(label), label)}: {m.sum()} points ({100 * m.mean():.1f} %), '
                  f'median {np.median(dist[m]):.3f} m, {100 * np.mean(dist[m] > outlier):.1f} % > {outlier} m')


if __name__ == '__main__':
    main()
