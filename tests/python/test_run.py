"""fibra.run: a run as `fibra run` makes it, its progress, its stops and its resumption."""

import os
import pathlib
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import fibra
from conftest import EXAMPLES

CANTILEVER = EXAMPLES / "cantilever" / "cantilever.toml"


def test_the_cantilever_matches_the_elastica(tmp_path):
    seen = []
    result = fibra.run(CANTILEVER, out=tmp_path / "c", threads=1, progress=seen.append)
    assert result.converged and result.status == "converged" and result.message == ""
    assert result.report["stats"]["increments"] == len(seen) >= 10
    assert [i.total_increments for i in seen] == list(range(1, len(seen) + 1))
    assert seen[-1].load_factor == 1.0 and seen[-1].step_end and seen[-1].step == "load"
    assert all(i.residual < 1e-6 for i in seen)
    assert all(i.negative_pivots == 0 for i in seen)  # a stable equilibrium at every load
    tip = result.fibers["beam"].positions[-1]
    # Bisshopp & Drucker, P L^2 / (E I) = 2: tip deflection 0.4935 L, shortening 0.1606 L.
    assert tip[2] == pytest.approx(-0.4935, abs=2e-3)
    assert 1 - tip[0] == pytest.approx(0.1606, abs=2e-3)
    h = result.history
    assert list(h["step"][:2]) == ["initial", "load"]
    assert h["load_factor"][-1] == 1.0
    reaction = [n for n in h.dtype.names if n.startswith("reaction:beam:first:z")]
    assert reaction and h[reaction[0]][-1] == pytest.approx(3298.67, rel=1e-6)


def test_a_column_past_its_euler_load_is_reported_unstable(tmp_path):
    # Clamped-free, compressed to 2.2 times P_cr = pi^2 E I / (4 L^2) in 4 increments: past P_cr
    # the load step follows the straight equilibrium, unstable in both bending planes (below
    # the second mode's 9 P_cr: one negative pivot per plane).
    young, radius, length = 1e9, 0.01, 1.0
    critical = np.pi**2 * young * np.pi * radius**4 / 4 / (4 * length**2)
    case = tmp_path / "column.toml"
    case.write_text(textwrap.dedent(f"""
        [[material]]
        name = "m"
        young = {young}
        poisson = 0.3
        [[fiber]]
        name = "column"
        material = "m"
        radius = {radius}
        points = [[0, 0, 0], [{length}, 0, 0]]
        elements = 20
        [[fix]]
        fiber = "column"
        node = "first"
        [[step]]
        name = "compress"
        increments = 4
          [[step.load]]
          fiber = "column"
          node = "last"
          force = [{-2.2 * critical!r}, 0, 0]
        """))
    seen = []
    result = fibra.run(case, out=tmp_path / "c", threads=1, progress=seen.append)
    assert result.converged
    assert [i.negative_pivots for i in seen] == [0, 2, 2, 2]  # 0.55, 1.1, 1.65, 2.2 P_cr
    assert list(result.history["stability:negative_pivots"]) == [0, 0, 2, 2, 2]
    assert result.report["stats"]["indefinite_iterations"] > 0
    assert result.summary["unstable_equilibria"] == {
        "increments": 3, "first": {"step": "compress", "increment": 2, "load_factor": 0.5, "negative_pivots": 2}}


def test_a_case_file_and_a_run_from_python_write_the_same_outputs(tmp_path):
    cli = pathlib.Path(os.environ.get("FIBRA_BUILD_DIR", "")) / "fibra"
    if not cli.is_file():
        pytest.skip("FIBRA_BUILD_DIR does not hold the fibra program")
    subprocess.run([cli, "run", CANTILEVER, "--out", tmp_path / "cli", "--threads", "1"], check=True,
                   capture_output=True)
    fibra.run(fibra.load_case(CANTILEVER), out=tmp_path / "py", threads=1)
    for name in ("nodes.csv", "case.toml"):
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "py" / name).read_bytes(), name


def test_a_callback_stops_the_run_and_resume_finishes_it_as_if_never_stopped(tmp_path):
    whole = fibra.run(CANTILEVER, out=tmp_path / "whole", threads=1)
    stopped = fibra.run(CANTILEVER, out=tmp_path / "part", threads=1, progress=lambda i: i.total_increments < 4)
    assert stopped.status == "interrupted"
    assert len(stopped.history) == 1 + 4  # the initial row and four converged increments
    resumed = fibra.run(CANTILEVER, out=tmp_path / "part", threads=1, resume=True)
    assert resumed.converged
    assert (tmp_path / "part" / "nodes.csv").read_bytes() == (tmp_path / "whole" / "nodes.csv").read_bytes()
    np.testing.assert_array_equal(resumed.history["residual"], whole.history["residual"])


def test_an_exception_in_the_callback_stops_the_run_and_is_raised(tmp_path):
    def fail(info):
        if info.total_increments == 2:
            raise ZeroDivisionError("from the callback")

    with pytest.raises(ZeroDivisionError, match="from the callback"):
        fibra.run(CANTILEVER, out=tmp_path / "e", threads=1, progress=fail)
    kept = fibra.load_result(tmp_path / "e")
    assert kept.status == "interrupted" and len(kept.history) == 3


