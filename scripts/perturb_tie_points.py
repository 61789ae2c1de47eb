#!/usr/bin/env python3
"""perturb_tie_points.py SRC DST SEED AMP: copy a COLMAP text model (cameras.txt, images.txt,
points3D.txt) with every tie point moved by uniform noise of at most AMP model units per axis.

How far a run's result moves under a change of the last bits of its input (docs/EXPERIMENTS.md
"A micrometre of the tie points against the CPU's kernels")."""
import random, shutil, sys, os
src, dst, seed, amp = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
os.makedirs(dst, exist_ok=True)
for f in ("cameras.txt", "images.txt"):
    shutil.copy(os.path.join(src, f), os.path.join(dst, f))
rng = random.Random(seed)
with open(os.path.join(src, "points3D.txt")) as fi, open(os.path.join(dst, "points3D.txt"), "w") as fo:
    for line in fi:
        if line.startswith("#") or not line.strip():
            fo.write(line); continue
        t = line.split()
        for i in (1, 2, 3):
            t[i] = repr(float(t[i]) + rng.uniform(-amp, amp))
        fo.write(" ".join(t) + "\n")
