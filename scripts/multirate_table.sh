#!/usr/bin/env bash
# The multirate haptic loop measured (docs/decisions/haptics_multirate_physics_at_the_bodys_rate_with_a_local_model.md): the slab press
# (`haptic_slab_press`) with its mesh replaced by CGAL slabs of about 10k and 20k nodes, and the
# soft tissue block (`haptic_tissue_press`), each with its scene's settings: lockstep at 1 kHz
# with the lag-free filter (the reference), real time, and real time beside one busy process.
# Prints one markdown row per body and session: the physics' step and pace, the force held
# while the hand is still (t 1.3-1.8 s) and its largest change between two servo cycles, the
# session's largest change, deadline misses, the watchdog, the energy to the user.
# Usage: scripts/multirate_table.sh [BUILD_DIR]   (about 10 minutes on 2 cores)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
vtb=${1:-$root/build}/bin/vtb
tmp=$(mktemp -d)
load=""
cleanup() { [ -n "$load" ] && kill "$load" 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
scenes=$root/experiments/scenes
for n in 10000 20000; do
  "$vtb" mesh generate slab --nodes "$n" -o "$tmp/slab$n.msh" >/dev/null
  sed "s#^file = .*#file = \"$tmp/slab$n.msh\"#" "$scenes/haptic_slab_press.toml" >"$tmp/slab$n.toml"
done
cp "$scenes/haptic_tissue_press.toml" "$tmp/tissue.toml"
row() { # body session dir
  python3 - "$1" "$2" "$3" <<'PY'
import csv, json, math, sys
body, session, d = sys.argv[1:]
s = json.load(open(d + '/summary.json'))
rows = list(csv.DictReader(open(d + '/haptics.csv')))
f = [math.hypot(float(r['fx']), float(r['fy'])) for r in rows]
t = [float(r['t']) for r in rows]
held = [x for x, tt in zip(f, t) if 1.3 <= tt <= 1.8]
mean = sum(held) / len(held)
step = max(abs(a - b) for a, b in zip(held, held[1:]))
whole = max(abs(a - b) for a, b in zip(f, f[1:]))
print(f"| {body} | {session} | {s['physics_filter']} | {s['physics_dt_us'] / 1e3:g} | {s['physics_time_ratio']:.2f} "
      f"| {mean:.3f} | {100 * step / mean:.1f} | {whole:.3f} | {s['deadline_misses']} "
      f"| {s.get('fault_reason', '') or 'no'} | {s['energy_to_user']:.4f} |")
PY
}
echo "| body | session | filter | physics dt [ms] | time ratio | held [N] | held change [%] | largest change [N] | misses | watchdog | energy to user [J] |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for body in slab10000 slab20000 tissue; do
  scene=$tmp/$body.toml
  sed 's/^kind = "filtered".*/kind = "filtered"\nfilter = "tensor-multigrid"/' "$scene" >"$tmp/lag_free.toml"
  "$vtb" haptics "$tmp/lag_free.toml" --lockstep --out "$tmp/lock" >/dev/null 2>&1
  row "$body" "lockstep 1 kHz" "$tmp/lock"
  "$vtb" haptics "$scene" --out "$tmp/rt" >/dev/null 2>&1
  row "$body" "real time" "$tmp/rt"
  (while :; do :; done) & load=$!
  "$vtb" haptics "$scene" --out "$tmp/busy" >/dev/null 2>&1
  kill "$load"; load=""
  row "$body" "real time, busy" "$tmp/busy"
done
