"""Cases from files and from Python dicts: one reader, the same messages, TOML written back."""

import json
import tomllib

import numpy as np
import pytest

import fibra
from conftest import EXAMPLES

WOVEN = EXAMPLES / "woven_sample" / "woven_sample.toml"


def woven_dict():
    with open(WOVEN, "rb") as f:
        return tomllib.load(f)


def test_a_file_and_its_dict_make_the_same_case():
    from_file = fibra.load_case(WOVEN)
    from_dict = fibra.Case(woven_dict(), name="woven_sample")
    assert from_file.name == from_dict.name == "woven_sample"
    assert from_file.to_toml(expanded=True) == from_dict.to_toml(expanded=True)
    assert [s["name"] for s in from_dict.steps] == ["weave", "relax", "pull"]
    assert [s["kind"] for s in from_dict.steps] == ["weave", "relax", "biaxial"]
    assert from_dict.tows == ["warp0", "warp1", "weft0", "weft1"]
    counts = from_dict.check()
    assert counts["fibers"] == 12 and counts["nodes"] == 396 and counts["dofs"] == 3636


def test_a_dict_error_names_the_key_as_a_json_file_does(tmp_path):
    data = woven_dict()
    data["fabric"]["fiber"]["radius"] = -1.0
    with pytest.raises(fibra.InputError) as from_dict:
        fibra.Case(data)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(fibra.InputError) as from_file:
        fibra.load_case(path)
    assert isinstance(from_dict.value, ValueError)
    assert from_dict.value.file == "<dict>"
    assert from_dict.value.key == from_file.value.key == "fabric.fiber.radius"
    assert str(from_dict.value).removeprefix("<dict>") == str(from_file.value).removeprefix(str(path))


def test_unknown_keys_are_suggested():
    data = woven_dict()
    data["fabric"]["warp"]["spacng"] = data["fabric"]["warp"].pop("spacing")
    with pytest.raises(fibra.InputError, match=r'fabric\.warp\.spacng: unknown key "spacng" \(did you mean "spacing"\?\)'):
        fibra.Case(data)


def test_numpy_numbers_are_numbers_and_nan_is_refused():
    data = woven_dict()
    data["fabric"]["warp"]["spacing"] = np.float64(1.1e-3)
    data["fabric"]["warp"]["tows"] = np.int64(2)
    case = fibra.Case(data)
    assert "spacing = 0.0011" in case.to_toml() or "spacing = 1.1e-03" in case.to_toml()
    data["fabric"]["warp"]["spacing"] = float("nan")
    with pytest.raises(fibra.InputError, match=r"<dict>: fabric\.warp\.spacing: expected a finite number"):
        fibra.Case(data)
    data["fabric"]["warp"]["spacing"] = object()
    with pytest.raises(fibra.InputError, match=r"fabric\.warp\.spacing: expected a number"):
        fibra.Case(data)


def test_toml_written_reads_back_to_the_same_dict(tmp_path):
    case = fibra.Case(woven_dict(), name="woven_sample")
    path = case.write(tmp_path / "written.toml")
    again = fibra.load_case(path)
    assert again.to_dict() == case.to_dict() == woven_dict()
    assert again.to_toml(expanded=True) == case.to_toml(expanded=True)
    expanded = fibra.load_case(case.write(tmp_path / "expanded.toml", expanded=True))
    assert "fabric" not in expanded.to_dict()
    assert len(expanded.to_dict()["fiber"]) == 12
    assert expanded.to_toml(expanded=True) == case.to_toml(expanded=True)


def test_none_leaves_a_key_out():
    data = woven_dict()
    data["title"] = None
    assert "title" not in fibra.Case(data).to_toml()


def test_with_values_sets_keys_by_path():
    case = fibra.load_case(WOVEN)
    denser = case.with_values({"fabric.warp.spacing": 0.9e-3, "step[2].strain": 0.02}, title="denser")
    d = denser.to_dict()
    assert d["fabric"]["warp"]["spacing"] == 0.9e-3
    assert d["step"][2]["strain"] == 0.02
    assert denser.title == "denser"
    assert case.to_dict()["fabric"]["warp"]["spacing"] == 1.0e-3  # the original is unchanged
    with pytest.raises(KeyError, match=r"step\[7\]"):
        case.with_values({"step[7].strain": 0.02})
    with pytest.raises(fibra.InputError, match=r"step\[2\]\.strain"):
        case.with_values({"step[2].strain": "much"})


def test_a_missing_file_and_a_syntax_error_are_input_errors(tmp_path):
    with pytest.raises(fibra.InputError, match="no_such.toml"):
        fibra.load_case(tmp_path / "no_such.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[[material]\nname = 1\n")
    with pytest.raises(fibra.InputError) as e:
        fibra.load_case(bad)
    assert e.value.file == str(bad)
    with pytest.raises(TypeError):
        fibra.Case([1, 2])


def test_the_schema_is_the_readers():
    tables = fibra.case_keys()
    assert {"top", "material", "fiber", "fabric", "step", "solver", "contact", "output"} <= set(tables)
    fabric = {k["name"]: k for k in fibra.case_keys("fabric")}
    assert "pattern" in fabric and fabric["pattern"]["type"] == "string"
    solver = {k["name"]: k for k in fibra.case_keys("solver")}
    assert solver["max_iterations"]["default"] not in ("", "required")
    # A key the schema does not declare is refused in a case dict, as in a file.
    data = fibra.load_case(EXAMPLES / "woven_sample" / "woven_sample.toml").to_dict()
    data["contact"]["no_such_key"] = 1
    with pytest.raises(fibra.InputError, match="contact.no_such_key"):
        fibra.Case(data)
    with pytest.raises(KeyError, match="no table"):
        fibra.case_keys("nowhere")


def test_a_derived_case_goes_on_from_the_same_run(tmp_path):
    """`[start] from` relative to the case file stays the same run in a case derived from it."""
    out = tmp_path / "runs" / "first"
    fibra.run(EXAMPLES / "cantilever" / "cantilever.toml", out=out, threads=1)
    follow = tmp_path / "runs" / "follow.toml"
    follow.write_text('[start]\nfrom = "first"\nstep = "load"\n\n[[step]]\nname = "more"\nincrements = 1\n')
    case = fibra.load_case(follow)
    derived = case.with_values({"step[0].increments": 2})
    assert derived.to_dict()["start"]["from"] == str(tmp_path / "runs" / "first")
    assert derived.steps[0]["increments"] == 2


def test_upper_case_json_and_a_byte_order_mark(tmp_path):
    upper = tmp_path / "case.JSON"
    upper.write_text(json.dumps(woven_dict()))
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + WOVEN.read_bytes())
    for path in (upper, bom):
        try:
            case = fibra.load_case(path)
        except fibra.InputError as e:  # refused by the reader: then with a file and a key
            assert e.file == str(path)
            continue
        assert case.to_dict() == woven_dict()
