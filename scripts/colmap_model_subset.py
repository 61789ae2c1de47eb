#!/usr/bin/env python3
"""Copies a COLMAP text model without some images, for peers that have no --exclude-images.

    colmap_model_subset.py SPARSE SPEC OUT

SPEC is Facets' image selection (io/image_subset.cc): every-5th / every-N (images sorted by
name, the N-th, 2N-th, ... held out), a comma list of names, or a file of names (one per line,
# comments). The held-out images leave images.txt; their observations leave points3D.txt;
points left with fewer than two images are dropped and their 2D observations in the kept
images are set to -1. The held-out names are printed.
"""
import os
import re
import sys


def data_lines(path):
    with open(path) as f:
        return [line.rstrip("\n") for line in f if not line.startswith("#")]


def read_images(path):
    lines = data_lines(path)
    images = []
    i = 0
    while i < len(lines):
        if not lines[i].strip():
            i += 1
            continue
        header = lines[i]
        points = lines[i + 1] if i + 1 < len(lines) else ""
        fields = header.split()
        images.append({"id": int(fields[0]), "name": " ".join(fields[9:]), "header": header,
                       "points": points})
        i += 2
    return images


def selected_names(images, spec):
    match = re.fullmatch(r"every-(\d+)(st|nd|rd|th)?", spec)
    if match:
        n = int(match.group(1))
        if n < 2:
            sys.exit(f"image selection {spec}: N must be at least 2")
        by_name = sorted(image["name"] for image in images)
        return set(by_name[n - 1::n])
    if os.path.isfile(spec):
        with open(spec) as f:
            names = [l.strip() for l in f if l.strip() and not l.strip().startswith("#")]
    else:
        names = [n.strip() for n in spec.split(",") if n.strip()]
    known = {image["name"] for image in images}
    for name in names:
        if name not in known:
            sys.exit(f"image selection {spec}: no image named {name} in the model")
    return set(names)


def kept_points(points_path, dropped_ids):
    """Returns {point id: line} of the points seen by two or more kept images."""
    kept = {}
    for line in data_lines(points_path):
        fields = line.split()
        if not fields:
            continue
        track = list(zip(fields[8::2], fields[9::2]))
        track = [(i, p) for i, p in track if int(i) not in dropped_ids]
        if len({i for i, _ in track}) < 2:
            continue
        kept[int(fields[0])] = " ".join(fields[:8] + [x for pair in track for x in pair])
    return kept


def without_dropped_points(points_line, kept_ids):
    fields = points_line.split()
    for k in range(2, len(fields), 3):
        if int(fields[k]) != -1 and int(fields[k]) not in kept_ids:
            fields[k] = "-1"
    return " ".join(fields)


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    sparse, spec, out = sys.argv[1:]
    images = read_images(os.path.join(sparse, "images.txt"))
    held_out = selected_names(images, spec)
    dropped_ids = {image["id"] for image in images if image["name"] in held_out}
    points = kept_points(os.path.join(sparse, "points3D.txt"), dropped_ids)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(sparse, "cameras.txt")) as src, \
            open(os.path.join(out, "cameras.txt"), "w") as dst:
        dst.write(src.read())
    with open(os.path.join(out, "images.txt"), "w") as f:
        for image in images:
            if image["id"] in dropped_ids:
                continue
            f.write(image["header"] + "\n")
            f.write(without_dropped_points(image["points"], points) + "\n")
    with open(os.path.join(out, "points3D.txt"), "w") as f:
        for line in points.values():
            f.write(line + "\n")
    print("held out: " + ", ".join(sorted(held_out)))
    print(f"kept {len(images) - len(dropped_ids)} images, {len(points)} points")


if __name__ == "__main__":
    main()
