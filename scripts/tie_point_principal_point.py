#!/usr/bin/env python3
"""Principal-point check of a COLMAP text model from its tie points.

Prints the mean reprojection residual per image (observed keypoint minus projection, pixels)
and the common principal-point shift (dx, dy) that, added to every camera, best explains the
keypoints when the 3D points are re-triangulated with it: Gauss-Newton over the shift and all
points, the points eliminated per point (Schur complement). A calibration converted with
another pixel-centre convention shows as a shift of about (0.5, 0.5) with small per-image
scatter. Poses are held fixed; distortion is ignored (PINHOLE / SIMPLE_PINHOLE models).

usage: tie_point_principal_point.py SPARSE_DIR
"""
import sys

import numpy as np


def quaternion_to_rotation(w, x, y, z):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def read_model(folder):
    cameras = {}
    for line in open(folder + '/cameras.txt'):
        if line.startswith('#') or not line.strip():
            continue
        t = line.split()
        p = [float(v) for v in t[4:]]
        cameras[int(t[0])] = p[0:4] if t[1] == 'PINHOLE' else [p[0], p[0], p[1], p[2]]
    images = {}
    lines = [line for line in open(folder + '/images.txt') if not line.startswith('#')]
    for i in range(0, len(lines) - 1, 2):
        t = lines[i].split()
        if not t:
            continue
        p = lines[i + 1].split()
        images[int(t[0])] = dict(R=quaternion_to_rotation(*map(float, t[1:5])), t=np.array(list(map(float, t[5:8]))),
                                 cam=cameras[int(t[8])], name=t[9],
                                 obs=[(float(p[k]), float(p[k + 1]), int(p[k + 2])) for k in range(0, len(p), 3)])
    points = {}
    for line in open(folder + '/points3D.txt'):
        if not line.startswith('#') and line.strip():
            t = line.split()
            points[int(t[0])] = np.array(list(map(float, t[1:4])))
    return images, points


def project(image, X):
    """Projection without the shift, and its Jacobian by X."""
    f = image['cam']
    Xc = image['R'] @ X + image['t']
    u = np.array([f[0] * Xc[0] / Xc[2] + f[2], f[1] * Xc[1] / Xc[2] + f[3]])
    J = np.array([[f[0] / Xc[2], 0, -f[0] * Xc[0] / Xc[2] ** 2], [0, f[1] / Xc[2], -f[1] * Xc[1] / Xc[2] ** 2]])
    return u, J @ image['R']


def common_shift(images, tracks, points, rounds=10):
    shift = np.zeros(2)
    points = {pid: points[pid].copy() for pid in tracks}
    for _ in range(rounds):
        N, b, cost, back = np.zeros((2, 2)), np.zeros(2), 0.0, {}
        for pid, track in tracks.items():
            Jp, r = [], []
            for iid, x, y in track:
                u, J = project(images[iid], points[pid])
                Jp.append(J)
                r.append(np.array([x, y]) - u - shift)
            Jp, r = np.vstack(Jp), np.concatenate(r)
            Js = np.tile(np.eye(2), (len(track), 1))
            cost += r @ r
            Ai = np.linalg.inv(Jp.T @ Jp)
            P = Jp @ Ai @ Jp.T
            N += Js.T @ Js - Js.T @ P @ Js
            b += Js.T @ r - Js.T @ P @ r
            back[pid] = (Ai, Jp, Js, r)
        step = np.linalg.solve(N, b)
        for pid, (Ai, Jp, Js, r) in back.items():
            points[pid] = points[pid] + Ai @ Jp.T @ (r - Js @ step)
        shift += step
    observations = sum(len(t) for t in tracks.values())
    rms = np.sqrt(cost / observations)
    sigma = np.sqrt(np.diag(np.linalg.inv(N)) * rms ** 2 / 2)
    return shift, sigma, rms


def main():
    images, points = read_model(sys.argv[1])
    tracks = {}
    for iid, image in images.items():
        for x, y, pid in image['obs']:
            if pid >= 0 and pid in points:
                tracks.setdefault(pid, []).append((iid, x, y))
    residuals = {}
    for pid, track in tracks.items():
        for iid, x, y in track:
            residuals.setdefault(iid, []).append(np.array([x, y]) - project(images[iid], points[pid])[0])
    everything = np.vstack([np.array(v) for v in residuals.values()])
    print('as stored: %d observations, mean residual %+.3f %+.3f px, rms %.3f px' %
          (len(everything), *everything.mean(0), np.sqrt((everything ** 2).sum(1).mean())))
    for iid in sorted(residuals):
        v = np.array(residuals[iid])
        print('  %-24s %5d observations, mean %+.3f %+.3f px' % (images[iid]['name'], len(v), *v.mean(0)))
    shift, sigma, rms = common_shift(images, tracks, points)
    print('common principal-point shift with re-triangulated points: %+.3f %+.3f px (+- %.3f %.3f), rms %.3f px' %
          (*shift, *sigma, rms))


if __name__ == '__main__':
    main()
