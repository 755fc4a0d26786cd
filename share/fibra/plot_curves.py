#!/usr/bin/python3
"""Plots of the loading curves of fibra's biaxial and shear steps (curves_STEP.csv).

fibra runs this script (`fibra run` at the end of every biaxial or shear step, `fibra plot`
for several result directories); it reads a job file that fibra writes:

    python3 plot_curves.py --job JOB.json

JOB.json: {"figures": [{"step": NAME, "kind": "biaxial" | "shear", "title": TEXT,
                        "stem": PATH, "runs": [{"label": TEXT, "csv": PATH}, ...]}, ...]}

For each figure it writes STEM.png (150 dpi), STEM.svg (text kept as text) and STEM.json, the
sidecar: the exact series drawn (label, x, y, units, source columns), so that scripts and tests
can check what a figure shows without reading pixels. Biaxial: axial force [N] against axial
strain [%], warp and weft; shear: shear force [N] against shear angle [deg]. Several runs in a
figure are overlaid, one colour per run. See docs/outputs.md, "Plots".

Exit codes: 0 done, 2 bad job or curves file, 3 matplotlib missing. Errors go to stderr, one
line each, naming the file; nothing is printed on success.
"""

import argparse
import csv
import json
import math
import os
import sys
import textwrap

# What a figure of each step kind draws: per series the curves_STEP.csv columns for x and y,
# the scale that turns the column into the plotted unit, and the direction's name.
KINDS = {
    "biaxial": {
        "x": {"quantity": "axial strain", "unit": "%"},
        "y": {"quantity": "axial force", "unit": "N"},
        "series": [
            {"name": "warp", "x_column": "warp_strain", "x_scale": 100.0, "y_column": "warp_force"},
            {"name": "weft", "x_column": "weft_strain", "x_scale": 100.0, "y_column": "weft_force"},
        ],
    },
    "shear": {
        "x": {"quantity": "shear angle", "unit": "deg"},
        "y": {"quantity": "shear force", "unit": "N"},
        "series": [
            {"name": "shear", "x_column": "shear_angle_deg", "x_scale": 1.0, "y_column": "shear_force"},
        ],
    },
}

# One run: warp blue, weft red (the slices' palette, docs/outputs.md). Several runs: one
# colour per run, the direction told by the line style and marker.
DIRECTION_COLOURS = {"warp": "#1f5fa8", "weft": "#c0392b", "shear": "#1f5fa8"}
RUN_COLOURS = ["#1f5fa8", "#c0392b", "#13807d", "#f0922b", "#4b4ba8", "#8e2452", "#5fa8dc", "#9a9a9a"]
DIRECTION_STYLES = {"warp": ("-", "o"), "weft": ("--", "s"), "shear": ("-", "o")}


class JobError(Exception):
    """A job or curves file that cannot be used; the message names the file."""


def fail(message, code):
    print("plot_curves.py: " + message, file=sys.stderr)
    sys.exit(code)


