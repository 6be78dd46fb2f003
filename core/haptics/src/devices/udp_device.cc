#include "vtb/haptics/devices/udp_device.hh"

#include "vtb/base/input_error.hh"
#include "vtb/haptics/force_shaping.hh"
#include "vtb/problem/run_report.hh"

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>

namespace vtb {
namespace {

std::uint64_t now_ns(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

} // namespace

UdpEndpoint parse_endpoint(const std::string& text, const std::string& what) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0)
    throw InputError(what + ": \"" + text + "\" is not HOST:PORT (for example 127.0.0.1:47000)");
  UdpEndpoint e;
  e.host = text.substr(0, colon);
  if (e.host == "localhost") e.host = "127.0.0.1";
  in_addr a{};
  if (inet_pton(AF_INET, e.host.c_str(), &a) != 1)
    throw InputError(what + ": \"" + e.host + "\" is not an IPv4 address (the bridge binds a numeric address)");
  const std::string port = text.substr(colon + 1);
  char* end = nullptr;
  const long p = std::strtol(port.c_str(), &end, 10);
  if (port.empty() || *end != '\0' || p < 1 || p > 65535)
    throw InputError(what + ": port \"" + port + "\" is not a number in 1-65535");
  e.port = static_cast<int>(p);
  return e;
}

UdpDevice::UdpDevice(const DeviceSpec& spec, const Options& o)
    : m_spec(spec), m_opt(o), m_where(o.endpoint.host + ":" + std::to_string(o.endpoint.port)) {
  const std::string what = "udp:" + m_where;
  m_socket = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (m_socket < 0) throw InputError(what + ": cannot open a UDP socket: " + std::strerror(errno));
  const int on = 1;
  setsockopt(m_socket, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on); // the kernel's arrival time
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(o.endpoint.port));
  inet_pton(AF_INET, o.endpoint.host.c_str(), &addr.sin_addr);
  if (bind(m_socket, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const std::string why = std::strerror(errno);
    close(m_socket);
    throw InputError(what + ": cannot bind: " + why);
  }
  m_rtt_us.reserve(static_cast<std::size_t>(std::max(1L, o.max_samples)));
  // Wait for the device's first state packet: the session starts with the device there.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.connect_timeout);
  while (m_stats.received == 0) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      close(m_socket);
      throw InputError(what + ": no device packet within " + std::to_string(static_cast<int>(o.connect_timeout)) +
                       " s (start the device after vtb, e.g. python3 experiments/devices/udp_device.py " + m_where +
                       " --scene SCENE)");
    }
    pollfd p{m_socket, POLLIN, 0};
    poll(&p, 1, static_cast<int>(std::min<long>(left.count(), 100)));
    drain();
  }
}

UdpDevice::~UdpDevice() {
  if (m_socket >= 0) {
    send(Eigen::Vector2d::Zero(), 0.0, m_position);
    close(m_socket);
  }
}

void UdpDevice::drain() const {
  std::uint8_t buf[udp::kSize + 16];
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec))];
  for (;;) {
    sockaddr_in from{};
    iovec iov{buf, sizeof buf};
    msghdr msg{};
    msg.msg_name = &from;
    msg.msg_namelen = sizeof from;
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    const ssize_t n = recvmsg(m_socket, &msg, MSG_DONTWAIT);
    if (n < 0) return; // EAGAIN: nothing more now (or an error the next cycle meets again)
    // The kernel's arrival time on the realtime clock, taken to the monotonic one.
    const std::uint64_t mono = now_ns(CLOCK_MONOTONIC), real = now_ns(CLOCK_REALTIME);
    std::uint64_t arrival = mono;
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c))
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
        const std::uint64_t k =
            static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<std::uint64_t>(ts.tv_nsec);
        if (k <= real && real - k < mono) arrival = mono - (real - k);
      }
    const auto p = udp::decode(buf, static_cast<std::size_t>(n));
    if (!p || p->kind != udp::Kind::state) {
      ++m_stats.malformed;
      continue;
    }
    if (m_stats.received > 0 && p->sequence <= m_last.sequence) {
      ++m_stats.stale; // the latest packet wins: an older one arriving late is dropped
      continue;
    }
    if (m_stats.received > 0) m_stats.lost += static_cast<long>(p->sequence - m_last.sequence - 1);
    ++m_stats.received;
    m_last = *p;
    m_last_arrival = arrival;
    m_peer = from;
    // The round trip of the command this packet echoes, less the time it was held at the device.
    if (p->echo_sequence > 0 && p->echo_time_ns > 0 && arrival > p->echo_time_ns + p->echo_hold_ns &&
        m_rtt_us.size() < m_rtt_us.capacity())
      m_rtt_us.push_back(static_cast<double>(arrival - p->echo_time_ns - p->echo_hold_ns) * 1e-3);
    const Eigen::Vector2d pos(p->a[0], p->a[1]), vel(p->b[0], p->b[1]);
    if (pos.allFinite() && vel.allFinite()) {
      m_position = pos;
      m_velocity = vel;
    } else {
      ++m_stats.faults; // a non-finite state is not taken; the handle stays where it was
    }
  }
}

void UdpDevice::read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const {
  drain();
  if (!m_started) {
    // The link's counts start with the servo: packets the kernel dropped while the session was
    // being set up (its buffer holds a few hundred) are no loss of the session's.
    m_started = true;
    m_stats.lost = m_stats.stale = 0;
  }
  position = m_position;
  velocity = m_velocity;
}

void UdpDevice::command(const Eigen::Vector2d& force, double stiffness, const Eigen::Vector2d& anchor, double t) {
  m_t = t;
  const bool silent = now_ns(CLOCK_MONOTONIC) - m_last_arrival > static_cast<std::uint64_t>(m_opt.watchdog * 1e9);
  m_zeroed = silent;
  if (silent) {
    ++m_stats.silent_cycles;
    if (m_stats.first_silent_time < 0) m_stats.first_silent_time = t;
  }
  const Eigen::Vector2d f = silent ? Eigen::Vector2d::Zero() : saturate(force, m_spec.max_force);
  const double k = !silent && std::isfinite(stiffness) ? std::clamp(stiffness, 0.0, m_spec.max_stiffness) : 0.0;
  send(f, k, anchor.allFinite() ? anchor : m_position);
}

void UdpDevice::send(const Eigen::Vector2d& force, double stiffness, const Eigen::Vector2d& anchor) {
  if (m_stats.received == 0) return;
  udp::Packet p;
  p.kind = udp::Kind::command;
  p.sequence = ++m_sent;
  const std::uint64_t now = now_ns(CLOCK_MONOTONIC);
  p.time_ns = now;
  p.echo_sequence = m_last.sequence;
  p.echo_time_ns = m_last.time_ns;
  p.echo_hold_ns = now > m_last_arrival ? now - m_last_arrival : 0;
  p.a[0] = force.x();
  p.a[1] = force.y();
  p.b[0] = anchor.x();
  p.b[1] = anchor.y();
  p.c = stiffness;
  const auto bytes = udp::encode(p);
  if (sendto(m_socket, bytes.data(), bytes.size(), MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&m_peer),
             sizeof m_peer) < 0)
    ++m_stats.faults; // a full buffer or a vanished peer: the next cycle sends again
}

DeviceLinkStats UdpDevice::link_stats() const {
  DeviceLinkStats s = m_stats;
  const StepStats rtt = step_stats(m_rtt_us); // the run's own percentiles: sample floor(q n)
  s.rtt_p50_us = rtt.median;
  s.rtt_p99_us = rtt.p99;
  return s;
}

} // namespace vtb
