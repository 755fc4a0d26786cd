"""Checks what examples/python/parametric_study.py left in its directory (argument 1): a row
per fabric and spacing, each run converged, and the trends the weaves must show: the warp
crimp and the stiffness per unit width fall as the tows are spaced further apart."""

import csv
import pathlib
import sys

out = pathlib.Path(sys.argv[1])
with open(out / "study.csv", newline="") as f:
    rows = list(csv.DictReader(f))
patterns = sorted({r["pattern"] for r in rows})
assert len(patterns) >= 4, patterns
for pattern in patterns:
    mine = sorted((r for r in rows if r["pattern"] == pattern), key=lambda r: float(r["spacing_mm"]))
    assert len(mine) >= 4, (pattern, len(mine))
    crimp = [float(r["warp_crimp"]) for r in mine]
    stiffness = [float(r["stiffness_N_per_m"]) for r in mine]
    assert all(0 < c < 0.05 for c in crimp), (pattern, crimp)
    assert all(a > b for a, b in zip(crimp, crimp[1:])), (pattern, "crimp", crimp)
    assert all(a > b for a, b in zip(stiffness, stiffness[1:])), (pattern, "stiffness", stiffness)
png = (out / "study.png").read_bytes()
assert png.startswith(b"\x89PNG") and len(png) > 10000
print(f"{len(rows)} fabrics: crimp and stiffness fall with the spacing for {', '.join(patterns)}")
