"""Results read back as numpy arrays; slices, plots and exports called from Python."""

import json
import pathlib

import numpy as np
import pytest

import fibra


def test_status_summary_and_case(woven):
    assert woven.converged
    again = fibra.load_result(woven.out)
    assert again.status == "converged" and again.report is None
    assert again.summary["counts"]["fibers"] == 12
    assert [s["name"] for s in again.case.steps] == ["weave", "relax", "pull"]
    assert "woven" in repr(again) or "converged" in repr(again)


def test_curves_are_the_csv_with_named_fields(woven):
    pull = woven.curves["pull"]
    lines = (woven.out / "curves_pull.csv").read_text().splitlines()
    header = lines[0].split(",")
    assert list(pull.dtype.names) == header
    assert len(pull) == len(lines) - 1
    assert pull["warp_strain"][-1] == pytest.approx(0.01, rel=1e-9)
    # Equibiaxial: the edges' forces grow with the strain, warp and weft alike.
    assert np.all(np.diff(pull["warp_force"]) > 0)
    assert pull["warp_force"][-1] == pytest.approx(pull["weft_force"][-1], rel=0.05)
    for k, line in enumerate(lines[1:]):
        assert pull["warp_force"][k] == float(line.split(",")[header.index("warp_force")])


def test_history_keeps_text_integer_and_float_columns(woven):
    h = woven.history
    assert h.dtype["step"].kind == "U" and h.dtype["increment"].kind == "i" and h.dtype["residual"].kind == "f"
    assert h["step"][0] == "initial" and h["step"][-1] == "pull"
    assert len(h) == 1 + woven.report["stats"]["increments"]


def test_fibers_hold_positions_and_section_vectors(woven):
    fibers = woven.fibers
    assert len(fibers) == 12
    assert list(fibers)[0] == "warp0.f0"
    f = fibers["warp0.f0"]
    assert f.positions.shape == f.g1.shape == f.g2.shape == (33, 3)
    # A warp fiber runs along x; its section vectors, of unit length in the reference state,
    # stretch little and stay across the fiber.
    assert np.all(np.diff(f.positions[:, 0]) > 0)
    assert np.linalg.norm(f.g1, axis=1) == pytest.approx(np.ones(33), abs=0.05)
    assert np.linalg.norm(f.g2, axis=1) == pytest.approx(np.ones(33), abs=0.05)
    tangent = np.gradient(f.positions, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1)[:, None]
    assert np.max(np.abs(np.sum(tangent * f.g1, axis=1))) < 0.05
    nodes = woven.nodes
    assert len(nodes) == 396 and nodes.dtype.names[:3] == ("fiber", "node", "x")


def test_fabric_report_per_tow(woven):
    fabric = woven.fabric
    tows = fabric["tows"]
    assert list(tows["name"]) == ["warp0", "warp1", "weft0", "weft1"]
    assert set(tows["direction"]) == {"warp", "weft"}
    assert np.all(tows["crimp"] > 0) and np.all(tows["crimp"] < 0.05)
    assert np.all(tows["mid_section_fibers"] == 3)
    assert fabric["thickness"] > 0
    summary = json.loads((woven.out / "summary.json").read_text())
    assert tows["crimp"][0] == summary["fabric"]["tows"][0]["crimp"]
    assert woven.fabric_steps["relax"]["warp_crimp"] > 0


def test_contact_elements_of_the_last_saved_increment(woven):
    c = woven.contacts()
    assert len(c) > 0
    assert set(("x", "gap", "normal_force", "friction", "normal", "slip", "zone")) <= set(c.dtype.names)
    assert c["normal"].shape == (len(c), 3)
    assert np.allclose(np.linalg.norm(c["normal"], axis=1), 1, atol=1e-9)
    # The fabric is held together by pressure: its normal forces are positive and balance
    # nothing else than the fibers (no net force on the assembly from the contacts).
    assert np.all(c["normal_force"] >= 0) and np.sum(c["normal_force"]) > 0
    first = woven.contacts(0)
    assert len(first) > 0


def test_slices_plots_and_export_from_python(woven, tmp_path):
    files = woven.slice("x=0", out=tmp_path / "cut")
    assert [pathlib.Path(f).name for f in files] == ["cut.svg", "cut.png"]
    assert all(pathlib.Path(f).stat().st_size > 0 for f in files)
    tow = woven.slice(tow="warp0", stations=3, out=tmp_path / "tow")
    assert len(tow) == 6
    with pytest.raises(fibra.InputError, match="--tow"):
        woven.slice(tow="nowhere", stations=3)
    with pytest.raises(fibra.InputError, match="--plane"):
        woven.slice("x=1")  # beyond the sample
    plots = fibra.plot([woven], out=tmp_path / "plots")
    assert any(p.endswith("pull.png") for p in plots)
    exported = woven.export(tmp_path / "export", voxels=(8, 8, 4))
    assert exported["voxels"] == [8, 8, 4] and exported["tows"] == 4
    assert 0 < exported["fiber_volume_fraction"] < 1
    assert (tmp_path / "export" / exported["files"][0]).is_file()
    with pytest.raises(fibra.InputError, match="--voxels"):
        woven.export(tmp_path / "export2", voxels=(0, 8, 4))


def test_a_directory_that_is_not_a_result(tmp_path):
    with pytest.raises(fibra.InputError, match="no such directory"):
        fibra.load_result(tmp_path / "nothing")
    with pytest.raises(fibra.InputError) as e:
        fibra.load_result(tmp_path)
    assert e.value.key == "(file)" and e.value.file.endswith("case.toml")


def test_a_killed_run_still_gives_its_fibers_and_a_cut_line_is_left_out(woven, tmp_path):
    import shutil
    killed = tmp_path / "killed"
    shutil.copytree(woven.out, killed)
    (killed / "nodes.csv").unlink()
    history = (killed / "history.csv").read_text()
    (killed / "history.csv").write_text(history[: history.rstrip("\n").rfind("\n") + 1] + "pull,2,3,0.5")
    r = fibra.load_result(killed)
    assert len(r.history) == len(woven.history) - 1
    fibers = r.fibers
    assert list(fibers) == list(woven.fibers)
    # lines.pvd's last saved increment is the final state nodes.csv held.
    np.testing.assert_allclose(fibers["weft1.f2"].positions, woven.fibers["weft1.f2"].positions, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fibers["weft1.f2"].g2, woven.fibers["weft1.f2"].g2, rtol=0, atol=1e-12)


def test_csv_columns_and_bad_files(tmp_path):
    from fibra._result import read_csv
    p = tmp_path / "t.csv"
    p.write_text("step,increment,x,name\nload,1,2,a\nload,2,,b\n")
    t = read_csv(p)
    assert t.dtype["increment"].kind == "i" and t.dtype["x"].kind == "f" and t.dtype["name"].kind == "U"
    assert t["x"][0] == 2.0 and np.isnan(t["x"][1])
    p.write_text("a,a\n1,2\n")
    with pytest.raises(fibra.InputError, match="distinct"):
        read_csv(p)
    p.write_text("a,b\n1\n")
    with pytest.raises(fibra.InputError, match="line 2"):
        read_csv(p)
