#!/usr/bin/env bash
# The README's viewer pictures, made by the viewer's headless mode under Xvfb (needs the
# packages of setup.sh): the paper's 517-node plate under its step load with a pull held on
# its top edge, the press scene in device mode (the ProCAT's handle pressing the edge), and the
# 3D slab in device mode (the handle pressing its top face in the scene's [haptics.plane]), and the
# example bean (a user's surface, meshed fine under the tool) pressed by the tool tip.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
img="$VTB_ROOT/docs/img"
mkdir -p "$img"
run() { xvfb-run -a -s "-screen 0 1280x800x24" "$VTB_BUILD/bin/vtb" view "$@"; }
run "$VTB_ROOT/experiments/scenes/plate517_step.toml" --frames 120 --drag 0.1,0.05:0.11,0.07 \
  --screenshot "$img/viewer_plate517.png"
run "$VTB_ROOT/experiments/scenes/haptic_press.toml" --device --frames 120 --drag 0.05,0.08:0.05,0.045 \
  --screenshot "$img/viewer_device.png"
run "$VTB_ROOT/experiments/scenes/haptic_slab_press.toml" --device --frames 120 \
  --drag 0.1,0.025,0.05:0.1,0.025,0.015 --screenshot "$img/viewer_slab_device.png"
run "$VTB_ROOT/experiments/scenes/bean_press.toml" --device --frames 120 \
  --drag 0,0.008,0.044:0,0.008,0.02 --screenshot "$img/viewer_bean_device.png"
