#!/usr/bin/env python3
"""How much a silhouette IoU loses to a camera that is off by a fraction of a pixel.

Reads the foreground masks that `facets evaluate --silhouette --mask-dir DIR` writes (grey 255
"both" and 170 "foreground only" are the image's foreground), converted to binary PGM
(`oiiotool DIR/X.png -o DIR/X.pgm`), and scores each mask against itself shifted by 0.5, 1
and 1.5 pixels (bilinear, thresholded at one half) along x, y and the diagonal. Prints per
image: foreground pixels, outline length (pixel edges) and the lowest IoU over the three
directions at each shift: what a perfect surface would score through a calibration that far
off.

usage: mask_shift_iou.py MASK.pgm [MASK.pgm ...]
"""
import sys

import numpy as np


def read_pgm(path):
    data = open(path, 'rb').read()
    magic, width, height, _, body = data.split(maxsplit=4)
    if magic != b'P5':
        sys.exit(f'{path}: not a binary PGM')
    width, height = int(width), int(height)
    return np.frombuffer(body[-width * height:], np.uint8).reshape(height, width)


def shifted(mask, dx, dy):
    f = mask.astype(float)
    ix, iy = int(np.floor(dx)), int(np.floor(dy))
    fx, fy = dx - ix, dy - iy
    r = np.roll(np.roll(f, iy, 0), ix, 1)
    rx, ry = np.roll(r, 1, 1), np.roll(r, 1, 0)
    g = ((1 - fx) * (1 - fy) * r + fx * (1 - fy) * rx + (1 - fx) * fy * ry
         + fx * fy * np.roll(rx, 1, 0))
    return g >= 0.5


def iou(a, b):
    return (a & b).sum() / (a | b).sum()


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    print('mask  foreground  outline  IoU at 0.5 / 1 / 1.5 px')
    for path in sys.argv[1:]:
        grey = read_pgm(path)
        mask = (grey == 170) | (grey == 255)
        outline = (mask ^ np.roll(mask, 1, 0)).sum() + (mask ^ np.roll(mask, 1, 1)).sum()
        directions = lambda s: ((s, 0), (0, s), (s / 2 ** .5, s / 2 ** .5))
        lows = [min(iou(mask, shifted(mask, dx, dy)) for dx, dy in directions(s))
                for s in (0.5, 1.0, 1.5)]
        print(path, mask.sum(), outline, ' '.join(f'{v:.3f}' for v in lows))


if __name__ == '__main__':
    main()
