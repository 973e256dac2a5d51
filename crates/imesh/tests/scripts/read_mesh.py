"""Reads a mesh with meshio and prints what it found as JSON (used by tests/interop.rs)."""
import json
import sys

import meshio

mesh = meshio.read(sys.argv[1])
cells = {}
for block in mesh.cells:
    cells[block.type] = cells.get(block.type, 0) + int(len(block.data))
labels = sorted({int(v) for block in mesh.cell_data.get("label", []) for v in block.ravel()})
physical = sorted({
    int(v)
    for block, tags in zip(mesh.cells, mesh.cell_data.get("gmsh:physical", []))
    if block.type in ("triangle", "quad")
    for v in tags
})
# The groups meshio gives the line cells (one per line: the first of its entity's groups).
group_name = {(int(v[1]), int(v[0])): k for k, v in mesh.field_data.items()}
line_groups = sorted({
    group_name.get((1, int(v)), str(int(v)))
    for block, tags in zip(mesh.cells, mesh.cell_data.get("gmsh:physical", []))
    if block.type == "line"
    for v in tags
})
# Signed areas in the file's frame: every element must be counter-clockwise.
negative = 0
area = 0.0
for block in mesh.cells:
    if block.type not in ("triangle", "quad"):
        continue
    for cell in block.data:
        p = mesh.points[cell][:, :2]
        a = 0.5 * sum(p[i - 1][0] * p[i][1] - p[i][0] * p[i - 1][1] for i in range(len(p)))
        negative += a <= 0
        area += a
print(json.dumps({
    "points": int(len(mesh.points)),
    "cells": cells,
    "labels": labels,
    "physical": physical,
    "names": sorted(mesh.field_data.keys()),
    "line_groups": line_groups,
    "cell_sets": sorted(mesh.cell_sets.keys()),
    "point_sets": sorted(mesh.point_sets.keys()),
    "negative": int(negative),
    "area": float(area),
}))
