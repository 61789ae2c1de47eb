#!/usr/bin/env python3
# Usage: python3 scripts/tin_normal_histogram.py RUN/tin.ply (docs/EXPERIMENTS.md, boruszyn walls)
# Histogram of vertex-normal tilt from tin.ply of facets (binary_little_endian, x y z nx ny nz sigma views).
# Wall vertices: normal within 45 deg of horizontal; reported: their count and how far the
# wall (plane through the vertex perpendicular to the normal) is from vertical = elevation of
# the normal above the horizontal plane.
import struct, sys, math
path = sys.argv[1]
data = open(path, 'rb').read()
end = data.index(b'end_header\n') + len(b'end_header\n')
header = data[:end].decode()
props = [l.split()[2] for l in header.splitlines() if l.startswith('property') and 'list' not in l]
nv = int([l for l in header.splitlines() if l.startswith('element vertex')][0].split()[2])
fmt = '<' + ''.join({'x':'d','y':'d','z':'d','nx':'f','ny':'f','nz':'f','sigma':'f','views':'i','red':'B','green':'B','blue':'B'}[p] for p in props)
size = struct.calcsize(fmt)
bins = [0]*10  # elevation of the normal in 5-degree bins 0..45, only views >= 2
allv = 0; seen2 = 0; wall = 0
for i in range(nv):
    rec = dict(zip(props, struct.unpack_from(fmt, data, end + i*size)))
    allv += 1
    if rec.get('views', 2) < 2: continue
    seen2 += 1
    n = (rec['nx'], rec['ny'], rec['nz'])
    l = math.sqrt(sum(c*c for c in n)) or 1
    elev = math.degrees(math.asin(max(-1, min(1, abs(n[2])/l))))
    if elev < 45:
        wall += 1
        bins[int(elev // 5)] += 1
print(f'{path}: {allv} vertices, {seen2} seen by >= 2 images, {wall} with normals within 45 deg of horizontal (wall-like)')
print('normal elevation (deg) = wall tilt from vertical: ' + ', '.join(f'{5*k}-{5*k+5}: {b}' for k, b in enumerate(bins[:9])))
# Faces: area-weighted elevation histogram and azimuths of steep faces (views >= 2 at all corners).
pts = []; views = []
for i in range(nv):
    rec = dict(zip(props, struct.unpack_from(fmt, data, end + i*size)))
    pts.append((rec['x'], rec['y'], rec['z'])); views.append(rec.get('views', 2))
off = end + nv*size
nf = int([l for l in header.splitlines() if l.startswith('element face')][0].split()[2])
has_label = 'property int label' in header
area_bins = [0.0]*10; az = {}
total = 0.0
for f in range(nf):
    cnt = data[off]; off += 1
    idx = struct.unpack_from('<%di' % cnt, data, off); off += 4*cnt
    if has_label: off += 4
    a, b, c = (pts[k] for k in idx[:3])
    u = [b[i]-a[i] for i in range(3)]; v = [c[i]-a[i] for i in range(3)]
    n = (u[1]*v[2]-u[2]*v[1], u[2]*v[0]-u[0]*v[2], u[0]*v[1]-u[1]*v[0])
    l = math.sqrt(sum(x*x for x in n))
    if l == 0 or min(views[k] for k in idx[:3]) < 2: continue
    area = l/2; total += area
    elev = math.degrees(math.asin(min(1, abs(n[2])/l)))
    if elev < 45:
        area_bins[int(elev//5)] += area
    if elev < 10:
        az_b = int((math.degrees(math.atan2(n[1], n[0])) % 180) // 15) * 15
        az[az_b] = az.get(az_b, 0) + area
print(f'faces: total area {total:.1f}; area by face-normal elevation: ' + ', '.join(f'{5*k}-{5*k+5}: {x:.1f}' for k, x in enumerate(area_bins[:9])))
print('azimuth (mod 180, 15-deg bins) of faces steeper than 80 deg, area: ' + ', '.join(f'{k}: {az[k]:.1f}' for k in sorted(az)))
