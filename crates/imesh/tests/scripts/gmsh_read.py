"""Opens a .msh file with Gmsh's own API and prints what Gmsh sees as JSON (used by
tests/interop.rs): nodes, 2D elements by type, and each physical group with its name and the
number of elements in it, and the extent of its nodes."""
import json
import sys

import gmsh

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.open(sys.argv[1])
node_tags, _, _ = gmsh.model.mesh.getNodes()
types, element_tags, _ = gmsh.model.mesh.getElements(2)
by_type = {}
for t, tags in zip(types, element_tags):
    name = gmsh.model.mesh.getElementProperties(t)[0]
    by_type[name] = by_type.get(name, 0) + len(tags)
groups = []
for dim, tag in gmsh.model.getPhysicalGroups():
    count = 0
    for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        _, tags, _ = gmsh.model.mesh.getElements(dim, entity)
        count += sum(len(t) for t in tags)
    _, coords = gmsh.model.mesh.getNodesForPhysicalGroup(dim, tag)
    xs, ys = list(coords[0::3]), list(coords[1::3])
    groups.append({
        "dim": dim,
        "tag": tag,
        "name": gmsh.model.getPhysicalName(dim, tag),
        "elements": count,
        "x": [min(xs), max(xs)] if xs else None,
        "y": [min(ys), max(ys)] if ys else None,
    })
gmsh.finalize()
print(json.dumps({"nodes": len(node_tags), "elements": by_type, "groups": groups}))
