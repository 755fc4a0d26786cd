"""Reads an Abaqus input file written by `fibra export` with meshio and checks it against what
the test expects (a JSON file): node and element counts, C3D8R elements, the element and node
sets and their sizes, each face set on its face, and one orientation per element whose axis 1
is the expected fiber direction and axis 2 a unit vector normal to it.

    python3 check_inp.py voxels.inp expected.json

Prints what differs and exits 1, or exits 0.
"""
import json
import sys

import meshio
import numpy as np


def distribution_rows(path):
    """The data lines of the *Distribution block, as {element: (a, b)}."""
    rows, inside = {}, False
    with open(path) as f:
        for line in f:
            if line.startswith("*"):
                inside = line.lower().startswith("*distribution,")
                continue
            if not inside or line.startswith("**") or not line.strip():
                continue
            fields = [v.strip() for v in line.split(",")]
            if fields[0] == "":
                continue  # the default line
            values = [float(v) for v in fields[1:]]
            rows[int(fields[0])] = (np.array(values[:3]), np.array(values[3:6]))
    return rows


def main():
    path, expected_path = sys.argv[1], sys.argv[2]
    with open(expected_path) as f:
        expected = json.load(f)
    mesh = meshio.read(path, file_format="abaqus")
    problems = []

    def check(what, got, want):
        if got != want:
            problems.append(f"{what}: got {got}, expected {want}")

    check("nodes", len(mesh.points), expected["nodes"])
    check("cell blocks", [c.type for c in mesh.cells], ["hexahedron"])
    check("elements", sum(len(c.data) for c in mesh.cells), expected["elements"])
    elsets = {name: sum(len(block) for block in blocks) for name, blocks in mesh.cell_sets.items()}
    check("element sets", elsets, expected["elsets"])
    nsets = {name: len(ids) for name, ids in mesh.point_sets.items()}
    check("node sets", nsets, expected["nsets"])
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    for name, ids in mesh.point_sets.items():
        axis, side = "XYZ".index(name[0]), name[1:]
        face = lo[axis] if side == "MIN" else hi[axis]
        if not np.allclose(mesh.points[ids, axis], face, rtol=0, atol=1e-12 * (hi - lo).max()):
            problems.append(f"node set {name} has nodes off its face")
    with open(path) as f:
        text = f.read().lower()
    check("C3D8R element type", "*element, type=c3d8r" in text, True)
    rows = distribution_rows(path)
    check("orientation rows", len(rows), expected["elements"])
    for element, direction in expected["directions"].items():
        a, b = rows[int(element)]
        want = np.array(direction)
        if np.linalg.norm(want) == 0:
            want = np.array([1.0, 0.0, 0.0])
        if np.linalg.norm(a - want) > 1e-6:
            problems.append(f"element {element}: axis 1 {a}, expected {want}")
        if abs(np.linalg.norm(b) - 1) > 1e-6 or abs(a.dot(b)) > 1e-6:
            problems.append(f"element {element}: axis 2 {b} is not a unit vector normal to axis 1")
    sections = [line for line in text.splitlines() if line.startswith("*solid section")]
    check("solid sections", len(sections), len(expected["elsets"]))
    for line in problems:
        print(line)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
