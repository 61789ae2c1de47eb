#!/usr/bin/env python3
# Usage: python3 scripts/block_wall_bands.py SCENE.json SAMPLES.json [--min-views N]
# Where a block scene's walls are lost: completeness at 1 GSD of the wall truth samples
# (`facets evaluate --samples --json SAMPLES.json`), per building of the scene file and per
# wall side (N, E, S, W in the building's own axes) and by height band (share of the
# building's height), with the median distance. Walls lost only at eaves and feet show
# low figures in the outer bands; walls crumpled all over show them in every band
# (docs/EXPERIMENTS.md, session 10). numpy required (/usr/bin/python3 on Debian).
import json, sys
import numpy as np

BANDS = [0, .15, .3, .5, .7, .85, 1.01, 10]


def main(argv):
    if len(argv) < 2: sys.exit(__doc__ or 'usage: block_wall_bands.py SCENE.json SAMPLES.json [--min-views N]')
    min_views = int(argv[argv.index('--min-views') + 1]) if '--min-views' in argv else 2
    scene = json.load(open(argv[0]))
    data = json.load(open(argv[1]))
    if 'truth_samples' not in data: sys.exit(f'{argv[1]}: no truth_samples (run facets evaluate with --samples)')
    gsd = data['ground_pixel_size']
    x, y, z, label, views, dist = np.array(data['truth_samples'], dtype=float).T
    wall = (label == 2) & (views >= min_views)
    print(f'wall samples seen by >= {min_views} images: {wall.sum()}, within 1 GSD {100 * np.mean(dist[wall] <= gsd):.1f} %')
    print('height bands (share of the building height): ' + ' '.join(f'{a:g}-{b:g}' for a, b in zip(BANDS[:-2], BANDS[1:-1])) + ', above')
    buildings = [o for o in scene['surface'] if o['type'] == 'building']
    for i, b in enumerate(buildings):
        cx, cy = b['centre'][:2]
        half_l, half_w, height = b['length'] / 2, b['width'] / 2, b['height']
        az = np.radians(b.get('azimuth_deg', 0.0))
        u = np.cos(az) * (x - cx) + np.sin(az) * (y - cy)
        v = -np.sin(az) * (x - cx) + np.cos(az) * (y - cy)
        near = wall & (np.abs(u) < half_l + 3) & (np.abs(v) < half_w + 3)
        if not near.any(): continue
        ok = dist[near] <= gsd
        print(f'building {i} ({b["roof"]}, {b["length"]:g} x {b["width"]:g} x {height:g} m): {near.sum()} samples, within 1 GSD {100 * ok.mean():.1f} %')
        uu, vv, rel = u[near], v[near], z[near] / height
        side = np.where(np.abs(uu) / half_l > np.abs(vv) / half_w, np.where(uu > 0, 'E', 'W'), np.where(vv > 0, 'N', 'S'))
        for s in 'NESW':
            k = side == s
            if k.sum() < 50: continue
            cells = []
            for a, c in zip(BANDS[:-1], BANDS[1:]):
                m = k & (rel >= a) & (rel < c)
                cells.append(f'{100 * ok[m].mean():3.0f}' if m.sum() > 20 else '  -')
            print(f'  {s}: {k.sum():6d} samples, {100 * ok[k].mean():5.1f} %, by band {" ".join(cells)} %, median {np.median(dist[near][k]) / gsd:.2f} GSD')


if __name__ == '__main__':
    main(sys.argv[1:])
