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
        ridges_and_eaves(json.load(open(files[1])), x, y, (label == 1) & seen, d)
    if cells > 0:
        print(f'walls: the {cells} cells of 2 m with most of the squared distance')
        wall_cells(x[wall], y[wall], z[wall], d[wall], cells)


if __name__ == '__main__':
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # quiet under `| head`
    main(sys.argv[1:])