def read_curves(path, columns):
    """The named columns of a curves_STEP.csv as lists of floats (nan where empty or 'nan')."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        raise JobError(f"{path}: cannot read: {e.strerror}")
    if not rows:
        raise JobError(f"{path}: empty: expected a header line and one row per load level")
    header = rows[0]
    for c in columns:
        if c not in header:
            raise JobError(f"{path}: no column '{c}': expected the header of curves_STEP.csv "
                           f"(docs/outputs.md), got {','.join(header)}")
    out = {c: [] for c in columns}
    for line, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        if len(row) != len(header):
            raise JobError(f"{path}: line {line}: {len(row)} fields, expected {len(header)}")
        for c in columns:
            text = row[header.index(c)]
            try:
                out[c].append(float(text) if text else math.nan)
            except ValueError:
                raise JobError(f"{path}: line {line}: column '{c}': expected a number, got '{text}'")
    return out


def json_number(v):
    """A float for the sidecar; JSON has no NaN, so an undefined value is null."""
    return v if math.isfinite(v) else None


def figure_series(figure):
    """The series of one figure: per run, per direction of the step kind, the plotted values."""
    spec = KINDS[figure["kind"]]
    runs = figure["runs"]
    series = []
    for r, run in enumerate(runs):
        columns = [c for s in spec["series"] for c in (s["x_column"], s["y_column"])]
        values = read_curves(run["csv"], columns)
        for s in spec["series"]:
            # One run: the direction names the line; several: the run (and the direction).
            if len(runs) == 1:
                label = s["name"] if len(spec["series"]) > 1 else run["label"]
            else:
                label = f"{run['label']}: {s['name']}" if len(spec["series"]) > 1 else run["label"]
            series.append({
                "label": label,
                "run": run["label"],
                "direction": s["name"],
                "run_index": r,
                "source": run["csv"],
                "x_column": s["x_column"],
                "x_scale": s["x_scale"],
                "y_column": s["y_column"],
                "y_scale": 1.0,
                "x_unit": spec["x"]["unit"],
                "y_unit": spec["y"]["unit"],
                "x": [s["x_scale"] * v for v in values[s["x_column"]]],
                "y": list(values[s["y_column"]]),
            })
    return series


def draw(plt, figure, series):
    """The figure of one step, as a matplotlib Figure."""
    spec = KINDS[figure["kind"]]
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    several = len(figure["runs"]) > 1
    for s in series:
        style, marker = DIRECTION_STYLES[s["direction"]]
        colour = RUN_COLOURS[s["run_index"] % len(RUN_COLOURS)] if several else DIRECTION_COLOURS[s["direction"]]
        ax.plot(s["x"], s["y"], linestyle=style, marker=marker, markersize=4, color=colour, label=s["label"])
    ax.set_xlabel(f"{spec['x']['quantity']} [{spec['x']['unit']}]")
    ax.set_ylabel(f"{spec['y']['quantity']} [{spec['y']['unit']}]")
    # Long titles (an overlay names every run) wrap instead of running off the figure.
    ax.set_title("\n".join(textwrap.wrap(figure["title"], 80)), fontsize=11)
    ax.grid(True, color="#dddddd", linewidth=0.6)
    ax.axhline(0, color="#888888", linewidth=0.6)
    ax.legend(fontsize=9)
    fig.tight_layout()
    return fig


def save_atomic(fig, path, fmt, **kwargs):
    """Writes PATH.tmp and renames it over PATH: a reader never sees a half-written figure."""
    tmp = path + ".tmp"
    fig.savefig(tmp, format=fmt, **kwargs)
    os.replace(tmp, path)


def write_json_atomic(path, data):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, allow_nan=False)
        f.write("\n")
    os.replace(tmp, path)


def sidecar(figure, series, stem):
    """What the figure shows, exactly: the numbers drawn and where they come from."""
    spec = KINDS[figure["kind"]]
    here = os.path.dirname(os.path.abspath(stem))
    name = os.path.basename(stem)
    out = []
    for s in series:
        entry = {k: s[k] for k in ("label", "run", "direction", "x_column", "x_scale", "y_column", "y_scale",
                                   "x_unit", "y_unit")}
        # The source relative to the sidecar, so a result directory can move as a whole.
        entry["source"] = os.path.relpath(os.path.abspath(s["source"]), here)
        entry["x"] = [json_number(v) for v in s["x"]]
        entry["y"] = [json_number(v) for v in s["y"]]
        out.append(entry)
    return {
        "step": figure["step"],
        "kind": figure["kind"],
        "title": figure["title"],
        "files": [name + ".png", name + ".svg"],
        "x": spec["x"],
        "y": spec["y"],
        "series": out,
    }


def check_figure(figure, job_path, k):
    where = f"{job_path}: figures[{k}]"
    for key in ("step", "kind", "title", "stem", "runs"):
        if key not in figure:
            raise JobError(f"{where}: no '{key}'")
    if figure["kind"] not in KINDS:
        raise JobError(f"{where}: kind: expected one of {', '.join(KINDS)}, got '{figure['kind']}'")
    if not figure["runs"]:
        raise JobError(f"{where}: runs: expected at least one run")
    for r, run in enumerate(figure["runs"]):
        if "label" not in run or "csv" not in run:
            raise JobError(f"{where}: runs[{r}]: expected 'label' and 'csv'")


def main():
    parser = argparse.ArgumentParser(description="Plots of fibra's loading curves (see docs/outputs.md).")
    parser.add_argument("--job", required=True, help="job file written by fibra (JSON)")
    args = parser.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        fail(f"matplotlib is not available to {sys.executable} ({e}): install it (Debian: apt-get install "
             f"python3-matplotlib) or set FIBRA_PYTHON to a Python 3 that has it", 3)
    # Text stays text in the SVG (searchable, editable); fixed ids and no date, so that the same
    # curves give the same file.
    matplotlib.rcParams["svg.fonttype"] = "none"
    matplotlib.rcParams["svg.hashsalt"] = "fibra"
    try:
        try:
            with open(args.job) as f:
                job = json.load(f)
        except (OSError, ValueError) as e:
            raise JobError(f"{args.job}: cannot read the job: {e}")
        figures = job.get("figures", []) if isinstance(job, dict) else []
        for k, figure in enumerate(figures):
            check_figure(figure, args.job, k)
        for figure in figures:
            series = figure_series(figure)
            stem = figure["stem"]
            os.makedirs(os.path.dirname(os.path.abspath(stem)), exist_ok=True)
            fig = draw(plt, figure, series)
            save_atomic(fig, stem + ".png", "png", dpi=150)
            save_atomic(fig, stem + ".svg", "svg", metadata={"Date": None})
            plt.close(fig)
            write_json_atomic(stem + ".json", sidecar(figure, series, stem))
    except JobError as e:
        fail(str(e), 2)
    except OSError as e:
        fail(f"{e.filename or ''}: cannot write: {e.strerror}", 2)


if __name__ == "__main__":
    main()
