#!/usr/bin/env bash
# Deadline misses of the real-time servo loop on a loaded machine, per servo-thread set-up
# (docs/decisions/haptics_servo_fifo_priority_windowed_velocity_ten_period_watchdog.md). Load: one busy process per core. Each
# set-up runs REPEATS sessions of the scene (3 s, 3000 servo cycles at 1 kHz).
# Usage: scripts/haptics_under_load.sh [SCENE] [REPEATS]   (prints a table; writes nothing else)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
vtb=${VTB_BUILD:-$root/build}/bin/vtb
scene=${1:-$root/experiments/scenes/haptic_press.toml}
repeats=${2:-3}
tmp=$(mktemp -d)
load=()
cleanup() { kill "${load[@]}" 2>/dev/null || true; rm -rf "$tmp"; }
trap cleanup EXIT
for _ in $(seq "$(nproc)"); do (while :; do :; done) & load+=($!); done
printf '%-28s %-26s %s\n' "set-up" "granted" "misses per run / worst period [us] / p99 [us]"
for setup in "--no-realtime-priority" "" "--lock-memory" "--pin-cpu 1" "--lock-memory --pin-cpu 1"; do
  runs=""
  granted=""
  for r in $(seq "$repeats"); do
    # shellcheck disable=SC2086
    "$vtb" haptics "$scene" $setup --out "$tmp/run" >/dev/null 2>&1 || true
    runs+=$(python3 -c "import json;j=json.load(open('$tmp/run/summary.json'));print(f\"{j['deadline_misses']}/{j['period_max_us']:.0f}/{j['period_p99_us']:.0f} \",end='')")
    granted=$(python3 -c "import json;print(','.join(json.load(open('$tmp/run/summary.json'))['realtime_setup']) or '-')")
  done
  printf '%-28s %-26s %s\n' "${setup:-(default: fifo)}" "$granted" "$runs"
done
