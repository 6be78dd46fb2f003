#!/usr/bin/env bash
# The tests on a fresh machine: install, build, ctest.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$VTB_BUILD"
ctest --output-on-failure -j "$(nproc)"
