#!/usr/bin/env python3
# Usage: python3 scripts/tin_wall_patches.py RUN/tin.ply --wall NAME X0 Y0 X1 Y1 [--wall ...]
#          [--min-views 2] [--min-patch 4] [--band 2.5] [--steep 45] [--section-step 1]
# Wall faces of a facets TIN (docs/EXPERIMENTS.md, boruszyn_kap walls), told apart from roof,
# ground and spikes: a face counts as wall when
#   - all three corners are seen by >= --min-views images (tin.ply `views`),
#   - its normal is more than --steep degrees from vertical (tilt from vertical < 90 - steep),
#   - it lies in a connected patch (shared edges) of such faces of >= --min-patch m2, and
#   - its centre lies within --band m (horizontally) of a given wall line (an eave line from the
#     tie points), between the line's ends (+- 1 m).
# Reported per wall and over all walls: area histogram of the tilt from vertical (elevation of
# the face normal above the horizontal) in 5-degree bins, the azimuth of the area-weighted mean
# normal against the line's normal, a total-least-squares plane through the wall faces' corners
# (its tilt from vertical; "body": corners in the middle 60 % of their height range; both are
# ill-conditioned on long crumpled walls) and the horizontal offset of the wall from the line by
# height. Sections (--section-step m, default 1): the TIN cut across the line, the outermost
# crossing at every 0.25 m of height; the wall run is the longest stretch steeper than 45 degrees
# and at least 2 m high, its lean from vertical the slope of a line fitted to offset(height);
# histogram of the sections by lean.
import math, struct, sys

def read_ply(path):
    data = open(path, 'rb').read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    header = data[:end].decode()
    lines = header.splitlines()
    if 'binary_little_endian' not in header:
        sys.exit(f'{path}: expected a binary_little_endian tin.ply of facets')
    props = [l.split()[2] for l in lines if l.startswith('property') and 'list' not in l]
    vprops = []
    in_vertex = False
    for l in lines:
        if l.startswith('element'):
            in_vertex = l.split()[1] == 'vertex'
        elif l.startswith('property') and 'list' not in l and in_vertex:
            vprops.append((l.split()[1], l.split()[2]))
    tmap = {'double': 'd', 'float': 'f', 'int': 'i', 'uchar': 'B', 'uint': 'I', 'int32': 'i', 'float32': 'f', 'float64': 'd', 'uint8': 'B'}
    fmt = '<' + ''.join(tmap[t] for t, _ in vprops)
    names = [n for _, n in vprops]
    nv = int([l for l in lines if l.startswith('element vertex')][0].split()[2])
    nf = int([l for l in lines if l.startswith('element face')][0].split()[2])
    size = struct.calcsize(fmt)
    pts, views = [], []
    for i in range(nv):
        rec = dict(zip(names, struct.unpack_from(fmt, data, end + i * size)))
        pts.append((rec['x'], rec['y'], rec['z']))
        views.append(rec.get('views', 2))
    off = end + nv * size
    face_extra = [l for l in lines[lines.index([l for l in lines if l.startswith('element face')][0]) + 1:]
                  if l.startswith('property') and 'list' not in l]
    extra = struct.calcsize('<' + ''.join(tmap[l.split()[1]] for l in face_extra)) if face_extra else 0
    faces = []
    for _ in range(nf):
        cnt = data[off]; off += 1
        faces.append(struct.unpack_from('<%di' % cnt, data, off)[:3]); off += 4 * cnt + extra
    del props
    return pts, views, faces

