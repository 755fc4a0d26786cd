"""Shared fixtures of the Python module's tests (run by ctest: tests/CMakeLists.txt sets
PYTHONPATH to the build's python/ folder and FIBRA_SOURCE_DIR to the source tree)."""

import os
import pathlib

import pytest

SOURCE = pathlib.Path(os.environ.get("FIBRA_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
EXAMPLES = SOURCE / "examples"


@pytest.fixture(scope="session")
def source_dir():
    return SOURCE


@pytest.fixture(scope="session")
def woven(tmp_path_factory):
    """The default example (a 2 x 2 plain weave woven, relaxed and pulled 1 %), run once."""
    import fibra
    out = tmp_path_factory.mktemp("woven") / "out"
    return fibra.run(EXAMPLES / "woven_sample" / "woven_sample.toml", out=out, threads=1)
