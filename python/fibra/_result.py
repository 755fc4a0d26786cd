"""Results: the output directory of a run read back as numpy arrays with named fields."""

import csv
import dataclasses
import json
import os
import pathlib
import xml.etree.ElementTree as ElementTree

import numpy as np

from . import _fibra
from ._case import _input_error


# The columns of fibra's CSV files that hold counts (the others that hold numbers are floats).
INTEGER_COLUMNS = {"node", "step_index", "increment", "iterations"}


def _column(name, values):
    """A CSV column as a numpy array: the count columns as int64, the numeric ones as float64
    (an empty cell is nan), the others as text."""
    if name in INTEGER_COLUMNS:
        try:
            return np.array([int(v) for v in values], dtype=np.int64)
        except ValueError:
            pass
    try:
        return np.array([float(v) if v.strip() else np.nan for v in values], dtype=np.float64)
    except ValueError:
        return np.array(values, dtype=str)


def read_csv(path):
    """A CSV file with a header line as a numpy structured array, one field per column, under
    the column's own name ("body:warp0.start:fx"): the count columns (node, step_index,
    increment, iterations) as int64, the other numeric ones as float64 (an empty cell is nan),
    the others as text. A last line without its end of line (a run killed while writing it) is
    left out."""
    path = os.fspath(path)
    try:
        with open(path, newline="", encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError as e:
        raise _input_error(path, "(file)", f"cannot be read: {e.strerror}") from None
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]  # a line cut short
    rows = list(csv.reader(text.splitlines()))
    if not rows:
        raise _input_error(path, "(file)", "empty: expected a header line")
    header, body = rows[0], rows[1:]
    if len(set(header)) != len(header) or not all(header):
        raise _input_error(path, "line 1", "expected a header of distinct, non-empty column names")
    for i, row in enumerate(body):
        if len(row) != len(header):
            raise _input_error(path, f"line {i + 2}", f"{len(row)} values for {len(header)} columns")
    columns = [_column(name, [row[k] for row in body]) for k, name in enumerate(header)]
    dtype = [(name, c.dtype if c.dtype.kind != "U" else f"U{max(1, c.dtype.itemsize // 4)}")
             for name, c in zip(header, columns)]
    out = np.empty(len(body), dtype=dtype)
    for name, c in zip(header, columns):
        out[name] = c
    return out


def _flatten(d, prefix=""):
    flat = {}
    for k, v in d.items():
        if isinstance(v, dict):
            flat.update(_flatten(v, f"{prefix}{k}_"))
        else:
            flat[f"{prefix}{k}"] = v
    return flat


def _records(items):
    """A list of flat dicts (nested dicts joined by "_") as a structured array."""
    flats = [_flatten(i) for i in items]
    names = []
    for f in flats:
        names += [n for n in f if n not in names]
    dtype = []
    for n in names:
        values = [f.get(n) for f in flats]
        numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)
        if all(isinstance(v, str) for v in values):
            dtype.append((n, f"U{max(1, max(len(v) for v in values))}"))
        elif numbers:
            dtype.append((n, np.int64 if all(isinstance(v, int) for v in values) else np.float64))
        else:
            dtype.append((n, object))
    out = np.empty(len(flats), dtype=dtype)
    for i, f in enumerate(flats):
        for n in names:
            out[i][n] = f.get(n)
    return out


@dataclasses.dataclass(frozen=True)
class Fiber:
    """One fiber's nodes at the run's final state: positions (n × 3) [m] and the section
    vectors g1, g2 (n × 3; unit length in the reference state, their stretches and angle are
    the section's deformation)."""

    name: str
    positions: np.ndarray
    g1: np.ndarray
    g2: np.ndarray


