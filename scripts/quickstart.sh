#!/usr/bin/env bash
# One command: install what is missing, build in Release, run the default example.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/deps.sh"
bash "$root/scripts/build.sh"
cd "$root"
"${FIBRA_BUILD_DIR:-$root/build}/fibra" run examples/woven_sample/woven_sample.toml --out out/woven_sample
