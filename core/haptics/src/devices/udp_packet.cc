#include "vtb/haptics/devices/udp_packet.hh"

#include <bit>
#include <cstring>
#include <type_traits>

namespace vtb::udp {
namespace {

// Explicit little-endian bytes, whatever the host's order.
template <class T> void put(std::uint8_t* out, T v) {
  std::uint64_t u = 0;
  if constexpr (sizeof(T) == 8 && std::is_floating_point_v<T>)
    u = std::bit_cast<std::uint64_t>(v);
  else
    u = static_cast<std::uint64_t>(v);
  for (std::size_t i = 0; i < sizeof(T); ++i) out[i] = static_cast<std::uint8_t>(u >> (8 * i));
}
template <class T> T get(const std::uint8_t* in) {
  std::uint64_t u = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) u |= static_cast<std::uint64_t>(in[i]) << (8 * i);
  if constexpr (std::is_floating_point_v<T>)
    return std::bit_cast<T>(u);
  else
    return static_cast<T>(u);
}

} // namespace

std::array<std::uint8_t, kSize> encode(const Packet& p) {
  std::array<std::uint8_t, kSize> out{};
  std::uint8_t* o = out.data();
  put<std::uint32_t>(o + 0, kMagic);
  put<std::uint16_t>(o + 4, kVersion);
  put<std::uint16_t>(o + 6, static_cast<std::uint16_t>(p.kind));
  put<std::uint32_t>(o + 8, p.sequence);
  put<std::uint32_t>(o + 12, p.echo_sequence);
  put<std::uint64_t>(o + 16, p.time_ns);
  put<std::uint64_t>(o + 24, p.echo_time_ns);
  put<std::uint64_t>(o + 32, p.echo_hold_ns);
  put<double>(o + 40, p.a[0]);
  put<double>(o + 48, p.a[1]);
  put<double>(o + 56, p.b[0]);
  put<double>(o + 64, p.b[1]);
  put<double>(o + 72, p.c);
  return out;
}

std::optional<Packet> decode(const std::uint8_t* in, std::size_t size) {
  if (size != kSize || get<std::uint32_t>(in) != kMagic || get<std::uint16_t>(in + 4) != kVersion) return std::nullopt;
  const auto kind = get<std::uint16_t>(in + 6);
  if (kind != static_cast<std::uint16_t>(Kind::state) && kind != static_cast<std::uint16_t>(Kind::command))
    return std::nullopt;
  Packet p;
  p.kind = static_cast<Kind>(kind);
  p.sequence = get<std::uint32_t>(in + 8);
  p.echo_sequence = get<std::uint32_t>(in + 12);
  p.time_ns = get<std::uint64_t>(in + 16);
  p.echo_time_ns = get<std::uint64_t>(in + 24);
  p.echo_hold_ns = get<std::uint64_t>(in + 32);
  p.a[0] = get<double>(in + 40);
  p.a[1] = get<double>(in + 48);
  p.b[0] = get<double>(in + 56);
  p.b[1] = get<double>(in + 64);
  p.c = get<double>(in + 72);
  return p;
}

} // namespace vtb::udp
