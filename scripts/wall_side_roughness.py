#!/usr/bin/env python3
"""Usage: python3 scripts/wall_side_roughness.py MESH.ply --wall NAME X0 Y0 X1 Y1 [--wall ...]
          [--near 0.5 2.5] [--far 2.5 5.0] [--chunk 4]

How rough the surface is on either side of a wall line (the walls of
scripts/tin_wall_patches.py): the mesh's vertices (any binary PLY with x, y, z: a Facets
tin.ply or a peer's mesh) whose horizontal distance from the line lies in the near band
(the eave or foot itself) or the far band (the roof or ground beside it), between the
line's ends less 2 m, cut into chunks of --chunk m along the line; per chunk a
total-least-squares plane through its vertices (at least 6) and its rms distance. Printed
per wall, side (+1: left of X0 Y0 -> X1 Y1 looking along it) and band: vertex count, median
height, and the chunks' plane rms median, 25th and 75th percentile (m). A roof or the
ground 2.5-5 m from a wall is a plane to a few centimetres; the crease steps of the aerial
path (straightening, wall corners, feet, eaves) take a side as planar within a tenth of
an edge. numpy required (/usr/bin/python3 on Debian).
"""
import sys

import numpy as np


def read_vertices(path):
    data = open(path, 'rb').read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    lines = data[:end].decode().splitlines()
    if not any('binary_little_endian' in line for line in lines):
        sys.exit(f'{path}: expected a binary_little_endian PLY')
    props, in_vertex, count = [], False, 0
    for line in lines:
        words = line.split()
        if words[0] == 'element':
            in_vertex = words[1] == 'vertex'
            if in_vertex:
                count = int(words[2])
        elif words[0] == 'property' and in_vertex and words[1] != 'list':
            props.append((words[1], words[2]))
    types = {'double': 'f8', 'float64': 'f8', 'float': 'f4', 'float32': 'f4', 'int': 'i4', 'int32': 'i4',
             'uint': 'u4', 'uint32': 'u4', 'uchar': 'u1', 'uint8': 'u1', 'short': 'i2', 'ushort': 'u2'}
    dtype = np.dtype([(name, '<' + types[kind]) for kind, name in props])
    v = np.frombuffer(data, dtype=dtype, count=count, offset=end)
    return np.stack([v['x'], v['y'], v['z']], 1).astype(float)


def chunk_rms(points, t, length, chunk):
    rms = []
    for start in np.arange(2.0, length - 2.0, chunk):
        sel = points[(t >= start) & (t < start + chunk)]
        if len(sel) < 6:
            continue
        centred = sel - sel.mean(0)
        normal = np.linalg.svd(centred)[2][2]
        rms.append(np.sqrt(np.mean((centred @ normal) ** 2)))
    return rms


def main():
    args = sys.argv[1:]
    if not args or args[0].startswith('-'):
        sys.exit(__doc__)
    points = read_vertices(args[0])
    walls, bands, chunk = [], {'near': (0.5, 2.5), 'far': (2.5, 5.0)}, 4.0
    i = 1
    while i < len(args):
        if args[i] == '--wall':
            walls.append((args[i + 1], [float(x) for x in args[i + 2:i + 6]]))
            i += 6
        elif args[i] in ('--near', '--far'):
            bands[args[i][2:]] = (float(args[i + 1]), float(args[i + 2]))
            i += 3
        elif args[i] == '--chunk':
            chunk = float(args[i + 1])
            i += 2
        else:
            sys.exit(f'unknown argument {args[i]}\n' + __doc__)
    for name, (x0, y0, x1, y1) in walls:
        a, b = np.array([x0, y0]), np.array([x1, y1])
        length = np.linalg.norm(b - a)
        along = (b - a) / length
        left = np.array([-along[1], along[0]])
        t = (points[:, :2] - a) @ along
        s = (points[:, :2] - a) @ left
        inside = (t > 2.0) & (t < length - 2.0)
        for side in (+1, -1):
            for band, (lo, hi) in bands.items():
                sel = inside & (side * s > lo) & (side * s < hi)
                rms = chunk_rms(points[sel], t[sel], length, chunk)
                if not rms:
                    print(f'{name} side {side:+d} {band} {lo}-{hi} m: {sel.sum()} vertices, no chunk of 6')
                    continue
                print(f'{name} side {side:+d} {band} {lo}-{hi} m: {sel.sum()} vertices, height median '
                      f'{np.median(points[sel, 2]):.2f} m, chunk plane rms median {np.median(rms):.3f} m '
                      f'(p25 {np.percentile(rms, 25):.3f}, p75 {np.percentile(rms, 75):.3f}) over {len(rms)} chunks')


if __name__ == '__main__':
    main()
