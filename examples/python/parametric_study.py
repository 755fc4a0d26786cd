#!/usr/bin/env python3
"""Biaxial stiffness and crimp of four woven fabrics against their tow spacing.

Four weaves of the same glass tows (3 fibers of radius 50 µm each), each at four tow
spacings, are woven by simulation, relaxed and pulled 1 % in equibiaxial tension. For each
fabric the study takes from its results

  * the crimp of its warp tows after relaxing (path length over straight length, minus one),
  * its equibiaxial membrane stiffness along the warp: the warp edge's force at 1 % strain
    over the strain and the width of the sample [N/m],

writes them to study.csv and draws them against the spacing in study.png.

    python3 examples/python/parametric_study.py [--out DIR] [--threads N]

The cases are built as Python dicts with the keys of a case file (docs/case-file.md).
"""

import argparse
import csv
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import fibra  # noqa: E402

# The fabrics: a weave and the number of tows of each direction (its repeat, at least 2).
FABRICS = [("plain", 2), ("twill 2/1", 3), ("basket 2", 4), ("twill 2/2", 4)]
SPACINGS = [0.9e-3, 1.0e-3, 1.1e-3, 1.2e-3]  # tow spacing [m]; the tows are 0.7 mm wide
STRAIN = 0.01


def fabric_case(pattern, tows, spacing):
    """A woven sample: weave, relax, then equibiaxial tension to STRAIN in 4 load levels."""
    return {
        "title": f"{pattern}, spacing {spacing * 1e3:.2f} mm",
        "material": [{"name": "glass", "young": 72e9, "poisson": 0.22}],
        "fabric": {
            "pattern": pattern,
            "warp": {"tows": tows, "spacing": spacing},
            "weft": {"tows": tows, "spacing": spacing},
            "margin": 0.5e-3,
            "tension": 0.05,
            "tow": {"fibers": 3, "width": 0.7e-3, "thickness": 0.25e-3},
            "fiber": {"radius": 5.0e-5, "material": "glass", "element_length": 2.5e-4},
        },
        "contact": {"friction": 0.2, "elastic_slip": 5e-7},
        "step": [
            {"name": "weave", "kind": "weave", "increments": 10},
            {"name": "relax", "kind": "relax", "increments": 10},
            {"name": "pull", "kind": "biaxial", "strain": STRAIN, "ratio": 1, "increments": 4},
        ],
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/parametric_study", help="directory of the runs, table and figure")
    parser.add_argument("--threads", type=int, default=0, help="threads per run (0: all cores)")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    rows = []
    for pattern, tows in FABRICS:
        for spacing in SPACINGS:
            name = f"{pattern.replace(' ', '').replace('/', '')}_{spacing * 1e6:.0f}um"
            case = fibra.Case(fabric_case(pattern, tows, spacing), name=name)
            result = fibra.run(case, out=out / name, threads=args.threads)
            if not result.converged:
                sys.exit(f"{name}: {result.status}: {result.message}")
            pull = result.curves["pull"]
            width = tows * spacing  # the warp edge spans the warp tows
            stiffness = pull["warp_force"][-1] / (pull["warp_strain"][-1] * width)
            crimp = result.fabric_steps["relax"]["warp_crimp"]
            rows.append({"pattern": pattern, "spacing_mm": spacing * 1e3, "warp_crimp": crimp,
                         "stiffness_N_per_m": stiffness, "wall_time_s": result.report["wall_time"]})
            print(f"{pattern:10s} spacing {spacing * 1e3:.2f} mm: warp crimp {100 * crimp:.3f} %, "
                  f"stiffness {stiffness:.4g} N/m ({result.report['wall_time']:.1f} s)", flush=True)

    with open(out / "study.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)

    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4), constrained_layout=True)
    for pattern, _ in FABRICS:
        mine = [r for r in rows if r["pattern"] == pattern]
        spacing = [r["spacing_mm"] for r in mine]
        left.plot(spacing, [100 * r["warp_crimp"] for r in mine], "o-", label=pattern)
        right.plot(spacing, [r["stiffness_N_per_m"] / 1e3 for r in mine], "o-", label=pattern)
    left.set(xlabel="tow spacing [mm]", ylabel="warp crimp after relaxing [%]", title="Crimp")
    right.set(xlabel="tow spacing [mm]", ylabel="equibiaxial stiffness along the warp [kN/m]",
              title=f"Stiffness at {100 * STRAIN:g} % equibiaxial strain")
    for axes in (left, right):
        axes.grid(alpha=0.3)
        axes.legend()
    figure.savefig(out / "study.png", dpi=120)
    print(f"table {out / 'study.csv'}, figure {out / 'study.png'}")


if __name__ == "__main__":
    main()
