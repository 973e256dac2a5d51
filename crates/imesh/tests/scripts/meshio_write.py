"""Writes the triangles and quads of a mesh again with meshio, as an ASCII VTK XML file and an
Abaqus file next to it, and prints their paths as JSON (used by tests/interop.rs: imesh must read
what meshio writes, not only what imesh writes)."""
import json
import sys

import meshio

source = meshio.read(sys.argv[1])
cells = [block for block in source.cells if block.type in ("triangle", "quad")]
mesh = meshio.Mesh(source.points, cells)
base = sys.argv[1].rsplit(".", 1)[0]
out = {"vtu": base + ".meshio.vtu", "inp": base + ".meshio.inp"}
meshio.write(out["vtu"], mesh, binary=False)
meshio.write(out["inp"], mesh)
print(json.dumps(out))
