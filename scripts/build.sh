#!/usr/bin/env bash
# Configures and builds fibra in Release into build/ (or $FIBRA_BUILD_DIR), then puts its
# Python module on the user's Python path: a fibra.pth naming <build>/python in the user's
# site-packages of Debian's python3, so that `python3 -c "import fibra"` works in any shell,
# from any directory (docs/python.md).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FIBRA_BUILD_DIR:-$root/build}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build" -j "$(nproc)"
if [ -f "$build/python/fibra/__init__.py" ]; then
  python=/usr/bin/python3
  site="$("$python" -c 'import site; print(site.getusersitepackages())')"
  mkdir -p "$site"
  echo "$build/python" > "$site/fibra.pth"
  (cd / && "$python" -c "import fibra") || { echo "fibra: the Python module does not import" >&2; exit 1; }
  echo "fibra: Python module: import fibra (from $build/python, named by $site/fibra.pth)"
fi
