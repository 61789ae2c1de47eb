#!/usr/bin/env python3
# Usage: python3 scripts/tie_point_walls.py MODEL_DIR [--region X0 X1 Y0 Y1] [--cell 2]
#          [--max-incidence 65] [--select NAME XMIN XMAX YMIN YMAX AZMIN AZMAX ...]
# Where are building walls visible, from a COLMAP text model alone (docs/EXPERIMENTS.md,
# boruszyn_kap walls): the tie points gridded (cells of --cell m, 75th percentile of z, holes
# filled from their neighbours), building cells > 2.5 m above the 10th percentile within 14 m,
# boundary cells with the outward normal of the building mask. For each boundary cell and image:
# the ray from the wall's mid height (half a cell outside) to the projection centre, in the frame
# (PINHOLE, SIMPLE_PINHOLE, SIMPLE_RADIAL, RADIAL), facing the wall, not hidden by the gridded
# tie points; incidence = angle between the ray and the horizontal wall normal; wall height in
# pixels = height x focal / distance x cos(incidence).
# Prints per building and wall direction (azimuth of the outward normal, counter-clockwise from
# +x, 45-degree bins) how many cells >= 2 images see below --max-incidence. With --select: the
# boundary cells inside the box whose normal azimuth lies in [AZMIN, AZMAX] give a wall: a line
# fitted to them, moved out to the 95th percentile of the roof tie points behind it (eave line),
# and the images that see >= 30 % of its cells at a median incidence below --max-incidence
# (median incidence, wall height in pixels).
import collections, math, os, sys


def quat_to_r(w, x, y, z):
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def read_model(folder):
    cams = {}
    for path in ('cameras.txt', 'images.txt', 'points3D.txt'):
        if not os.path.exists(os.path.join(folder, path)):
            sys.exit(f'{os.path.join(folder, path)}: missing (COLMAP text model expected)')
    for l in open(os.path.join(folder, 'cameras.txt')):
        if l.startswith('#') or not l.strip(): continue
        p = l.split(); model = p[1]; w, h = int(p[2]), int(p[3]); q = list(map(float, p[4:]))
        if model == 'PINHOLE': f, cx, cy, k = 0.5 * (q[0] + q[1]), q[2], q[3], (0.0, 0.0)
        elif model == 'SIMPLE_PINHOLE': f, cx, cy, k = q[0], q[1], q[2], (0.0, 0.0)
        elif model == 'SIMPLE_RADIAL': f, cx, cy, k = q[0], q[1], q[2], (q[3], 0.0)
        elif model == 'RADIAL': f, cx, cy, k = q[0], q[1], q[2], (q[3], q[4])
        else: sys.exit(f'{folder}/cameras.txt: camera model {model} not handled')
        cams[p[0]] = (w, h, f, cx, cy, k)
    images = []
    lines = [l for l in open(os.path.join(folder, 'images.txt')) if not l.startswith('#')]
    for i in range(0, len(lines) - 1, 2):
        p = lines[i].split()
        if len(p) < 10: continue
        R = quat_to_r(*map(float, p[1:5])); t = list(map(float, p[5:8]))
        C = [-sum(R[k][j] * t[k] for k in range(3)) for j in range(3)]
        images.append(dict(name=p[9], R=R, t=t, C=C, cam=cams[p[8]]))
    points = []
    for l in open(os.path.join(folder, 'points3D.txt')):
        if l.startswith('#') or not l.strip(): continue
        p = l.split(); points.append((float(p[1]), float(p[2]), float(p[3])))
    return images, points


def project(im, X):
    R, t = im['R'], im['t']; w, h, f, cx, cy, k = im['cam']
    Xc = [sum(R[r][q] * X[q] for q in range(3)) + t[r] for r in range(3)]
    if Xc[2] <= 0: return None
    u, v = Xc[0] / Xc[2], Xc[1] / Xc[2]; r2 = u * u + v * v; d = 1 + k[0] * r2 + k[1] * r2 * r2
    x, y = f * u * d + cx, f * v * d + cy
    return (x, y) if 0 <= x < w and 0 <= y < h else None


