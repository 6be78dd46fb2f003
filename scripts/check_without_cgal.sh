#!/usr/bin/env bash
# The build without the CGAL mesh generators (VTB_WITH_CGAL=OFF: the CLI, viewer and Python module
# without CGAL meshes) configures, builds and passes its tests. Run by .ci/run after the README's test command.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${VTB_BUILD_NOCGAL:-$root/build-nocgal}
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DVTB_WITH_CGAL=OFF -DVTB_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j "$(nproc)"
(cd "$build" && ctest --output-on-failure -j "$(nproc)")
