#!/usr/bin/env bash
# The main job on a fresh machine: install, build, then the paper's reproduction
# (`vtb reproduce`: timing table on the 517- and 123-node plates, Fig. 3 analogue,
# accuracy vs speed, stability map, creep, scaling, the haptic loop, report.md), then the
# paper (scripts/build_paper.sh: out/paper/vtb.pdf). `--quick` (2 s of simulated time, small
# ladders) takes about 5 min once built; the full run adds the long ladders (docs/harness.md).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
out=${VTB_OUT:-$VTB_ROOT/out/reproduce}
"$VTB_BUILD/bin/vtb" reproduce --out "$out" "$@"
# The paper from this reproduction (figures also as PNG beside report.md); prints the PDF's path.
bash "$VTB_ROOT/scripts/build_paper.sh" "$out" "${VTB_PAPER_OUT:-$VTB_ROOT/out/paper}"
