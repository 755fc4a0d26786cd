#!/usr/bin/env python3
"""Compares Google Benchmark JSON results with bench/baseline.json.

usage: compare.py BASELINE RESULT.json [RESULT.json ...] [--threshold 0.30] [--allow-missing]
                  [--regressed-out FILE]
       compare.py BASELINE RESULT.json [...] --write-baseline   (rewrite BASELINE from results)

The baseline holds, per benchmark name, either "items_per_second" (throughput benchmarks:
higher is better) or "real_time" with its "time_unit" (lower is better). A benchmark is a
regression when it is more than THRESHOLD slower than its baseline:
    slowdown = current_time / baseline_time = baseline_rate / current_rate > 1 + THRESHOLD.
When a benchmark appears in several result files (a re-run), the best figure counts.
--regressed-out writes "<result file stem>\t<benchmark name>" for each regressed or errored
benchmark, so the caller can re-run just those once to rule out a noisy machine.
The "real/cpu" column is wall time over the main thread's CPU time: about 1 on an idle machine
(the main thread works throughout, also in the OpenMP benchmarks); clearly above 1 means the
benchmark was preempted by other processes and its figure is not trustworthy.
Exit status: 0 all within the threshold, 1 any regression, error or missing benchmark, 2 usage.
"""
import argparse
import json
import os
import platform
import subprocess
import sys
from datetime import date

UNIT_SECONDS = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def seconds(entry):
    return entry["real_time"] * UNIT_SECONDS[entry.get("time_unit", "ns")]


def better(a, b):
    """True if result a is better (faster) than b; errored results are worst."""
    if a.get("error_occurred") or b.get("error_occurred"):
        return not a.get("error_occurred") and bool(b.get("error_occurred"))
    if "items_per_second" in a and "items_per_second" in b:
        return a["items_per_second"] > b["items_per_second"]
    return seconds(a) < seconds(b)


def load_results(paths):
    """Benchmark name -> (result entry, file stem); iterations only, best entry per name."""
    results = {}
    for path in paths:
        with open(path) as f:
            data = json.load(f)
        stem = os.path.basename(path).split(".")[0]
        for b in data.get("benchmarks", []):
            if b.get("run_type", "iteration") != "iteration":
                continue
            old = results.get(b["name"])
            if old is None or better(b, old[0]):
                results[b["name"]] = (b, stem)
    return results


BUSY_RATIO = 1.2  # real/cpu above this: the benchmark was preempted


def busy_ratio(entry):
    """Wall time over main-thread CPU time of a result (None if unknown)."""
    if entry.get("error_occurred") or not entry.get("cpu_time"):
        return None
    return entry["real_time"] / entry["cpu_time"]


def metric_of(entry):
    """The metric a new baseline entry should use for a result."""
    if "items_per_second" in entry:
        return {"items_per_second": entry["items_per_second"]}
    return {"real_time": entry["real_time"], "time_unit": entry.get("time_unit", "ns")}


