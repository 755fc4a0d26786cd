"""Runs: a case solved step by step, as `fibra run` does, with its outputs in a directory."""

import dataclasses
import operator
import os
import sys

from . import _fibra
from ._case import Case
from ._result import Result


@dataclasses.dataclass(frozen=True)
class Increment:
    """A converged increment, as the progress callback receives it."""

    step: str  #: the step's name
    step_index: int  #: 0-based
    increment: int  #: converged increments so far in this step
    total_increments: int  #: converged increments since the start of the run
    load_factor: float  #: in [0, 1] within the step
    iterations: int  #: Newton iterations of this increment
    residual: float  #: final relative residual
    wall_time: float  #: since the start of the run [s]
    step_end: bool  #: the step's last increment
    settled: bool  #: an equilibrium without drag (a point of the step's curve, for tests)
    contact_elements: int  #: active contact elements
    #: load steps: negative pivots of the tangent at this equilibrium, its unstable modes
    #: (0: stable; -1: unknown; docs/outputs.md, stability:negative_pivots)
    negative_pivots: int

    def __str__(self):
        return (f'step {self.step_index + 1} "{self.step}"  load {self.load_factor:6.4f}  '
                f"iterations {self.iterations:2d}  residual {self.residual:.2e}  {self.wall_time:7.2f} s")


class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a run at its last converged increment. Its outputs are kept and
    `result` reads them; `fibra.run(case, out, resume=True)` goes on from there."""

    def __init__(self, result):
        super().__init__(f"run interrupted; outputs of every converged increment kept in {result.out}")
        self.result = result


def run(case, out=None, *, threads=0, progress=None, resume=False):
    """Runs `case` (a Case, a case file's path, or a dict of its keys) and returns its Result.

    out: the output directory (default out/<case name>); its files are those of `fibra run`
    (docs/outputs.md). threads: OpenMP threads (0: all cores). progress: True prints a line
    per converged increment on stderr; a callable is called with an Increment after each one
    (its outputs are written by then) and stops the run by returning False. resume: go on
    from the checkpoint of a run in `out` that was stopped.

    A run that does not converge returns normally: result.status is "failed" and
    result.message says where and why. A run stopped by the callback has status
    "interrupted". Ctrl-C stops the run at its last converged increment and raises
    RunInterrupted (a KeyboardInterrupt) holding the result. An exception raised by the
    callback stops the run likewise and is raised again. Bad input raises InputError.
    """
    if isinstance(case, dict):
        case = Case(case)
    elif not isinstance(case, Case):
        case = Case.load(case)
    try:
        count = operator.index(threads)
    except TypeError:
        count = -1
    if isinstance(threads, bool) or not 0 <= count <= 4096:
        raise ValueError(f"threads: expected 0 (all cores) or a count of threads, got {threads!r}")
    threads = count
    out = os.fspath(out) if out is not None else os.path.join("out", case.name)
    if not out:
        raise _fibra.InputError('fibra.run: out: expected a directory, got ""')
    callback = None
    if progress is True:
        def callback(info):
            print(str(Increment(**info)), file=sys.stderr, flush=True)
    elif callable(progress):
        def callback(info):
            return progress(Increment(**info))
    elif progress not in (None, False):
        raise TypeError("progress: expected True, False, None or a callable taking an Increment")
    report = _fibra.run(case._handle, out, int(threads), bool(resume), callback)
    result = Result(out, report=report)
    if report["interrupted_by_signal"]:
        raise RunInterrupted(result)
    return result
