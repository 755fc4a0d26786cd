#!/usr/bin/env python3
"""Runs docs/tutorial.md as a reader would, and fails when it no longer works.

Every ```toml or ```python block whose first line is `# file: NAME` is written to NAME in
a scratch directory; every ```console block is a list of commands (`$ COMMAND`) each followed by the
output the tutorial shows. Each command runs in the scratch directory with this build's
`fibra` first on PATH and its Python module first on the Python path; it must exit with 0 (or with the code a `# exit N` comment after it
says), and every line the tutorial shows must appear in its output, in order, with numbers
compared loosely (times and counts change from machine to machine: every number matches any
number). A shown line `...` stands for lines left out.

    run_tutorial.py TUTORIAL.md BUILD_DIR
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

NUMBER = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


def loose(line):
    """The line with every number replaced by #, whitespace runs by one space."""
    return " ".join(NUMBER.sub("#", line).split())


def blocks(text):
    """(kind, lines) of every fenced block."""
    out, kind, lines = [], None, []
    for line in text.splitlines():
        if kind is None:
            m = re.match(r"^```(\w+)\s*$", line)
            if m:
                kind, lines = m.group(1), []
        elif line.startswith("```"):
            out.append((kind, lines))
            kind = None
        else:
            lines.append(line)
    return out


def commands(lines):
    """(command, expected exit code, shown output lines) of a console block."""
    out = []
    for line in lines:
        if line.startswith("$ "):
            command, code = line[2:], 0
            m = re.search(r"\s+# exit (\d+)$", command)
            if m:
                command, code = command[: m.start()], int(m.group(1))
            out.append([command, code, []])
        elif out:
            out[-1][2].append(line)
    return out


def main():
    tutorial, build = sys.argv[1], os.path.abspath(sys.argv[2])
    with open(tutorial, encoding="utf-8") as f:
        text = f.read()
    work = tempfile.mkdtemp(prefix="fibra_tutorial_")
    env = dict(os.environ, PATH=build + os.pathsep + os.environ.get("PATH", ""),
               PYTHONPATH=os.path.join(build, "python"))
    failures, ran = 0, 0
    for kind, lines in blocks(text):
        if kind in ("toml", "python") and lines and lines[0].startswith("# file: "):
            with open(os.path.join(work, lines[0][len("# file: "):].strip()), "w", encoding="utf-8") as f:
                f.write("\n".join(lines[1:]) + "\n")
        if kind != "console":
            continue
        for command, code, shown in commands(lines):
            ran += 1
            r = subprocess.run(command, shell=True, cwd=work, env=env, capture_output=True, text=True, timeout=600)
            output = [loose(l) for l in (r.stdout + r.stderr).splitlines()]
            problems = []
            if r.returncode != code:
                problems.append(f"exit code {r.returncode}, the tutorial says {code}")
            at = 0
            for want in shown:
                if want.strip() == "...":
                    continue
                w = loose(want)
                while at < len(output) and output[at] != w:
                    at += 1
                if at == len(output):
                    problems.append(f"shown line not in the output (in order): {want!r}")
                    break
                at += 1
            if problems:
                failures += 1
                print(f"FAILED: $ {command}")
                for p in problems:
                    print("  " + p)
                print("  output:\n    " + "\n    ".join((r.stdout + r.stderr).splitlines()))
            else:
                print(f"ok: $ {command}")
    if ran == 0:
        print("no command found in " + tutorial)
        failures += 1
    if failures == 0:
        shutil.rmtree(work, ignore_errors=True)
    else:
        print("scratch directory kept: " + work)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