def test_ctrl_c_stops_at_the_last_converged_increment(tmp_path):
    """SIGINT sent to a Python process running a case: RunInterrupted with the result, its
    outputs kept, and the run resumed to its end."""
    script = tmp_path / "run.py"
    script.write_text(textwrap.dedent(f"""
        import sys, fibra
        def progress(info):
            print("increment", info.total_increments, flush=True)
        try:
            fibra.run({str(EXAMPLES / "woven_sample" / "woven_sample.toml")!r}, out={str(tmp_path / "o")!r},
                      threads=1, progress=progress)
            print("finished")
        except fibra.RunInterrupted as e:
            print("interrupted", e.result.status, len(e.result.history), flush=True)
            sys.exit(7)
        """))
    p = subprocess.Popen([sys.executable, script], stdout=subprocess.PIPE, text=True, env=os.environ)
    first = p.stdout.readline()
    assert first.startswith("increment"), first
    p.send_signal(signal.SIGINT)
    rest, _ = p.communicate(timeout=120)
    assert p.returncode == 7, rest
    last = rest.strip().splitlines()[-1].split()
    assert last[:2] == ["interrupted", "interrupted"]
    rows = int(last[2])
    assert rows >= 2
    resumed = fibra.run(EXAMPLES / "woven_sample" / "woven_sample.toml", out=tmp_path / "o", threads=1, resume=True)
    assert resumed.converged
    assert len(resumed.history) > rows


def test_a_failed_run_returns_with_its_message(tmp_path):
    data = fibra.load_case(CANTILEVER).to_dict()
    data["step"][0]["increments"] = 1
    data["step"][0]["load"][0]["force"] = [0, 0, -3.3e7]  # P L^2 / (E I) = 20000 in one increment
    data["solver"] = {"max_iterations": 3, "max_cuts": 0}
    result = fibra.run(data, out=tmp_path / "f", threads=1)
    assert result.status == "failed"
    assert result.message
    again = fibra.load_result(tmp_path / "f")
    assert again.status == "failed"
    # Columns of numbers are floats whatever their values (a failed run's may all be integers).
    for name in ("load_factor", "residual", "wall_time"):
        assert again.history.dtype[name].kind == "f", name


def test_bad_arguments(tmp_path):
    with pytest.raises(ValueError, match="threads"):
        fibra.run(CANTILEVER, out=tmp_path / "x", threads=-1)
    with pytest.raises(TypeError, match="progress"):
        fibra.run(CANTILEVER, out=tmp_path / "x", progress=3)
    with pytest.raises(fibra.InputError, match="checkpoint"):
        fibra.run(CANTILEVER, out=tmp_path / "none", resume=True)


def test_runs_from_two_threads_take_turns_and_one_stop_stops_one_run(tmp_path):
    import concurrent.futures
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        stopped = pool.submit(fibra.run, CANTILEVER, out=tmp_path / "a", threads=1,
                              progress=lambda i: i.total_increments < 2)
        whole = pool.submit(fibra.run, CANTILEVER, out=tmp_path / "b", threads=1)
        assert stopped.result().status == "interrupted"
        assert whole.result().converged
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_threads_zero_is_all_cores_after_a_run_with_one(tmp_path):
    every = fibra.run(CANTILEVER, out=tmp_path / "a", threads=0).summary["solver"]["threads"]
    assert fibra.run(CANTILEVER, out=tmp_path / "b", threads=1).summary["solver"]["threads"] == 1
    assert fibra.run(CANTILEVER, out=tmp_path / "c", threads=0).summary["solver"]["threads"] == every
    assert every == os.cpu_count() or "OMP_NUM_THREADS" in os.environ


def test_sigint_during_a_run_and_an_ignored_sigint(tmp_path):
    def ctrl_c(info):
        if info.total_increments == 2:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(fibra.RunInterrupted) as e:
        fibra.run(CANTILEVER, out=tmp_path / "i", threads=1, progress=ctrl_c)
    assert e.value.result.status == "interrupted" and len(e.value.result.history) == 3
    assert isinstance(e.value, KeyboardInterrupt)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        assert fibra.run(CANTILEVER, out=tmp_path / "j", threads=1, progress=ctrl_c).converged
        assert signal.getsignal(signal.SIGINT) == signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)


def test_resume_with_the_same_case_built_in_python(tmp_path):
    fibra.run(CANTILEVER, out=tmp_path / "r", threads=1, progress=lambda i: i.total_increments < 3)
    same = fibra.load_case(CANTILEVER).with_values({})
    assert fibra.run(same, out=tmp_path / "r", threads=1, resume=True).converged
    fibra.run(same, out=tmp_path / "s", threads=1, progress=lambda i: i.total_increments < 3)
    assert fibra.run(fibra.Case(same.to_dict()), out=tmp_path / "s", threads=1, resume=True).converged
    changed = same.with_values({"step[0].load[0].force": [0, 0, -1000.0]})
    fibra.run(same, out=tmp_path / "t", threads=1, progress=lambda i: i.total_increments < 3)
    with pytest.raises(fibra.InputError, match=r"step\[0\]\.load\[0\]\.force"):
        fibra.run(changed, out=tmp_path / "t", threads=1, resume=True)


def test_an_empty_output_directory_name_is_refused(tmp_path):
    with pytest.raises(fibra.InputError, match="out"):
        fibra.run(CANTILEVER, out="", threads=1)
    with pytest.raises(ValueError, match="threads"):
        fibra.run(CANTILEVER, out=tmp_path / "x", threads="2")
    with pytest.raises(ValueError, match="name"):
        fibra.Case(fibra.load_case(CANTILEVER).to_dict(), name="")
