#!/usr/bin/env python3
# Usage: python3 scripts/tin_topology.py RUN/tin.ply ...
# Is the TIN one sheet? Connected components (through shared edges), boundary loops
# (edges used by one face, chained), non-manifold edges (used by more than two faces),
# Euler characteristic V - E + F (a disc: 1; each hole inside lowers it by 1, so a single
# sheet without holes has 1 component, 1 boundary loop and characteristic 1).
# Self-intersections are counted by the engine (report.json, levels[].self_intersections).
import collections, os, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tin_plane_fit import read  # noqa: E402


def main(paths):
    for path in paths:
        vs, faces = read(path)
        uses = collections.Counter()
        for f in faces:
            for i in range(len(f)):
                a, b = f[i], f[(i + 1) % len(f)]
                uses[(min(a, b), max(a, b))] += 1
        parent = list(range(len(faces)))

        def find(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i
        by_edge = collections.defaultdict(list)
        for k, f in enumerate(faces):
            for i in range(len(f)):
                a, b = f[i], f[(i + 1) % len(f)]
                by_edge[(min(a, b), max(a, b))].append(k)
        for ks in by_edge.values():
            for k in ks[1:]:
                parent[find(k)] = find(ks[0])
        components = len({find(k) for k in range(len(faces))})
        border = [e for e, n in uses.items() if n == 1]
        nonmanifold = sum(1 for n in uses.values() if n > 2)
        # Boundary loops: components of the border edges' graph.
        bparent = {}

        def bfind(v):
            while bparent[v] != v:
                bparent[v] = bparent[bparent[v]]
                v = bparent[v]
            return v
        for a, b in border:
            bparent.setdefault(a, a)
            bparent.setdefault(b, b)
            bparent[bfind(a)] = bfind(b)
        loops = len({bfind(v) for v in bparent})
        used = {i for f in faces for i in f}
        euler = len(used) - len(uses) + len(faces)
        print(f'{path}: {len(used)} vertices (of {len(vs)}), {len(faces)} faces, {len(uses)} edges; '
              f'{components} connected component(s), {loops} boundary loop(s), {len(border)} border edges, '
              f'{nonmanifold} non-manifold edges, Euler characteristic {euler}')


if __name__ == '__main__':
    main(sys.argv[1:])
