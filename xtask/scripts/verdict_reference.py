"""Quality reference table from VTK's vtkMeshQuality (Verdict), for imesh-quality's tests.

Run by `cargo xtask fixtures quality` inside a virtual environment with vtk==9.7.2:
    python verdict_reference.py OUT_DIR
Writes OUT_DIR/verdict-quads.csv and OUT_DIR/verdict-triangles.csv: one element per row, its
corner coordinates and the value of every metric as VTK computes it. Floats are written with repr()
so that they read back bit for bit. Deterministic (fixed seed).
"""
import math
import random
import sys

import vtk

QUAD_METRICS = [
    ("area", "Area"),
    ("shape", "Shape"),
    ("relative_size_squared", "RelativeSizeSquared"),
    ("shape_and_size", "ShapeAndSize"),
    ("scaled_jacobian", "ScaledJacobian"),
    ("condition", "Condition"),
    ("jacobian", "Jacobian"),
    ("minimum_angle", "MinAngle"),
    ("maximum_angle", "MaxAngle"),
    ("aspect_ratio", "AspectRatio"),
    ("edge_ratio", "EdgeRatio"),
]
TRI_METRICS = [
    ("area", "Area"),
    ("shape", "Shape"),
    ("condition", "Condition"),
    ("scaled_jacobian", "ScaledJacobian"),
    ("minimum_angle", "MinAngle"),
    ("maximum_angle", "MaxAngle"),
    ("aspect_ratio", "AspectRatio"),
    ("relative_size_squared", "RelativeSizeSquared"),
    ("shape_and_size", "ShapeAndSize"),
]


def rotate(pts, angle, centre=(0.0, 0.0)):
    c, s = math.cos(angle), math.sin(angle)
    cx, cy = centre
    return [(cx + c * (x - cx) - s * (y - cy), cy + s * (x - cx) + c * (y - cy)) for x, y in pts]


def scale_translate(pts, k, dx=0.0, dy=0.0):
    return [(k * x + dx, k * y + dy) for x, y in pts]


