"""Reads a second-order mesh with meshio (and a .msh file with Gmsh too) and prints as JSON
its cells, the area its 9-node quads cover and their smallest Jacobian determinant at 3 × 3
Gauss points, as each library computes them (used by tests/interop.rs)."""
import json
import sys

import meshio
import numpy as np

path = sys.argv[1]
mesh = meshio.read(path)
cells = {}
for block in mesh.cells:
    cells[block.type] = cells.get(block.type, 0) + int(len(block.data))

# The 9-node quad's Lagrange basis (Gmsh's and VTK's node order) and its derivatives.
g = np.array([0.5 - 0.5 * np.sqrt(0.6), 0.5, 0.5 + 0.5 * np.sqrt(0.6)])
w = np.array([5.0, 8.0, 5.0]) / 18.0
lagrange = lambda t: np.array([(1 - t) * (1 - 2 * t), 4 * t * (1 - t), t * (2 * t - 1)])
slope = lambda t: np.array([4 * t - 3, 4 - 8 * t, 4 * t - 1])
grid = [[0, 7, 3], [4, 8, 6], [1, 5, 2]]  # node at (i/2, j/2)
area, smallest = 0.0, float("inf")
for block in mesh.cells:
    if block.type != "quad9":
        continue
    x = mesh.points[block.data][:, :, :2]
    for a in range(3):
        for b in range(3):
            xu = sum(slope(g[a])[i] * lagrange(g[b])[j] * x[:, grid[i][j]] for i in range(3) for j in range(3))
            xv = sum(lagrange(g[a])[i] * slope(g[b])[j] * x[:, grid[i][j]] for i in range(3) for j in range(3))
            det = xu[:, 0] * xv[:, 1] - xu[:, 1] * xv[:, 0]
            area += float(w[a] * w[b] * det.sum())
            smallest = min(smallest, float(det.min()))
out = {"cells": cells, "area": area, "min_jacobian": smallest}

if path.endswith(".msh"):
    import gmsh

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.open(path)
    types, _, _ = gmsh.model.mesh.getElements(2)
    names, least = [], float("inf")
    for t in types:
        names.append(gmsh.model.mesh.getElementProperties(t)[0])
        local, _ = gmsh.model.mesh.getIntegrationPoints(t, "Gauss4")
        _, determinants, _ = gmsh.model.mesh.getJacobians(t, local)
        least = min(least, float(np.min(determinants)))
    gmsh.finalize()
    out["gmsh_elements"] = names
    out["gmsh_min_jacobian"] = least
print(json.dumps(out))
