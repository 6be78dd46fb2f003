#!/usr/bin/env bash
# The tests on a fresh machine: install, build, ctest.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
(cd "$VTB_BUILD" && ctest --output-on-failure -j "$(nproc)")
# Bounded fuzzing of the .msh hardening, the scene parser and the surface readers (a fixed seed and
# input count, about 100 s each; VTB_SKIP_FUZZ=1 skips).
if [ "${VTB_SKIP_FUZZ:-0}" != 1 ]; then bash "$VTB_ROOT/scripts/run_fuzz.sh"; fi