def fmt_time(seconds):
    for unit, scale in (("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("ns", 1e-9)):
        if seconds >= scale:
            return f"{seconds / scale:.3g} {unit}"
    return f"{seconds / 1e-9:.3g} ns"


def fmt_rate(rate):
    for suffix, scale in (("G/s", 1e9), ("M/s", 1e6), ("k/s", 1e3)):
        if rate >= scale:
            return f"{rate / scale:.3g} {suffix}"
    return f"{rate:.3g} /s"


def machine():
    model = platform.processor() or platform.machine()
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=False).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                model = line.split(":", 1)[1].strip()
    except OSError:
        pass
    return model


def write_baseline(path, results):
    baseline = {
        "_comment": "Reference figures for bench/compare.py (scripts/bench.sh). Regenerate with "
                    "scripts/bench.sh --update-baseline on the reference machine.",
        "_machine": machine(),
        "_date": date.today().isoformat(),
        "benchmarks": {name: metric_of(entry) for name, (entry, _) in sorted(results.items())
                       if not entry.get("error_occurred")},
    }
    with open(path, "w") as f:
        json.dump(baseline, f, indent=2)
        f.write("\n")
    print(f"wrote {len(baseline['benchmarks'])} baseline entries to {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("baseline")
    ap.add_argument("results", nargs="+")
    ap.add_argument("--threshold", type=float, default=0.30, help="allowed slowdown (default 0.30 = 30%%)")
    ap.add_argument("--allow-missing", action="store_true", help="do not fail on baseline entries without a result")
    ap.add_argument("--write-baseline", action="store_true", help="rewrite BASELINE from the results and exit")
    ap.add_argument("--regressed-out", metavar="FILE", help="write the regressed or errored benchmarks to FILE")
    args = ap.parse_args()

    results = load_results(args.results)
    if args.write_baseline:
        write_baseline(args.baseline, results)
        return 0
    with open(args.baseline) as f:
        baseline = json.load(f)["benchmarks"]

    rows = []  # name, baseline text, current text, slowdown, status, real/cpu
    failed = False
    regressed_names = []
    for name, ref in baseline.items():
        cur, stem = results.get(name, (None, None))
        if cur is None:
            status = "missing" if not args.allow_missing else "skipped"
            failed |= not args.allow_missing
            rows.append((name, "", "", None, status, None))
            continue
        if cur.get("error_occurred"):
            rows.append((name, "", cur.get("error_message", "error"), None, "ERROR", None))
            failed = True
            regressed_names.append((stem, name))
            continue
        if "items_per_second" in ref:
            if "items_per_second" not in cur:
                rows.append((name, "", "no items_per_second", None, "ERROR", None))
                failed = True
                continue
            slowdown = ref["items_per_second"] / cur["items_per_second"]
            ref_text, cur_text = fmt_rate(ref["items_per_second"]), fmt_rate(cur["items_per_second"])
        else:
            ref_s = seconds(ref)
            cur_s = seconds(cur)
            slowdown = cur_s / ref_s
            ref_text, cur_text = fmt_time(ref_s), fmt_time(cur_s)
        regressed = slowdown > 1.0 + args.threshold
        failed |= regressed
        if regressed:
            regressed_names.append((stem, name))
        status = "SLOWER" if regressed else ("faster" if slowdown < 1.0 / (1.0 + args.threshold) else "ok")
        rows.append((name, ref_text, cur_text, slowdown, status, busy_ratio(cur)))
    for name in sorted(set(results) - set(baseline)):
        cur = results[name][0]
        if cur.get("error_occurred"):
            text = cur.get("error_message", "error")
        else:
            text = fmt_rate(cur["items_per_second"]) if "items_per_second" in cur else fmt_time(seconds(cur))
        rows.append((name, "", text, None, "new", busy_ratio(cur)))
    if args.regressed_out:
        with open(args.regressed_out, "w") as f:
            for stem, name in regressed_names:
                f.write(f"{stem}\t{name}\n")

    width = max([len(r[0]) for r in rows] + [9])
    header = f"{'benchmark':<{width}}  {'baseline':>12}  {'current':>12}  {'slowdown':>8}  {'real/cpu':>8}  status"
    print(header)
    print("-" * len(header))
    busy = 0
    for name, ref_text, cur_text, slowdown, status, ratio in rows:
        sd = f"{slowdown:.2f}x" if slowdown is not None else ""
        rc = f"{ratio:.2f}" if ratio is not None else ""
        if status == "SLOWER" and ratio is not None and ratio > BUSY_RATIO:
            busy += 1
        print(f"{name:<{width}}  {ref_text:>12}  {cur_text:>12}  {sd:>8}  {rc:>8}  {status}")
    print()
    if busy:
        print(f"note: {busy} of the slower benchmarks ran with real/cpu > {BUSY_RATIO}: other processes "
              "took the cores; re-run on an idle machine before trusting them")
    limit = f"{args.threshold * 100:.0f}%"
    if failed:
        print(f"FAIL: regression beyond {limit}, error or missing benchmark (see status column)")
        return 1
    print(f"OK: every benchmark within {limit} of its baseline")
    return 0


if __name__ == "__main__":
    sys.exit(main())
