#!/usr/bin/env python3
"""A haptic device in another process, speaking vtb's UDP bridge (docs/devices.md, "The UDP bridge").

Start vtb first, then this:
    build/bin/vtb haptics SCENE --device udp:127.0.0.1:47000 &
    python3 experiments/devices/udp_device.py 127.0.0.1:47000 --scene SCENE

It plays the scene's [haptics.hand] path as the simulated ProCAT does: a handle of mass m with
viscous friction, pulled along the path by a grip spring and pushed by the force vtb sends, at
1 kHz. A driver for real hardware keeps the loop and the packets and replaces `Handle` with the
vendor SDK's read and write. At exit it prints one JSON line: packets, max_force, rtt_us_p50,
rtt_us_p99, lost (and stale, last_force, stopped).
"""
import argparse, json, socket, struct, sys, time, tomllib

MAGIC, VERSION, STATE, COMMAND = 0x44425456, 1, 1, 2
SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35)  # Linux's values where Python lacks the names
SCM_TIMESTAMPNS = SO_TIMESTAMPNS
PACKET = struct.Struct("<IHHIIQQQ5d")  # 80 bytes, little-endian: docs/devices.md byte by byte


class Handle:
    """The ProCAT's handle on a grip spring to a scripted hand (vtb's SimulatedProCAT, simplified)."""

    def __init__(self, waypoints, duration, grip, mass=0.15, viscous=0.5):
        self.w, self.T, self.k, self.m, self.b = waypoints, duration, grip, mass, viscous
        self.x, self.v = list(waypoints[0]), [0.0, 0.0]

    def hand(self, t):
        if len(self.w) == 1 or t <= 0: return self.w[0]
        s = min(t / self.T, 1.0) * (len(self.w) - 1)
        k = min(int(s), len(self.w) - 2); f = s - k
        return [(1 - f) * self.w[k][a] + f * self.w[k + 1][a] for a in range(2)]

    def advance(self, t, dt, force):
        h = dt / 8
        for i in range(8):
            hand = self.hand(t + (i + 1) * h)
            for a in range(2):  # implicit in the viscous and grip terms, as the simulated device
                f = self.k * (hand[a] - self.x[a]) + force[a] - self.b * self.v[a]
                self.v[a] += h * f / (self.m + h * self.b + h * h * self.k)
                self.x[a] += h * self.v[a]


def hand_in_plane(scene):
    """[haptics.hand] in device coordinates: [x, y] as given, [x, y, z] onto [haptics.plane]."""
    hp = scene["haptics"]; hand = hp["hand"]; plane = hp.get("plane", {})
    o = plane.get("origin"); ex = plane.get("x_axis", [1, 0, 0]); ey = plane.get("y_axis", [0, 1, 0])
    pts = []
    for w in hand["waypoints"]:
        if len(w) == 2: pts.append([float(w[0]), float(w[1])]); continue
        if o is None: sys.exit("udp_device: 3D waypoints need [haptics.plane].origin in the scene")
        d = [w[i] - o[i] for i in range(3)]
        pts.append([sum(d[i] * ex[i] for i in range(3)), sum(d[i] * ey[i] for i in range(3))])
    return pts, float(hand["duration"]), float(hand.get("grip_stiffness", 2000.0))


def kernel_arrival(ancillary):
    """When the kernel took the packet (SO_TIMESTAMPNS, realtime clock), on the monotonic clock:
    the time a packet waited for this loop's next poll is the device's hold, not the link's."""
    mono, real = time.monotonic_ns(), time.time_ns()
    for level, kind, data in ancillary:
        if level == socket.SOL_SOCKET and kind == SCM_TIMESTAMPNS and len(data) >= 16:
            sec, nsec = struct.unpack("qq", data[:16])
            return mono - max(0, real - (sec * 1_000_000_000 + nsec))
    return mono


def percentile(v, q):
    v = sorted(v); return v[min(len(v) - 1, int(q * len(v)))] if v else 0.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("address", help="HOST:PORT that vtb haptics --device udp:HOST:PORT binds")
    ap.add_argument("--scene", required=True, help="the scene whose [haptics.hand] the handle follows")
    ap.add_argument("--rate", type=float, default=1000.0, help="packets a second (Hz)")
    ap.add_argument("--stop-after", type=float, default=None, help="s: stop sending then (a device that dies mid-press)")
    a = ap.parse_args()
    host, port = a.address.rsplit(":", 1)
    with open(a.scene, "rb") as f: scene = tomllib.load(f)
    pts, duration, grip = hand_in_plane(scene)
    limit = float(scene["haptics"].get("max_force", 4.0))
    handle = Handle(pts, duration, grip)
    run_for = float(scene["scene"]["duration"]) + 1.0
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); sock.setblocking(False)
    sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
    peer = (host, int(port)); period = 1.0 / a.rate
    seq = 0; last = None; last_arrival = 0; rtt = []; taken = stale = lost = 0; max_force = 0.0
    force = [0.0, 0.0]; nonfinite = 0; next_t = time.monotonic(); heard = None; start = None
    opened = time.monotonic()
    while True:
        now = time.monotonic()
        # The hand's clock starts with vtb's first command (vtb builds its body before its servo
        # starts); until then the handle waits at the path's start and says where it is.
        t = now - start if start is not None else 0.0
        if start is None and now - opened > 300: sys.exit("udp_device: no command from vtb in 300 s")
        if t > run_for or (heard is not None and now - heard > 0.5): break  # vtb finished
        if a.stop_after is not None and t > a.stop_after: break
        while True:  # every command that arrived: the newest wins
            try: data, anc, _, _ = sock.recvmsg(256, 64)
            except BlockingIOError: break
            arrival = kernel_arrival(anc)
            if len(data) != PACKET.size: continue
            p = PACKET.unpack(data)
            if p[0] != MAGIC or p[1] != VERSION or p[2] != COMMAND: continue
            if last is not None and p[3] <= last[3]: stale += 1; continue
            if last is not None: lost += p[3] - last[3] - 1
            last, last_arrival, heard, taken = p, arrival, time.monotonic(), taken + 1
            if start is None: start = heard
            if p[4] > 0 and p[6] > 0: rtt.append((arrival - p[6] - p[7]) / 1e3)  # less vtb's holding time
            force = [p[8], p[9]]
            if not all(abs(x) < float("inf") for x in force): nonfinite += 1; force = [0.0, 0.0]
            max_force = max(max_force, (force[0] ** 2 + force[1] ** 2) ** 0.5)
        if start is not None: handle.advance(t, period, force)
        seq += 1; sent = time.monotonic_ns()
        echo = (last[3], last[5], sent - last_arrival) if last else (0, 0, 0)
        sock.sendto(PACKET.pack(MAGIC, VERSION, STATE, seq, echo[0], sent, echo[1], echo[2],
                                handle.x[0], handle.x[1], handle.v[0], handle.v[1], 0.0), peer)
        next_t += period
        while time.monotonic() < next_t - 0.0003: time.sleep(0.0002)
        while time.monotonic() < next_t: pass
    print(json.dumps({"packets": taken, "max_force": max_force, "rtt_us_p50": percentile(rtt, 0.5),
                      "rtt_us_p99": percentile(rtt, 0.99), "lost": lost, "stale": stale, "nonfinite": nonfinite,
                      "limit": limit, "last_force": (force[0] ** 2 + force[1] ** 2) ** 0.5, "sent": seq}))


if __name__ == "__main__":
    main()
