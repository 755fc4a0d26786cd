#!/usr/bin/env bash
# Installs the Debian 12 packages fibra needs (only those missing). Run as root.
#   bash scripts/deps.sh            build, tests, benchmarks, plots, the Python module (pybind11, numpy, tomli-w, pytest; meshio: the export's tests)
#   bash scripts/deps.sh sanitize   also Clang with its sanitizer and libFuzzer run-times, its
#                                   OpenMP and llvm-symbolizer (scripts/sanitize.sh, scripts/fuzz.sh)
set -euo pipefail
packages=(
  build-essential cmake pkg-config git
  libeigen3-dev libsuitesparse-dev libopenblas-dev libmetis-dev
  libtomlplusplus-dev libcli11-dev libfmt-dev nlohmann-json3-dev
  zlib1g-dev libcairo2-dev fonts-dejavu-core
  libgtest-dev libgmock-dev libbenchmark-dev
  python3 python3-dev python3-numpy python3-matplotlib python3-meshio python3-tomli-w python3-pytest pybind11-dev
)
case "${1:-}" in
  "") ;;
  sanitize) packages+=(clang-14 libclang-rt-14-dev libomp-14-dev llvm-14) ;;
  *) echo "usage: deps.sh [sanitize]" >&2; exit 2 ;;
esac
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "fibra: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
