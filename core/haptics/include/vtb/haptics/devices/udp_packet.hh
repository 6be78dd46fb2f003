#pragma once
/// \file
/// The UDP bridge's datagram (docs/devices.md, "The UDP bridge", byte by byte): 80 bytes,
/// little-endian, the same layout both ways. The device sends its handle's state; vtb answers
/// each servo cycle with the command. Each side numbers its packets and echoes the newest it
/// has taken, with that packet's time stamp and how long it waited there before the reply left,
/// so that each side measures the link's round trip without the other's holding time.

#include <array>
#include <cstdint>
#include <optional>

namespace vtb::udp {

inline constexpr std::uint32_t kMagic = 0x44425456; ///< the bytes "VTBD"
inline constexpr std::uint16_t kVersion = 1;
inline constexpr std::size_t kSize = 80;
enum class Kind : std::uint16_t { state = 1, command = 2 };

struct Packet {
  Kind kind = Kind::state;
  std::uint32_t sequence = 0;      ///< the sender's, from 1
  std::uint32_t echo_sequence = 0; ///< the newest packet taken from the other side (0: none yet)
  std::uint64_t time_ns = 0;       ///< the sender's monotonic clock when it sent this
  std::uint64_t echo_time_ns = 0;  ///< the echoed packet's time_ns (the other side's clock)
  std::uint64_t echo_hold_ns = 0;  ///< how long the echoed packet waited here before this one left
  double a[2] = {0, 0};            ///< state: handle position (m); command: force (N)
  double b[2] = {0, 0};            ///< state: handle velocity (m/s); command: the local model's anchor (m)
  double c = 0;                    ///< state: 0; command: the local model's stiffness (N/m)
};

std::array<std::uint8_t, kSize> encode(const Packet& p);
/// The packet in `bytes`, or nothing where the size, magic or version is not this layout's.
std::optional<Packet> decode(const std::uint8_t* bytes, std::size_t size);

} // namespace vtb::udp
