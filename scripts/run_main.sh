#!/usr/bin/env bash
# The main job on a fresh machine: install, build, then the paper's reproduction
# (`vtb reproduce`): timing table on the 517- and 123-node plates, Fig. 3 analogue,
# accuracy vs speed, stability map, report.md. `--quick` (2 s of simulated time, small
# ladders) takes about a minute; without it about five.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
out=${VTB_OUT:-$VTB_ROOT/out/reproduce}
"$VTB_BUILD/bin/vtb" reproduce --out "$out" "$@"
