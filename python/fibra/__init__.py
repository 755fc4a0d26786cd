"""fibra: woven fabrics and fiber assemblies simulated at the scale of their fibers.

    import fibra
    case = fibra.load_case("examples/woven_sample/woven_sample.toml")
    result = fibra.run(case, out="out/woven_sample", progress=True)
    pull = result.curves["pull"]                 # a numpy array with named fields
    print(pull["warp_strain"], pull["warp_force"])

Cases come from TOML or JSON case files (`load_case`) or from Python dicts with the same keys
(`Case`), checked by the same reader with the same messages (docs/case-file.md). `run` runs a
case as `fibra run` does and returns its `Result`; `load_result` reads the output directory of
any run. docs/python.md is the reference.
"""

import os as _os
import sys as _sys

# libgomp reads its wait policy, and OpenBLAS its thread count, when they are loaded: set them
# as the `fibra` program does (apps/fibra/main.cpp, docs/performance.md) unless the user has.
if "OMP_WAIT_POLICY" not in _os.environ:
    _os.environ["OMP_WAIT_POLICY"] = "passive"
if "OPENBLAS_NUM_THREADS" not in _os.environ:
    _os.environ["OPENBLAS_NUM_THREADS"] = "1"
    _os.environ["FIBRA_ADAPTIVE_BLAS_THREADS"] = "1"

try:
    import numpy as _numpy  # noqa: F401
except ImportError:
    # fibra is built for Debian's Python 3, with Debian's numpy (python3-numpy). Another
    # interpreter of the same version first on PATH (pyenv, a venv) may lack numpy: it then
    # uses Debian's packages, after its own.
    _debian = "/usr/lib/python3/dist-packages"
    if _os.path.isdir(_debian) and _debian not in _sys.path:
        _sys.path.append(_debian)
    import numpy as _numpy  # noqa: F401

from ._fibra import InputError, RunError  # noqa: E402
from ._case import Case, case_keys, load_case  # noqa: E402
from ._result import Result, load_result, plot  # noqa: E402
from ._run import Increment, RunInterrupted, run  # noqa: E402

__all__ = [
    "Case",
    "Increment",
    "InputError",
    "Result",
    "case_keys",
    "RunError",
    "RunInterrupted",
    "load_case",
    "load_result",
    "plot",
    "run",
]
