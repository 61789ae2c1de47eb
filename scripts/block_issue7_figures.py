#!/usr/bin/env python3
"""Usage: python3 scripts/block_issue7_figures.py SAMPLES.json [SCENE.json] [--cells N]

Issue 7's figures for a rendered block scene from `facets evaluate --samples --json
SAMPLES.json` (docs/EXPERIMENTS.md, sessions 24-28):
  - walls seen by >= 2 images: completeness at 1 GSD, median and rms in GSD;
  - roofs and ground: median over the samples seen by >= 2 images and over all;
  - the leaning walls and the crossing facet pairs the evaluation found;
with the scene file also
  - ridges and eaves: roof samples seen by >= 2 images; eaves = the outer 0.5 m of each
    roof, ridges = within 0.5 m of a gable's ridge line (eaves left out); median and p90
    in GSD, overall and per gable building with the p90 along the ridge in 8 bins;
  - where the walls' error sits: wall samples seen by >= 2 images split into zones within
    3 GSD of a vertical corner of their building (leaning walls followed), of its eave
    (or above it: gable ends), of the ground at their foot, and the rest (interior);
    per zone median, rms, share of the squared distance and completeness at 1 GSD;
and with --cells N the N 2 m cells that carry most of the walls' squared distance (where
the rms sits). numpy required (/usr/bin/python3 on Debian).
"""
import json
import signal
import sys

import numpy as np


def wall_cells(x, y, z, d, count):
    total = np.sum(d ** 2)
    keys, cell = np.unique(np.stack([np.floor(x / 2), np.floor(y / 2)], axis=1).astype(int), axis=0,
                           return_inverse=True)
    cell = cell.ravel()
    share = np.bincount(cell, weights=d ** 2) / total
    for k in np.argsort(-share)[:count]:
        m = cell == k
        i, j = keys[k]
        print(f'  {100 * share[k]:5.1f} % of the squared wall distance: x {2 * i}..{2 * i + 2} y {2 * j}..{2 * j + 2}, '
              f'{m.sum()} samples, median {np.median(d[m]):.2f} GSD, z {z[m].min():.1f}..{z[m].max():.1f}')


def building_frame(b, x, y):
    cx, cy = b['centre'][:2]
    az = np.radians(b.get('azimuth_deg', 0.0))
    u = np.cos(az) * (x - cx) + np.sin(az) * (y - cy)
    v = -np.sin(az) * (x - cx) + np.cos(az) * (y - cy)
    return u, v


def ridges_and_eaves(scene, x, y, roof, d):
    ridge = np.zeros_like(roof)
    eave = np.zeros_like(roof)
    per_gable = []
    for index, b in enumerate(scene['surface']):
        if b['type'] != 'building':
            continue
        u, v = building_frame(b, x, y)
        half_l, half_w = b['length'] / 2, b['width'] / 2
        inside = (np.abs(u) <= half_l + 0.01) & (np.abs(v) <= half_w + 0.01)
        outer = inside & ((np.abs(u) > half_l - 0.5) | (np.abs(v) > half_w - 0.5))
        eave |= roof & outer
        if b['roof'] == 'gable':
            line = roof & inside & ~outer & (np.abs(v) < 0.5)
            ridge |= line
            per_gable.append((index, b, line, u))
    for name, m in (('ridges', ridge), ('eaves', eave)):
        if m.sum():
            print(f'{name}: {m.sum()} samples, median {np.median(d[m]):.3f} / p90 {np.percentile(d[m], 90):.2f} GSD')
    for index, b, line, u in per_gable:
        if not line.sum():
            continue
        edges = np.linspace(-b['length'] / 2, b['length'] / 2, 9)
        bins = []
        for a, c in zip(edges[:-1], edges[1:]):
            m = line & (u >= a) & (u < c)
            bins.append(f'{np.percentile(d[m], 90):.2f}' if m.sum() else '-')
        print(f'  ridge of surface {index} (centre {b["centre"][0]:g}, {b["centre"][1]:g}): {line.sum()} samples, '
              f'median {np.median(d[line]):.3f} / p90 {np.percentile(d[line], 90):.2f} GSD; p90 along it: '
              + ' '.join(bins))