class Result:
    """The outputs of a run, read from its directory (docs/outputs.md).

    Result(out) reads the directory of any run (`fibra run` or fibra.run), finished or not;
    fibra.run returns one with `report`, the run's own account (status, counts, files).
    Everything is read when first asked for.
    """

    def __init__(self, out, report=None):
        self.out = pathlib.Path(out)
        if not self.out.is_dir():
            raise _input_error(str(self.out), "(directory)",
                               "no such directory: expected the output directory of a run")
        if not (self.out / "case.toml").is_file():
            raise _input_error(str(self.out / "case.toml"), "(file)",
                               "not found: expected the output directory of a run (it writes case.toml)")
        self.report = report
        self._cache = {}

    def _cached(self, key, make):
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    # -- the run -------------------------------------------------------------------------------
    @property
    def summary(self):
        """summary.json as a dict (an empty dict when the run was killed before writing it)."""
        def read():
            path = self.out / "summary.json"
            if not path.is_file():
                return {}
            with open(path) as f:
                return json.load(f)
        return self._cached("summary", read)

    @property
    def status(self):
        """"converged", "failed", "interrupted", "running" (killed while running) or
        "unknown" (no summary.json)."""
        if self.report is not None:
            return self.report["status"]
        return self.summary.get("status", "unknown")

    @property
    def converged(self):
        return self.status == "converged"

    @property
    def message(self):
        """Why the run stopped (empty when it converged)."""
        if self.report is not None:
            return self.report["message"]
        return self.summary.get("message", "")

    @property
    def case(self):
        """The case as run (case.toml: a [fabric] expanded), a fibra.Case."""
        from ._case import Case
        return self._cached("case", lambda: Case.load(self.out / "case.toml"))

    # -- tables ------------------------------------------------------------------------------
    @property
    def history(self):
        """history.csv: one row per converged increment (step, load factor, iterations,
        residual, reactions, body states, fabric columns)."""
        return self._cached("history", lambda: read_csv(self.out / "history.csv"))

    @property
    def curves(self):
        """The loading curves of the biaxial and shear steps: {step name: array of
        curves_STEP.csv} (warp_strain, weft_strain, warp_force, weft_force, shear_angle_deg,
        shear_force, ...)."""
        def read():
            listed = self.summary.get("curves")
            if listed is not None:
                return {c["step"]: read_csv(self.out / c["file"]) for c in listed
                        if (self.out / c["file"]).is_file()}
            return {p.stem[len("curves_"):]: read_csv(p) for p in sorted(self.out.glob("curves_*.csv"))}
        return self._cached("curves", read)

    @property
    def fabric(self):
        """The fabric report at the end of the last completed step (a woven case; None
        otherwise): crimp, thickness, penetration, and "tows", one row per tow with its
        crimp, amplitude, angle and its sections (mid_section_width, crossing_section_area,
        ...)."""
        def read():
            f = self.summary.get("fabric")
            if f is None:
                return None
            f = dict(f)
            f["tows"] = _records(f.get("tows", []))
            return f
        return self._cached("fabric", read)

    @property
    def fabric_steps(self):
        """The fabric report's main figures at the end of each step: {step name: dict}."""
        return {s["step"]: s for s in self.summary.get("fabric_steps", [])}

    @property
    def nodes(self):
        """nodes.csv: every node of the final state (fiber, node, x, y, z, g1x ... g2z)."""
        return self._cached("nodes", lambda: read_csv(self.out / "nodes.csv"))

    @property
    def fibers(self):
        """{fiber name: Fiber} at the final state, in the case's order. A run killed before it
        wrote nodes.csv gives the last state lines.pvd saved."""
        def read():
            if not (self.out / "nodes.csv").is_file() and (self.out / "lines.pvd").is_file():
                return self._fibers_from_lines()
            n = self.nodes
            names, first = np.unique(n["fiber"], return_index=True)
            out = {}
            for name in names[np.argsort(first)]:
                rows = n[n["fiber"] == name]
                rows = rows[np.argsort(rows["node"])]
                xyz = lambda a, b, c: np.column_stack([rows[a], rows[b], rows[c]])  # noqa: E731
                out[str(name)] = Fiber(str(name), xyz("x", "y", "z"), xyz("g1x", "g1y", "g1z"),
                                       xyz("g2x", "g2y", "g2z"))
            return out
        return self._cached("fibers", read)

    def _saved(self, collection, index):
        """The mesh of increment `index` of a ParaView collection (fibers.pvd, lines.pvd, ...)."""
        import meshio  # python3-meshio
        path = self.out / collection
        files = [d.get("file") for d in ElementTree.parse(path).getroot().iter("DataSet")]
        if not files:
            raise _input_error(str(path), "(file)", "lists no increment")
        return meshio.read(self.out / files[index])

    def _fibers_from_lines(self):
        """The fibers of the last increment lines.pvd lists (centroid lines with g1, g2)."""
        mesh = self._saved("lines.pvd", -1)
        names = self.case._handle.fibers
        fiber, node = mesh.point_data["fiber"].ravel(), mesh.point_data["node"].ravel()
        out = {}
        for k, name in enumerate(names):
            rows = np.flatnonzero(fiber == k)
            rows = rows[np.argsort(node[rows])]
            out[name] = Fiber(name, mesh.points[rows], mesh.point_data["g1"][rows], mesh.point_data["g2"][rows])
        return out

    def contacts(self, index=-1):
        """The contact elements of a saved increment of contacts.pvd (default the last), one
        row each: position x, y, z, gap, normal_force, friction (3), normal (3), slip (1 when
        sliding), zone. An empty array for a run without contact."""
        collection = self.out / "contacts.pvd"
        if not collection.is_file():
            return np.empty(0, dtype=[("x", float), ("y", float), ("z", float), ("gap", float),
                                      ("normal_force", float), ("friction", float, 3), ("normal", float, 3),
                                      ("slip", np.int32), ("zone", np.int32)])
        mesh = self._saved("contacts.pvd", index)
        data = mesh.point_data
        fields = [("x", float), ("y", float), ("z", float)]
        for name, values in data.items():
            shape = values.shape[1:] if values.ndim > 1 and values.shape[1] > 1 else ()
            fields.append((name, values.dtype, shape) if shape else (name, values.dtype))
        out = np.empty(len(mesh.points), dtype=fields)
        out["x"], out["y"], out["z"] = mesh.points[:, 0], mesh.points[:, 1], mesh.points[:, 2]
        for name, values in data.items():
            out[name] = values.reshape(len(mesh.points), -1).squeeze(axis=1) if values.ndim > 1 and \
                values.shape[1] == 1 else values
        return out

    # -- pictures and exports --------------------------------------------------------------------
    def slice(self, plane=None, *, tow=None, stations=None, out=""):
        """Draws slices of the final state (SVG and PNG) and returns their paths: plane="x=0"
        (or a list of planes, metres), or the slices of one tow at `stations` successive
        stations (tow="warp0", stations=6), as `fibra slice` does. out: the file stem
        (default OUT/slices/...)."""
        planes = [] if plane is None else [plane] if isinstance(plane, str) else list(plane)
        r = _fibra.slice(str(self.out), planes, tow, None if stations is None else str(stations), os.fspath(out))
        return r["files"]

    def plot(self, out=""):
        """Draws the loading curves of its biaxial and shear steps again (PNG, SVG, JSON;
        default OUT/plots) and returns the files."""
        return plot([self], out)

    def export(self, out, *, voxels=None, voxel_size=None, box=None, samples=None):
        """Exports the final state for composite models, as `fibra export` does (docs/export.md):
        tow envelopes (STL, VTP), a voxel model (VTI) and an Abaqus input (INP) in `out`.
        voxels: (NX, NY, NZ); voxel_size: an edge [m] (instead of voxels);
        box: (xmin, ymin, zmin, xmax, ymax, zmax) [m]; samples: K^3 points per voxel.
        Returns a dict: files, notes, tows, voxels, voxel_size, fiber_volume_fraction."""
        def words(v):
            if v is None:
                return []
            return [repr(float(x)) if isinstance(x, float) else str(x)
                    for x in (v if isinstance(v, (list, tuple, np.ndarray)) else [v])]
        return _fibra.export_result(str(self.out), os.fspath(out), words(voxels), words(voxel_size), words(box),
                                    words(samples))

    def __repr__(self):
        return f"<fibra.Result {str(self.out)!r}: {self.status}>"


def load_result(out):
    """The outputs of the run in directory `out`: a Result."""
    return Result(out)


def plot(results, out=""):
    """Draws the loading curves of several runs overlaid, one figure per step name they share
    (PNG, SVG, JSON), as `fibra plot` does; `results` are Results or directories, `out` the
    figures' directory (required for several runs). Returns the files written."""
    if isinstance(results, (str, os.PathLike, Result)):
        results = [results]
    dirs = [str(r.out) if isinstance(r, Result) else os.fspath(r) for r in results]
    return _fibra.plot(dirs, os.fspath(out))["files"]