def quads(rng):
    out = []
    # Squares and rectangles: axis-aligned, rotated, scaled, translated far away.
    for i in range(24):
        w, h = rng.choice([1.0, 1.0, 2.0, 0.5, 3.0]), rng.choice([1.0, 1.0, 0.25, 4.0])
        q = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
        if i % 3 == 1:
            q = rotate(q, rng.uniform(0, 2 * math.pi))
        if i % 4 == 2:
            q = scale_translate(q, rng.choice([1e-3, 7.0, 40.0]), rng.uniform(-1e6, 1e6), rng.uniform(-1e6, 1e6))
        out.append(("square", q))
    # Random convex: four angles on a jittered ellipse, counter-clockwise.
    for _ in range(90):
        a = sorted(rng.uniform(0, 2 * math.pi) for _ in range(4))
        rx, ry = rng.uniform(0.2, 3.0), rng.uniform(0.2, 3.0)
        q = [(rx * math.cos(t) * rng.uniform(0.8, 1.2), ry * math.sin(t) * rng.uniform(0.8, 1.2)) for t in a]
        q = scale_translate(q, rng.uniform(0.5, 20.0), rng.uniform(-50, 50), rng.uniform(-50, 50))
        out.append(("convex", q))
    # Nearly degenerate: slivers, nearly flat corners, tiny and collapsed quads.
    for i in range(30):
        e = 10.0 ** rng.uniform(-12, -2)
        kind = i % 6
        if kind == 0:
            q = [(0.0, 0.0), (1.0, 0.0), (1.0, e), (0.0, e)]
        elif kind == 1:
            q = [(0.0, 0.0), (1.0, 0.0), (2.0, e), (0.0, 1.0)]  # almost flat corner at P1
        elif kind == 2:
            s = 10.0 ** rng.uniform(-9, -6)
            q = scale_translate([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)], s)  # around Verdict's thresholds
        elif kind == 3:
            q = [(0.0, 0.0), (1.0, 0.0), (0.5, 1.0), (0.5, 1.0)]  # collapsed: P3 == P2
        elif kind == 4:
            q = [(0.0, 0.0), (0.0, 0.0), (1.0, 1.0), (0.0, 1.0)]  # repeated P1 == P0
        else:
            q = [(0.0, 0.0), (1.0, 0.0), (1.0 + e, 1.0), (e, 1.0)]
        out.append(("near_degenerate", rotate(q, rng.uniform(0, 2 * math.pi))))
    # Non-convex (arrow heads / darts) and bow-ties.
    for i in range(30):
        d = rng.uniform(0.05, 0.9)
        q = [(0.0, 0.0), (2.0, 1.0), (0.0, 2.0), (d, 1.0)]
        if i % 5 == 4:
            q = [(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]  # bow-tie
            q = scale_translate(q, rng.uniform(0.5, 3.0))
        out.append(("non_convex", rotate(q, rng.uniform(0, 2 * math.pi))))
    # Inverted: clockwise copies of convex quads.
    for _ in range(30):
        a = sorted(rng.uniform(0, 2 * math.pi) for _ in range(4))
        q = [(math.cos(t) * rng.uniform(0.7, 1.3), math.sin(t) * rng.uniform(0.7, 1.3)) for t in a]
        out.append(("inverted", list(reversed(q))))
    return out


def triangles(rng):
    out = []
    h = math.sqrt(3.0) / 2.0
    for i in range(10):
        t = [(0.0, 0.0), (1.0, 0.0), (0.5, h)] if i % 2 == 0 else [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]
        out.append(("regular", scale_translate(rotate(t, rng.uniform(0, 6.3)), rng.uniform(0.1, 10), rng.uniform(-9, 9), 3.0)))
    for _ in range(60):
        t = [(rng.uniform(-5, 5), rng.uniform(-5, 5)) for _ in range(3)]
        out.append(("random", t))
    for i in range(20):
        e = 10.0 ** rng.uniform(-13, -2)
        kind = i % 5
        if kind == 0:
            t = [(0.0, 0.0), (1.0, 0.0), (0.5, e)]  # flat sliver
        elif kind == 1:
            t = [(0.0, 0.0), (1.0, 0.0), (1.0 + e, e)]  # needle
        elif kind == 2:
            t = [(0.0, 0.0), (1.0, 1.0), (2.0, 2.0)]  # collinear
        elif kind == 3:
            t = [(0.0, 0.0), (0.0, 0.0), (1.0, 0.5)]  # repeated vertex
        else:
            t = scale_translate([(0.0, 0.0), (1.0, 0.0), (0.3, 0.8)], 10.0 ** rng.uniform(-9, -6))
        out.append(("near_degenerate", rotate(t, rng.uniform(0, 6.3))))
    for _ in range(20):
        t = [(rng.uniform(-5, 5), rng.uniform(-5, 5)) for _ in range(3)]
        area2 = (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[1][1] - t[0][1]) * (t[2][0] - t[0][0])
        out.append(("inverted", t if area2 < 0 else [t[0], t[2], t[1]]))
    return out


def measure(elements, cell_type, metrics, setter_prefix):
    """One fresh grid per metric: VTK reuses size hints found on its input (see the reference)."""
    columns = {}
    for name, vtk_name in metrics:
        points = vtk.vtkPoints()
        points.SetDataTypeToDouble()
        grid = vtk.vtkUnstructuredGrid()
        for _, corners in elements:
            ids = vtk.vtkIdList()
            for x, y in corners:
                ids.InsertNextId(points.InsertNextPoint(x, y, 0.0))
            grid.InsertNextCell(cell_type, ids)
        grid.SetPoints(points)
        f = vtk.vtkMeshQuality()
        f.SetInputData(grid)
        getattr(f, setter_prefix + vtk_name)()
        f.Update()
        q = f.GetOutput().GetCellData().GetArray("Quality")
        columns[name] = [q.GetValue(i) for i in range(q.GetNumberOfTuples())]
    return columns


def write(path, elements, corners, metrics, columns):
    with open(path, "w") as out:
        out.write("# Produced by xtask/scripts/verdict_reference.py with VTK %s (vtkMeshQuality).\n" % vtk.vtkVersion.GetVTKVersion())
        coords = ["x%d,y%d" % (i, i) for i in range(corners)]
        out.write("kind," + ",".join(coords) + "," + ",".join(n for n, _ in metrics) + "\n")
        for i, (kind, pts) in enumerate(elements):
            row = [kind] + [repr(float(c)) for p in pts for c in p] + [repr(float(columns[n][i])) for n, _ in metrics]
            out.write(",".join(row) + "\n")


def main():
    out_dir = sys.argv[1]
    rng = random.Random(20261122)
    q = quads(rng)
    t = triangles(rng)
    write(out_dir + "/verdict-quads.csv", q, 4, QUAD_METRICS, measure(q, vtk.VTK_QUAD, QUAD_METRICS, "SetQuadQualityMeasureTo"))
    write(out_dir + "/verdict-triangles.csv", t, 3, TRI_METRICS, measure(t, vtk.VTK_TRIANGLE, TRI_METRICS, "SetTriangleQualityMeasureTo"))
    print("%d quads, %d triangles" % (len(q), len(t)))


if __name__ == "__main__":
    main()
