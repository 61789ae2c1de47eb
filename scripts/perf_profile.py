#!/usr/bin/env python3
"""Usage: perf script -i perf.data -F tid,time,ip,sym,dso | python3 scripts/perf_profile.py

A sampling profile of `facets reconstruct` (recorded with `perf record -e cpu-clock -F 99
--call-graph dwarf,12288`) grouped as the run's profile in report.json groups it
(docs/BENCHMARKS.md, profile of the aerial path):
  - by category: the innermost frame, leaf outward, that names one; Embree's frames carry
    no unwind information and count as casting unless an Embree scene build calls them;
    memset and page faults under WindowAdjustment::Accumulate are its share buffers;
  - by stage: a main-thread sample goes to its outermost pipeline frame (the samples under
    JudgeProposal, the trials, apart); a worker thread's sample has no pipeline frame on
    its stack and goes to the stage of the main thread's latest sample before it;
  - the top functions by self and inclusive share.
"""
import bisect
import re
import sys
from collections import Counter

CATEGORIES = [
    ("scene build/refit (Embree)",
     r"TriangleScene::(AddOccluders|UpdateVertices|TriangleScene)|SurfaceScene::(Update|SurfaceScene)|rtcCommitScene"),
    ("cast", r"libembree|rtcIntersect|CastPixels|CastAll|ProjectedBlocks|ProjectBox|PixelRays|DropBackground|"
             r"TriangleScene::Intersect"),
    ("linearise: share buffers (memset, page faults)",
     r"^(__memset|asm_exc_page_fault|exc_page_fault|clear_page|pvm_irq|__raw_callee)"),
    ("linearise", r"WindowAdjustment::(Accumulate|ReduceShares|Linearise|RobustScale|VertexViews|InitialiseGrey|"
                  r"AddRidge)|facets::Linearise|SampleGrey"),
    ("solve", r"SparseLdlt|SimplicialLDLT|LDLT|SolvePcg|AMDOrdering|permute_symm|CsrMatrix::ToEigen|"
              r"SolveNormalEquations"),
    ("fold guard (CGAL box intersection)", r"LimitFoldingSteps"),
    ("precision, residual correlation", r"ComputePrecision|ResidualCorrelation|FinishReport"),
    ("update (vertices, normals, tessellation)",
     r"UpdateUnknowns|UpdateTessellationPoints|BuildPatches|ComputeCornerNormals|UpdateVertexNormals"),
    ("window setup (creases, tessellation, pattern)",
     r"PrepareRun|BuildTopologyTables|BuildPattern|FromCliques|DetectCreaseEdges|Tessellate|ExtractWindowMesh|"
     r"CollectOccluders|FaceBoxes|PartitionIntoWindows|PartitionFacesIntoWindows|IndependentWindowGroups"),
    ("normal search", r"SearchAlongNormals"),
    ("plane propagation", r"PropagatePlanes"),
    ("crossing counts", r"CountSelfIntersections|CountFoldedFaces|CountSurfaceFaults"),
    ("untangling", r"UntangleSelfIntersections"),
    ("products (flatten crossing facets, files)", r"FlattenCrossingFacets|WriteProducts"),
    ("images, pyramids", r"LevelImageSource|ReadImage|ReduceImage|Pyramid|png|inflate"),
    ("mesh ops (descent, walls, lips, relax)",
     r"DescendOneLevel|LayWallCorners|LayUnseenLips|RelaxUnseen|QualityPass|Subdivide"),
    ("tbb scheduler / idle", r"tbb::|sched_yield|libtbb"),
]
COMPILED = [(name, re.compile(rx)) for name, rx in CATEGORIES]
SHARE_BUFFERS = 2  # index of the memset / page-fault rule

STAGES = ["SplitStretchedEdges", "LayWallCorners", "SearchRounds", "StraightenCreases", "LayUnseenLips",
          "SearchBeforeLevel", "AdjustLevel", "DescendOneLevel", "GoBackUp", "UntangleCrossings",
          "CloseLevelReport", "RelaxUnseen", "HoldInsideVisualHull", "LevelImageSource", "MakeStartSurface",
          "PlanStart", "WriteProducts", "FlattenCrossingFacets"]
STAGE_RX = {s: re.compile(r"::" + s + r"(\s|\(|$)") for s in STAGES}


def read_samples(stream):
    """(tid, time, frames leaf first) per sample."""
    head, frames = None, []
    for line in stream:
        line = line.rstrip("\n")
        if not line.strip():
            if head:
                yield head[0], head[1], frames
            head, frames = None, []
        elif line[0] not in " \t":
            m = re.match(r"\s*(\d+)\s+([\d.]+):", line)
            head = (int(m.group(1)), float(m.group(2))) if m else None
        else:
            parts = line.strip().split(None, 1)
            if len(parts) == 2:
                frames.append(parts[1])
    if head:
        yield head[0], head[1], frames


def category(frames):
    name, rx = COMPILED[SHARE_BUFFERS]
    if frames and rx.search(frames[0]):
        return name if any("WindowAdjustment::Accumulate" in f for f in frames) else "kernel, memset elsewhere"
    for f in frames:
        for name, rx in COMPILED:
            if rx.search(f):
                return name
    return "other"


def stage(frames):
    for f in reversed(frames):  # outermost first
        for s in STAGES:
            if STAGE_RX[s].search(f):
                return s + (" > trial" if any("JudgeProposal" in g for g in frames) else "")
    return None


def function(frame):
    dso = re.search(r"\s+\((\S+)\)$", frame)
    frame = frame[:dso.start()] if dso else frame
    if frame == "[unknown]" and dso:
        return "[unknown] in " + dso.group(1).rsplit("/", 1)[-1]
    frame = frame.replace("(anonymous namespace)::", "")
    m = re.match(r"(facets::[A-Za-z_:]*[A-Za-z_])", frame)
    return m.group(1) if m else frame[:80]


def main():
    samples = list(read_samples(sys.stdin))
    total = len(samples)
    if total == 0:
        sys.exit("no samples on stdin (perf script -F tid,time,ip,sym,dso)")
    categories, self_time, inclusive = Counter(), Counter(), Counter()
    stages = [stage(frames) for _, _, frames in samples]
    for _, _, frames in samples:
        categories[category(frames)] += 1
        if frames:
            self_time[function(frames[0])] += 1
        for f in set(function(f) for f in frames):
            inclusive[f] += 1
    main_tid = Counter(s[0] for s, st in zip(samples, stages) if st).most_common(1)[0][0]
    main_thread = sorted((s[1], st) for s, st in zip(samples, stages) if st and s[0] == main_tid)
    times = [t for t, _ in main_thread]
    by_stage = Counter()
    for (_, t, _), st in zip(samples, stages):
        if st is None:
            i = bisect.bisect_right(times, t) - 1
            st = main_thread[i][1] if i >= 0 else "(before the first stage)"
        by_stage[st] += 1
    for title, counts, limit in (("by category", categories, None), ("by stage", by_stage, None),
                                 ("top functions by self", self_time, 25),
                                 ("top functions by inclusive", inclusive, 25)):
        print(f"{title} ({total} samples):")
        for name, n in counts.most_common(limit):
            print(f"  {100.0 * n / total:5.1f} %  {name}")


if __name__ == "__main__":
    main()
