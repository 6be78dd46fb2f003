#pragma once
/// \file
/// A device driven from another process over UDP (udp_packet.hh): vtb binds HOST:PORT (loopback
/// by default) and waits for the device's first state packet; from then on each servo cycle takes
/// the newest state (older or out-of-order packets are dropped and counted, gaps counted as lost)
/// and answers the device with the command. A link silent for longer than the watchdog gets 0 N
/// (summary.json's `device_silent_cycles`, the run line says when). Non-blocking sockets: a cycle
/// never waits for the network, and nothing allocates after the constructor.

#include "vtb/haptics/device.hh"
#include "vtb/haptics/devices/udp_packet.hh"

#include <cstdint>
#include <string>
#include <vector>

#include <netinet/in.h>

namespace vtb {

struct UdpEndpoint {
  std::string host = "127.0.0.1";
  int port = 0;
};
/// "HOST:PORT" (an IPv4 address or localhost; port 1-65535), or InputError naming `what`.
UdpEndpoint parse_endpoint(const std::string& text, const std::string& what);

class UdpDevice final : public HapticDevice {
public:
  struct Options {
    UdpEndpoint endpoint;
    double watchdog = 0.05;        ///< s without a state packet after which 0 N is commanded
    double connect_timeout = 10.0; ///< s to wait for the device's first packet
    long max_samples = 1 << 20;    ///< round-trip samples kept (the session's servo cycles)
  };
  /// Binds the endpoint and waits for the first state packet. Throws InputError naming
  /// "udp:HOST:PORT" when it cannot bind or no device spoke in time.
  UdpDevice(const DeviceSpec& spec, const Options& options);
  ~UdpDevice() override; // a zero command, then the socket closed
  UdpDevice(const UdpDevice&) = delete;
  UdpDevice& operator=(const UdpDevice&) = delete;

  const DeviceSpec& spec() const override { return m_spec; }
  void read(Eigen::Vector2d& position, Eigen::Vector2d& velocity) const override;
  void command(const Eigen::Vector2d& force) override { command(force, 0.0, m_position, m_t); }
  void command(const Eigen::Vector2d& force, double stiffness, const Eigen::Vector2d& anchor, double t) override;
  void advance(double dt) override { m_t += dt; }
  std::string name() const override { return "udp:" + m_where; }
  DeviceLinkStats link_stats() const override;
  bool zeroed() const override { return m_zeroed; }

private:
  void drain() const;
  void send(const Eigen::Vector2d& force, double stiffness, const Eigen::Vector2d& anchor);
  DeviceSpec m_spec;
  Options m_opt;
  std::string m_where;
  int m_socket = -1;
  double m_t = 0;
  std::uint32_t m_sent = 0;
  mutable sockaddr_in m_peer{};
  mutable udp::Packet m_last{};             ///< the newest state taken
  mutable std::uint64_t m_last_arrival = 0; ///< its arrival, ns on the monotonic clock
  mutable DeviceLinkStats m_stats;
  bool m_zeroed = false;          ///< the last command went out as 0 N (the link was silent)
  mutable bool m_started = false; ///< the servo's first read done (the counts start there)
  mutable std::vector<double> m_rtt_us;
  mutable Eigen::Vector2d m_position = Eigen::Vector2d::Zero(), m_velocity = Eigen::Vector2d::Zero();
};

} // namespace vtb