def main():
    a = sys.argv[1:]
    if not a or a[0].startswith('-'):
        sys.exit('usage: tie_point_walls.py MODEL_DIR [--region X0 X1 Y0 Y1] [--cell 2] [--max-incidence 65] '
                 '[--select NAME XMIN XMAX YMIN YMAX AZMIN AZMAX ...]')
    folder = a.pop(0); region = None; cs = 2.0; max_inc = 65.0; selects = []
    while a:
        o = a.pop(0)
        if o == '--region': region = list(map(float, a[:4])); del a[:4]
        elif o == '--cell': cs = float(a.pop(0))
        elif o == '--max-incidence': max_inc = float(a.pop(0))
        elif o == '--select': selects.append((a[0], *map(float, a[1:7]))); del a[:7]
        else: sys.exit(f'unknown argument {o}')
    images, P = read_model(folder)
    if region is None:
        xs = sorted(p[0] for p in P); ys = sorted(p[1] for p in P); n = len(P)
        region = [xs[n // 50], xs[-n // 50], ys[n // 50], ys[-n // 50]]
    x0, x1, y0, y1 = region
    nx, ny = int((x1 - x0) / cs), int((y1 - y0) / cs)
    cells = collections.defaultdict(list)
    for x, y, z in P:
        if x0 <= x < x1 and y0 <= y < y1: cells[(int((x - x0) // cs), int((y - y0) // cs))].append(z)
    dsm = {}
    for key, v in cells.items():
        v.sort(); dsm[key] = v[(3 * len(v)) // 4]
    def nb(src, i, j, r):
        return [src[(p, q)] for p in range(i - r, i + r + 1) for q in range(j - r, j + r + 1) if (p, q) in src]
    for _ in range(3):
        add = {}
        for i in range(nx):
            for j in range(ny):
                if (i, j) in dsm: continue
                v = sorted(nb(dsm, i, j, 1))
                if len(v) >= 3: add[(i, j)] = v[len(v) // 2]
        dsm.update(add)
    R = int(round(14 / cs))
    ground = {key: sorted(nb(dsm, key[0], key[1], R))[len(nb(dsm, key[0], key[1], R)) // 10] for key in dsm}
    bld = {key for key in dsm if dsm[key] - ground[key] > 2.5}
    comp = {}; sizes = {}; cid = 0
    for key in bld:
        if key in comp: continue
        cid += 1; stack = [key]; comp[key] = cid; n = 0
        while stack:
            c = stack.pop(); n += 1
            for d in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                m = (c[0] + d[0], c[1] + d[1])
                if m in bld and m not in comp: comp[m] = cid; stack.append(m)
        sizes[cid] = n
    def hidden(X, C):
        d = [C[q] - X[q] for q in range(3)]; L = math.sqrt(sum(v * v for v in d)); d = [v / L for v in d]
        s = 1.5; top = max(dsm.values())
        while s < L:
            p = [X[q] + s * d[q] for q in range(3)]
            if p[2] > top: return False
            key = (int((p[0] - x0) // cs), int((p[1] - y0) // cs))
            if key in dsm and dsm[key] > p[2] + 0.3: return True
            s += 0.5 * cs / 2
        return False
    rows = []
    for key in bld:
        if sizes[comp[key]] * cs * cs < 60: continue
        i, j = key
        if not any((i + p, j + q) in dsm and (i + p, j + q) not in bld for p, q in ((1, 0), (-1, 0), (0, 1), (0, -1))):
            continue
        gx = gy = 0.0
        for p in range(-2, 3):
            for q in range(-2, 3):
                if (p or q) and (i + p, j + q) in dsm and (i + p, j + q) not in bld: gx += p; gy += q
        L = math.hypot(gx, gy)
        if L == 0: continue
        n = (gx / L, gy / L)
        xc, yc = x0 + (i + 0.5) * cs + n[0] * cs * 0.5, y0 + (j + 0.5) * cs + n[1] * cs * 0.5
        g, r = ground[key], dsm[key]
        X = (xc, yc, 0.5 * (g + r))
        seen = []
        for im in images:
            C = im['C']; d = [C[q] - X[q] for q in range(3)]; Ld = math.sqrt(sum(v * v for v in d))
            cosi = (d[0] * n[0] + d[1] * n[1]) / Ld
            if cosi <= 0.05 or project(im, X) is None or hidden(X, C): continue
            seen.append((math.degrees(math.acos(cosi)), im['name'], (r - g) * im['cam'][2] / Ld * cosi))
        rows.append(dict(b=comp[key], x=xc, y=yc, n=n, g=g, r=r, az=math.degrees(math.atan2(n[1], n[0])) % 360,
                         seen=sorted(seen)))
    print(f'{len(images)} images, {len(P)} tie points; region x {x0:g}..{x1:g}, y {y0:g}..{y1:g}, cells {cs:g} m')
    for b in sorted({r['b'] for r in rows}, key=lambda b: -sizes[b]):
        R_ = [r for r in rows if r['b'] == b]
        print(f'building {b}: {sizes[b] * cs * cs:.0f} m2, x {min(r["x"] for r in R_):.0f}..{max(r["x"] for r in R_):.0f}, '
              f'y {min(r["y"] for r in R_):.0f}..{max(r["y"] for r in R_):.0f}, {len(R_)} wall cells')
        by = collections.defaultdict(list)
        for r in R_: by[int(((r['az'] + 22.5) % 360) // 45) * 45].append(r)
        for az in sorted(by):
            L_ = by[az]; k = [sum(1 for s in r['seen'] if s[0] < max_inc) for r in L_]
            print(f'  normal azimuth {az:3d}: {len(L_)} cells, wall height median '
                  f'{sorted(r["r"] - r["g"] for r in L_)[len(L_) // 2]:.1f} m, cells seen by >= 2 images below '
                  f'{max_inc:g} deg: {sum(1 for c in k if c >= 2)}, images per cell median {sorted(k)[len(k) // 2]} max {max(k)}')
    for name, xa, xb, ya, yb, aza, azb in selects:
        pts = [r for r in rows if xa <= r['x'] <= xb and ya <= r['y'] <= yb and aza <= r['az'] <= azb]
        if len(pts) < 2:
            print(f'{name}: {len(pts)} wall cells in the box'); continue
        n_ = len(pts); mx = sum(r['x'] for r in pts) / n_; my = sum(r['y'] for r in pts) / n_
        sxx = sum((r['x'] - mx) ** 2 for r in pts); syy = sum((r['y'] - my) ** 2 for r in pts)
        sxy = sum((r['x'] - mx) * (r['y'] - my) for r in pts)
        th = 0.5 * math.atan2(2 * sxy, sxx - syy); d = (math.cos(th), math.sin(th)); nrm = (-d[1], d[0])
        if nrm[0] * sum(r['n'][0] for r in pts) + nrm[1] * sum(r['n'][1] for r in pts) < 0: nrm = (-nrm[0], -nrm[1])
        ts = [(r['x'] - mx) * d[0] + (r['y'] - my) * d[1] for r in pts]; t0, t1 = min(ts), max(ts)
        g = sorted(r['g'] for r in pts)[n_ // 2]; roof = sorted(r['r'] for r in pts)[n_ // 2]
        offs = sorted((x - mx) * nrm[0] + (y - my) * nrm[1] for x, y, z in P
                      if t0 <= (x - mx) * d[0] + (y - my) * d[1] <= t1
                      and -5 <= (x - mx) * nrm[0] + (y - my) * nrm[1] <= 4 and z > g + 2.0)
        off = offs[min(len(offs) - 1, int(0.95 * len(offs)))] if offs else 0.0
        mx += off * nrm[0]; my += off * nrm[1]
        # images that see >= 30 % of the wall's cells, with a median incidence below max_inc
        imgs = collections.defaultdict(list)
        for r in pts:
            for s in r['seen']: imgs[s[1]].append(s)
        seen = sorted((sorted(s[0] for s in v)[len(v) // 2], k, sorted(s[2] for s in v)[len(v) // 2])
                      for k, v in imgs.items() if len(v) >= 0.3 * n_)
        seen = [s for s in seen if s[0] < max_inc]
        print(f'{name}: {n_} cells, eave line ({mx + t0 * d[0]:.1f}, {my + t0 * d[1]:.1f})-({mx + t1 * d[0]:.1f}, '
              f'{my + t1 * d[1]:.1f}), length {t1 - t0:.1f} m, outward normal azimuth '
              f'{math.degrees(math.atan2(nrm[1], nrm[0])) % 360:.0f}, ground {g:.1f} m, roof {roof:.1f} m; '
              f'{len(seen)} images below {max_inc:g} deg: ' + ', '.join(f'{k} {i:.0f} deg {p:.0f} px' for i, k, p in seen))


if __name__ == '__main__':
    main()
