#!/usr/bin/env bash
# The main job on a fresh machine: install, build, run. Options go to the job.
# Today the main job is one `vtb run` of the example plate scene (the paper's step-force
# experiment on a structured stand-in mesh); `--quick` shortens it to 0.5 s of simulated time.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
quick=()
for a in "$@"; do [ "$a" = "--quick" ] && quick=(--duration 0.5); done
out=${VTB_OUT:-$VTB_ROOT/out/plate-step}
"$VTB_BUILD/bin/vtb" run "$VTB_ROOT/experiments/scenes/plate_step.toml" --out "$out" "${quick[@]}"
echo "summary: $out/summary.json"