def main():
    args = sys.argv[1:]
    if not args or args[0].startswith('-'):
        sys.exit(__doc__ or 'usage: tin_wall_patches.py TIN --wall NAME X0 Y0 X1 Y1 ...')
    path = args.pop(0)
    walls = []; min_views = 2; min_patch = 4.0; band = 2.5; steep = 45.0; step = 1.0
    while args:
        a = args.pop(0)
        if a == '--wall':
            walls.append((args[0], *map(float, args[1:5]))); del args[:5]
        elif a == '--min-views': min_views = int(args.pop(0))
        elif a == '--min-patch': min_patch = float(args.pop(0))
        elif a == '--band': band = float(args.pop(0))
        elif a == '--steep': steep = float(args.pop(0))
        elif a == '--section-step': step = float(args.pop(0))
        else: sys.exit(f'unknown argument {a}')
    pts, views, faces = read_ply(path)
    info = []
    for (a, b, c) in faces:
        A, B, C = pts[a], pts[b], pts[c]
        u = [B[i] - A[i] for i in range(3)]; v = [C[i] - A[i] for i in range(3)]
        n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        l = math.sqrt(sum(x * x for x in n))
        if l == 0:
            info.append(None); continue
        n = tuple(x / l for x in n)
        tilt = math.degrees(math.asin(min(1.0, abs(n[2]))))  # tilt of the face from vertical
        seen = min(views[a], views[b], views[c]) >= min_views
        cen = tuple((A[i] + B[i] + C[i]) / 3 for i in range(3))
        info.append(dict(n=n, area=l / 2, tilt=tilt, seen=seen, cen=cen))
    steep_ok = [i is not None and i['seen'] and i['tilt'] < 90 - steep for i in info]
    # connected patches of steep, seen faces over shared edges
    edge_faces = {}
    for fi, (a, b, c) in enumerate(faces):
        if not steep_ok[fi]: continue
        for e in ((a, b), (b, c), (c, a)):
            edge_faces.setdefault((min(e), max(e)), []).append(fi)
    parent = list(range(len(faces)))
    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]; x = parent[x]
        return x
    for fl in edge_faces.values():
        for f in fl[1:]:
            ra, rb = find(fl[0]), find(f)
            if ra != rb: parent[ra] = rb
    patch_area = {}
    for fi in range(len(faces)):
        if steep_ok[fi]:
            r = find(fi); patch_area[r] = patch_area.get(r, 0) + info[fi]['area']
    seen_area = sum(i['area'] for i in info if i and i['seen'])
    steep_area = sum(info[f]['area'] for f in range(len(faces)) if steep_ok[f])
    big_area = sum(info[f]['area'] for f in range(len(faces)) if steep_ok[f] and patch_area[find(f)] >= min_patch)
    print(f'{path}: {len(pts)} vertices, {len(faces)} faces; seen by >= {min_views}: {seen_area:.1f} m2; '
          f'steeper than {steep:g} deg: {steep_area:.1f} m2, of it in patches >= {min_patch:g} m2: {big_area:.1f} m2')
    def hist(sel):
        h = [0.0] * 9
        for f in sel:
            h[min(8, int(info[f]['tilt'] // 5))] += info[f]['area']
        return h
    def show(name, sel, wall=None):
        tot = sum(info[f]['area'] for f in sel)
        if tot == 0:
            print(f'  {name}: no wall faces'); return
        h = hist(sel)
        tilts = sorted((info[f]['tilt'], info[f]['area']) for f in sel)
        acc = 0; med = tilts[-1][0]
        for t, a in tilts:
            acc += a
            if acc >= tot / 2: med = t; break
        line = (f'  {name}: {len(sel)} faces {tot:.1f} m2, tilt from vertical median {med:.1f} deg; area by tilt: '
                + ', '.join(f'{5*k}-{5*k+5}: {x:.1f}' for k, x in enumerate(h)))
        if wall:
            _, x0, y0, x1, y1, nx_, ny_ = wall
            mn = [sum(info[f]['n'][i] * info[f]['area'] for f in sel) for i in range(3)]
            az = math.degrees(math.atan2(mn[1], mn[0])) % 360
            naz = math.degrees(math.atan2(ny_, nx_)) % 360
            # plane through the wall faces' corners (total least squares)
            vs = sorted({v for f in sel for v in faces[f]})
            m = [sum(pts[v][i] for v in vs) / len(vs) for i in range(3)]
            C = [[sum((pts[v][i] - m[i]) * (pts[v][j] - m[j]) for v in vs) for j in range(3)] for i in range(3)]
            nrm = smallest_eigvec(C)
            ptilt = math.degrees(math.asin(min(1.0, abs(nrm[2]) / math.sqrt(sum(x * x for x in nrm)))))
            res = [sum((pts[v][i] - m[i]) * nrm[i] for i in range(3)) for v in vs]
            rms = math.sqrt(sum(r * r for r in res) / len(res))
            line += (f'; mean normal azimuth {az:.0f} (line {naz:.0f}); plane through {len(vs)} corners: '
                     f'tilt from vertical {ptilt:.1f} deg, rms {rms:.2f} m')
            # the wall's body: corners in the middle 60 % of the wall faces' height range
            # (no foot, no eave rounding)
            zs = sorted(pts[v][2] for v in vs)
            lo, hi = zs[int(0.05 * (len(zs) - 1))], zs[int(0.95 * (len(zs) - 1))]
            body = [v for v in vs if lo + 0.2 * (hi - lo) <= pts[v][2] <= hi - 0.2 * (hi - lo)]
            if len(body) >= 4:
                mb = [sum(pts[v][i] for v in body) / len(body) for i in range(3)]
                Cb = [[sum((pts[v][i] - mb[i]) * (pts[v][j] - mb[j]) for v in body) for j in range(3)] for i in range(3)]
                nb = smallest_eigvec(Cb)
                btilt = math.degrees(math.asin(min(1.0, abs(nb[2]) / math.sqrt(sum(x * x for x in nb)))))
                brms = math.sqrt(sum(sum((pts[v][i] - mb[i]) * nb[i] for i in range(3)) ** 2 for v in body) / len(body))
                line += f'; body ({lo + 0.2 * (hi - lo):.1f}-{hi - 0.2 * (hi - lo):.1f} m, {len(body)} corners): tilt {btilt:.1f} deg, rms {brms:.2f} m'
            # offset from the line by height (vertical profile)
            prof = {}
            for v in vs:
                o = (pts[v][0] - x0) * nx_ + (pts[v][1] - y0) * ny_
                prof.setdefault(math.floor(pts[v][2]), []).append(o)
            line += '; offset from the line by height (m: median offset, n): ' + ', '.join(
                f'{z}: {sorted(o)[len(o)//2]:+.2f} ({len(o)})' for z, o in sorted(prof.items()))
        print(line)
    allsel = []; leans = []
    for name, x0, y0, x1, y1 in walls:
        dx, dy = x1 - x0, y1 - y0; L = math.hypot(dx, dy); d = (dx / L, dy / L)
        # outward normal: the side the faces' normals point to, decided below by the majority
        n0 = (d[1], -d[0])
        sel = []
        for f in range(len(faces)):
            if not steep_ok[f] or patch_area[find(f)] < min_patch: continue
            cx, cy, _ = info[f]['cen']
            t = (cx - x0) * d[0] + (cy - y0) * d[1]; o = (cx - x0) * n0[0] + (cy - y0) * n0[1]
            if -1 <= t <= L + 1 and abs(o) <= band: sel.append(f)
        s = sum((info[f]['n'][0] * n0[0] + info[f]['n'][1] * n0[1]) * info[f]['area'] for f in sel)
        n = n0 if s >= 0 else (-n0[0], -n0[1])
        show(f'{name} ({x0:g},{y0:g})-({x1:g},{y1:g})', sel, (name, x0, y0, x1, y1, n[0], n[1]))
        allsel += [f for f in sel if f not in allsel]
        leans += sections(pts, faces, x0, y0, d, n, L, band, step, name)
    if walls:
        show('all walls', allsel)
        print_leans('all walls', leans)

def print_leans(name, leans):
    if not leans:
        print(f'  {name}: no section with a wall run'); return
    h = [0] * 10
    for t, _ in leans: h[min(9, int(t // 5))] += 1
    ts = sorted(t for t, _ in leans)
    print(f'  {name} sections: {len(leans)} with a wall run, lean from vertical median {ts[len(ts)//2]:.1f} deg, '
          f'run height median {sorted(r for _, r in leans)[len(leans)//2]:.1f} m; sections by lean: '
          + ', '.join(f'{5*k}-{5*k+5}: {c}' for k, c in enumerate(h[:9])) + f', >45: {h[9]}')

def sections(pts, faces, x0, y0, d, n, L, band, step, name):
    # Vertical sections across the wall every `step` m: the TIN cut by the plane, the outermost
    # crossing (along the outward normal n, within band + 2 m of the line) at every 0.25 m of
    # height; the wall run is the longest stretch of heights where the profile is steeper than
    # 45 degrees (|d offset| < d z), at least 2 m high; its lean is the slope of a straight line
    # fitted to offset(z) over the run.
    leans = []
    t = 0.5 * step
    while t < L:
        px, py = x0 + t * d[0], y0 + t * d[1]
        segs = []
        for f in faces:
            P = [pts[i] for i in f]
            s = [(p[0] - px) * d[0] + (p[1] - py) * d[1] for p in P]
            if max(s) < 0 or min(s) > 0: continue
            hits = []
            for a in range(3):
                b = (a + 1) % 3
                if (s[a] < 0) != (s[b] < 0):
                    u = s[a] / (s[a] - s[b]); q = [P[a][k] + u * (P[b][k] - P[a][k]) for k in range(3)]
                    hits.append(((q[0] - px) * n[0] + (q[1] - py) * n[1], q[2]))
            if len(hits) == 2: segs.append(hits)
        t += step
        if not segs: continue
        zmin = min(min(h[1] for h in sg) for sg in segs); zmax = max(max(h[1] for h in sg) for sg in segs)
        prof = []
        z = math.floor(zmin * 4) / 4 + 0.25
        while z < zmax:
            xs = []
            for a, b in segs:
                if (a[1] - z) * (b[1] - z) < 0:
                    u = (z - a[1]) / (b[1] - a[1]); o = a[0] + u * (b[0] - a[0])
                    if abs(o) <= band + 2: xs.append(o)
            prof.append((z, max(xs) if xs else None))
            z += 0.25
        best = []; cur = []
        for k in range(len(prof)):
            ok = prof[k][1] is not None and cur and abs(prof[k][1] - cur[-1][1]) < 0.25
            if ok: cur.append(prof[k])
            else:
                cur = [prof[k]] if prof[k][1] is not None else []
            if len(cur) > len(best): best = list(cur)
        if len(best) < 9: continue  # 2 m
        zs = [p[0] for p in best]; os_ = [p[1] for p in best]
        mz = sum(zs) / len(zs); mo = sum(os_) / len(os_)
        slope = sum((a - mz) * (b - mo) for a, b in zip(zs, os_)) / sum((a - mz) ** 2 for a in zs)
        leans.append((math.degrees(math.atan(abs(slope))), zs[-1] - zs[0]))
    print_leans(name, leans)
    return leans

def smallest_eigvec(C):
    # symmetric 3x3: inverse iteration on C + tiny shift (Jacobi would do as well)
    import itertools
    a = [row[:] for row in C]
    V = [[1.0 if i == j else 0.0 for j in range(3)] for i in range(3)]
    for _ in range(50):
        p, q = max(((i, j) for i, j in itertools.combinations(range(3), 2)), key=lambda ij: abs(a[ij[0]][ij[1]]))
        if abs(a[p][q]) < 1e-15: break
        th = 0.5 * math.atan2(2 * a[p][q], a[q][q] - a[p][p])
        c, s = math.cos(th), math.sin(th)
        for k in range(3):
            akp, akq = a[k][p], a[k][q]
            a[k][p] = c * akp - s * akq; a[k][q] = s * akp + c * akq
        for k in range(3):
            apk, aqk = a[p][k], a[q][k]
            a[p][k] = c * apk - s * aqk; a[q][k] = s * apk + c * aqk
        for k in range(3):
            vkp, vkq = V[k][p], V[k][q]
            V[k][p] = c * vkp - s * vkq; V[k][q] = s * vkp + c * vkq
    i = min(range(3), key=lambda i: a[i][i])
    return [V[k][i] for k in range(3)]

if __name__ == '__main__':
    main()
