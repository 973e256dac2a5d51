"""Meshes a planar straight-line graph with Gmsh (used by `cargo xtask compare gmsh`).

Input JSON on stdin: {"width", "height", "points": [[x, y], ...] (y up), "edges": [[a, b], ...],
"size": lc, "algorithm": "blossom" | "quasi-structured"}. The domain rectangle is cut by every
edge (OpenCASCADE fragment), each piece meshed with quads. Output JSON: nodes, quads and triangles
(0-based), the seconds of the meshing call alone, and the seconds of building the geometry (the
points, the lines, the fragment and its synchronisation) before it."""
import json
import sys
import time

import gmsh

spec = json.load(sys.stdin)
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
occ = gmsh.model.occ
geometry_start = time.perf_counter()
w, h = spec["width"], spec["height"]
rect = occ.addRectangle(0, 0, 0, w, h)
tags = [occ.addPoint(x, y, 0) for x, y in spec["points"]]
lines = []
for a, b in spec["edges"]:
    (xa, ya), (xb, yb) = spec["points"][a], spec["points"][b]
    on_border = (xa == xb and xa in (0, w)) or (ya == yb and ya in (0, h))
    if not on_border:
        lines.append(occ.addLine(tags[a], tags[b]))
occ.fragment([(2, rect)], [(1, l) for l in lines])
occ.synchronize()
geometry_seconds = time.perf_counter() - geometry_start
lc = spec["size"]
gmsh.option.setNumber("Mesh.MeshSizeMax", lc)
gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
if spec["algorithm"] == "blossom":
    gmsh.option.setNumber("Mesh.Algorithm", 8)  # Frontal-Delaunay for quads
    # Blossom recombination, then the all-quad subdivision of the hybrid mesh (Gmsh's full-quad
    # recombination, algorithm 3, refuses curves of a single segment, which G' has).
    gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)
    gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)
else:
    gmsh.option.setNumber("Mesh.Algorithm", 11)  # quasi-structured quads
gmsh.option.setNumber("Mesh.RecombineAll", 1)
start = time.perf_counter()
gmsh.model.mesh.generate(2)
seconds = time.perf_counter() - start
node_tags, coords, _ = gmsh.model.mesh.getNodes()
index = {int(t): i for i, t in enumerate(node_tags)}
nodes = [[coords[3 * i], coords[3 * i + 1]] for i in range(len(node_tags))]
quads, triangles = [], []
types, element_tags, element_nodes = gmsh.model.mesh.getElements(2)
for t, _, conn in zip(types, element_tags, element_nodes):
    k = {2: 3, 3: 4}.get(int(t))
    if k is None:
        continue
    cells = [[index[int(n)] for n in conn[i:i + k]] for i in range(0, len(conn), k)]
    (quads if k == 4 else triangles).extend(cells)
gmsh.finalize()
print(json.dumps({"nodes": nodes, "quads": quads, "triangles": triangles, "seconds": seconds,
                  "geometry_seconds": geometry_seconds}))
