"""Opens a .msh file with Gmsh's own API and prints what Gmsh sees as JSON (used by
tests/interop.rs): nodes, 2D elements by type, and each physical group with its name and the
number of elements in it."""
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
    groups.append({
        "dim": dim,
        "tag": tag,
        "name": gmsh.model.getPhysicalName(dim, tag),
        "elements": count,
    })
gmsh.finalize()
print(json.dumps({"nodes": len(node_tags), "elements": by_type, "groups": groups}))