def wall_zones(scene, x, y, z, d, ground_x, ground_y, ground_z, gsd):
    """Wall samples by zone (corner, eave, foot, interior); see the module comment."""
    r = 3 * gsd
    # Lowest ground sample per 1 m cell, then over the 3 x 3 cells around: the ground at a
    # wall's foot (the cells under a building hold no ground samples).
    x0, y0 = np.floor(ground_x.min()) - 1, np.floor(ground_y.min()) - 1
    nx = int(np.ceil(ground_x.max() - x0)) + 2
    ny = int(np.ceil(ground_y.max() - y0)) + 2
    grid = np.full((nx, ny), np.inf)
    np.minimum.at(grid, ((ground_x - x0).astype(int), (ground_y - y0).astype(int)), ground_z)
    low = grid.copy()
    for i in (-1, 0, 1):
        for j in (-1, 0, 1):
            low = np.minimum(low, np.roll(np.roll(grid, i, axis=0), j, axis=1))
    ix = np.clip((x - x0).astype(int), 0, nx - 1)
    iy = np.clip((y - y0).astype(int), 0, ny - 1)
    foot_height = z - low[ix, iy]
    zone = np.full(len(x), 'other', dtype=object)
    for b in scene['surface']:
        if b['type'] != 'building':
            continue
        u, v = building_frame(b, x, y)
        lean = np.tan(np.radians(b.get('wall_lean_deg', [0, 0, 0, 0])))
        cx, cy = b['centre'][:2]
        cell = np.clip(int(cx - x0), 0, nx - 1), np.clip(int(cy - y0), 0, ny - 1)
        ground = low[cell] if np.isfinite(low[cell]) else b['centre'][2]
        hz = np.maximum(z - ground, 0.0)
        u0, u1 = -b['length'] / 2 - hz * lean[2], b['length'] / 2 + hz * lean[0]
        v0, v1 = -b['width'] / 2 - hz * lean[3], b['width'] / 2 + hz * lean[1]
        inside = (zone == 'other') & (u > u0 - 0.5) & (u < u1 + 0.5) & (v > v0 - 0.5) & (v < v1 + 0.5)
        du = np.minimum(np.abs(u - u0), np.abs(u - u1))
        dv = np.minimum(np.abs(v - v0), np.abs(v - v1))
        corner = inside & (du < r) & (dv < r)
        eave = inside & ~corner & (hz > b['height'] - r)
        foot = inside & ~corner & ~eave & (foot_height < r)
        zone[corner] = 'corner'
        zone[eave] = 'eave'
        zone[foot] = 'foot'
        zone[inside & ~corner & ~eave & ~foot] = 'interior'
    total = np.sum(d ** 2)
    print(f'walls by zone (within {r:.2f} m of a vertical corner, of the eave or above, of the ground):')
    for name in ('corner', 'eave', 'foot', 'interior', 'other'):
        m = zone == name
        if m.sum():
            print(f'  {name:8s} {m.sum():7d} samples ({100 * m.mean():4.1f} %), median {np.median(d[m]):.3f}, '
                  f'rms {np.sqrt(np.mean(d[m] ** 2)):.3f} GSD, {100 * np.sum(d[m] ** 2) / total:4.1f} % of the '
                  f'squared distance, {100 * np.mean(d[m] <= 1):.1f} % within 1 GSD')


def main(argv):
    if not argv or argv[0].startswith('-'):
        sys.exit(__doc__)
    cells = int(argv[argv.index('--cells') + 1]) if '--cells' in argv else 0
    files = [a for i, a in enumerate(argv) if not a.startswith('--') and (i == 0 or argv[i - 1] != '--cells')]
    data = json.load(open(files[0]))
    if 'truth_samples' not in data:
        sys.exit(f'{files[0]}: no truth_samples (run facets evaluate with --samples)')
    gsd = data['ground_pixel_size']
    x, y, z, label, views, dist = np.array(data['truth_samples'], dtype=float).T
    seen = views >= 2
    d = dist / gsd
    wall = (label == 2) & seen
    print(f'walls >= 2 views: {wall.sum()} samples, {100 * np.mean(d[wall] <= 1):.1f} % within 1 GSD, '
          f'median {np.median(d[wall]):.3f}, rms {np.sqrt(np.mean(d[wall] ** 2)):.3f} GSD')
    for name, value in (('roofs', 1), ('ground', 0)):
        m = (label == value) & seen
        print(f'{name}: median {np.median(d[m]):.3f} GSD (>= 2 views), {np.median(d[label == value]):.3f} (all)')
    for lean in data.get('leaning_walls', []):
        print(f'leaning wall of building {lean.get("building")}: {lean["lean_deg"]:.2f} deg (true '
              f'{lean["true_lean_deg"]:.2f}), plane rms {lean["rms"]:.3f} m over {lean["vertices"]} vertices')
    print('crossing facet pairs:', data.get('mesh_crossing_pairs'))
    if len(files) > 1:
        scene = json.load(open(files[1]))
        ridges_and_eaves(scene, x, y, (label == 1) & seen, d)
        ground = label == 0
        wall_zones(scene, x[wall], y[wall], z[wall], d[wall], x[ground], y[ground], z[ground], gsd)
    if cells > 0:
        print(f'walls: the {cells} cells of 2 m with most of the squared distance')
        wall_cells(x[wall], y[wall], z[wall], d[wall], cells)


if __name__ == '__main__':
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # quiet under `| head`
    main(sys.argv[1:])
