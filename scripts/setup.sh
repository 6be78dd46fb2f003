#!/usr/bin/env bash
# Sourced by run_main.sh and run_tests.sh: installs the Debian packages vtb needs (only the
# missing ones; root or sudo), then configures (once) and builds (cmake decides what is stale).
set -euo pipefail

VTB_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
VTB_BUILD=${VTB_BUILD:-$VTB_ROOT/build}

# Everything the project uses, including what later modules (deal.II reference, CGAL meshes,
# SUNDIALS, benchmarks) need, so that set-up never changes under a user's feet.
VTB_PACKAGES=(
  g++ clang libclang-rt-14-dev cmake ninja-build pkg-config
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib
  libeigen3-dev libtomlplusplus-dev nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev libsuitesparse-dev libopenblas0-serial
  libgmsh-dev libcgal-dev libsundials-dev libdeal.ii-dev openmpi-bin python3 libbullet-dev
  libglfw3-dev libimgui-dev libstb-dev libgl-dev xvfb xauth libgl1-mesa-dri zlib1g-dev
  texlive-latex-extra texlive-pictures texlive-latex-recommended texlive-fonts-recommended latexmk poppler-utils
)

vtb_install_packages() {
  local missing=()
  for p in "${VTB_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "vtb setup: installing ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

vtb_build() {
  if [ ! -f "$VTB_BUILD/CMakeCache.txt" ]; then
    cmake -S "$VTB_ROOT" -B "$VTB_BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release
  fi
  cmake --build "$VTB_BUILD" -j "$(nproc)"
}

# `import vtb` from any folder: a vtb.pth in Debian's python3 site folder (the one with
# python3-numpy) names build/python. Where another python3 of the same version comes first on
# PATH without numpy (a pyenv build, say), its site folder gets a vtb.pth too, naming build/python
# and Debian's dist-packages after its own, so that `python3 script.py` finds vtb and numpy.
vtb_install_python() {
  local debian=/usr/bin/python3
  [ -x "$debian" ] || debian=$(command -v python3)
  local line="$VTB_BUILD/python"
  local site
  site=$("$debian" -c 'import sysconfig; print(sysconfig.get_path("purelib"))')
  if ! { mkdir -p "$site" && printf '%s\n' "$line" >"$site/vtb.pth"; } 2>/dev/null; then
    site=$("$debian" -m site --user-site)
    mkdir -p "$site" && printf '%s\n' "$line" >"$site/vtb.pth"
  fi
  local other
  other=$(command -v python3 || true)
  if [ -n "$other" ] && [ "$("$other" -c 'import sys; print(sys.executable)')" != "$("$debian" -c 'import sys; print(sys.executable)')" ] &&
     [ "$("$other" -c 'import sys; print(sys.version_info[:2])')" = "$("$debian" -c 'import sys; print(sys.version_info[:2])')" ] &&
     ! "$other" -c 'import numpy' 2>/dev/null; then
    local other_site dist
    other_site=$("$other" -c 'import sysconfig; print(sysconfig.get_path("purelib"))')
    dist=$("$debian" -c 'import numpy, os; print(os.path.dirname(os.path.dirname(numpy.__file__)))')
    mkdir -p "$other_site" 2>/dev/null && printf '%s\n%s\n' "$line" "$dist" >"$other_site/vtb.pth" 2>/dev/null || true
  fi
}

vtb_install_packages
vtb_build
vtb_install_python
