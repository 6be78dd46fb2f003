#!/usr/bin/env bash
# The UDP bridge end to end, in real time: vtb haptics with --device udp and the Python example
# device on the other end (experiments/devices/udp_device.py), on the plate press.
#  1. The whole press: vtb completes, the device received packets and every force it got was
#     finite and within the scene's 4 N limit, vtb's summary names the device and its packets.
#  2. The device stopping mid-press (--stop-after 1.5 s): vtb's watchdog sends 0 N from the
#     first cycle past link_watchdog (50 ms) without a packet, and the run line says so. The
#     bound on when: 1.5 s + the 50 ms watchdog + 50 ms for the two processes' clocks, whose
#     zeros differ by the first command's trip and a busy 2-core machine's scheduling.
set -euo pipefail
vtb=$1; root=$2
scene=$root/experiments/scenes/haptic_press.toml
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
port() { python3 -c 'import socket; s=socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }

p=$(port)
"$vtb" haptics "$scene" --device "udp:127.0.0.1:$p" --out "$work/full" > "$work/full.log" 2>&1 &
vtb_pid=$!
python3 "$root/experiments/devices/udp_device.py" "127.0.0.1:$p" --scene "$scene" > "$work/device.json"
wait $vtb_pid || { cat "$work/full.log"; echo "FAIL: vtb haptics --device udp exited non-zero"; exit 1; }
cat "$work/device.json"
python3 - "$work/device.json" <<'PY'
import json, math, sys
d = json.load(open(sys.argv[1]))
assert d["packets"] > 1000, f"the device received {d['packets']} commands in a 3 s session at 1 kHz"
assert d["nonfinite"] == 0, "a non-finite force reached the device"
assert math.isfinite(d["max_force"]) and d["max_force"] <= d["limit"], d
assert d["max_force"] > 0.05, "the press pushed back"
PY
[ "$(field "$work/full/summary.json" device)" = "udp:127.0.0.1:$p" ] || { echo "FAIL: summary.json device"; exit 1; }
[ "$(field "$work/full/summary.json" device_packets)" -gt 1000 ] || { echo "FAIL: device_packets"; exit 1; }
grep -q "device udp:127.0.0.1:$p: [0-9]* packets taken" "$work/full.log" || { cat "$work/full.log"; echo "FAIL: run line"; exit 1; }

p=$(port)
"$vtb" haptics "$scene" --device "udp:127.0.0.1:$p" --out "$work/stop" > "$work/stop.log" 2>&1 &
vtb_pid=$!
python3 "$root/experiments/devices/udp_device.py" "127.0.0.1:$p" --scene "$scene" --stop-after 1.5 > /dev/null
wait $vtb_pid || { cat "$work/stop.log"; echo "FAIL: vtb crashed when the device stopped"; exit 1; }
grep -q "the device's link fell silent at t = " "$work/stop.log" || { cat "$work/stop.log"; echo "FAIL: no silent line"; exit 1; }
python3 - "$work/stop/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
t = s["device_silent_time"]
assert 1.5 <= t <= 1.5 + 0.05 + 0.05, f"0 N from t = {t} s; the device stopped at 1.5 s, the watchdog is 50 ms"
assert s["device_silent_cycles"] > 1000, s["device_silent_cycles"]
# haptics.csv logs what the device got: 0 N from the first silent cycle on.
import csv, math, os
rows = list(csv.DictReader(open(os.path.join(os.path.dirname(sys.argv[1]), "haptics.csv"))))
after = [r for r in rows if float(r["t"]) >= t]
assert len(after) > 1000, len(after)
held = max(math.hypot(float(r["fx"]), float(r["fy"])) for r in after)
assert held == 0.0, f"haptics.csv logs {held} N after the link fell silent at t = {t} s"
assert max(math.hypot(float(r["fx"]), float(r["fy"])) for r in rows) > 0.1, "the press was felt before"
PY
echo "udp bridge: 2 passed, 0 failed"
