// Devices behind the plug-in ABI and the UDP bridge, without hardware: a plug-in of another ABI
// version is refused in one line; the host clamps what a plug-in receives and sends 0 N after a
// fault and at close; the null device renders nothing; the UDP link takes the newest packet,
// counts stale, lost and malformed ones, clamps, and commands 0 N once silent past its watchdog.
#include "support/fresh_dir.hh"
#include "vtb/base/input_error.hh"
#include "vtb/haptics/devices/builtin_devices.hh"
#include "vtb/haptics/devices/plugin_device.hh"
#include "vtb/haptics/devices/udp_device.hh"
#include "vtb/haptics/session.hh"
#include "vtb/problem/scene.hh"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <future>
#include <sstream>
#include <thread>

namespace vtb {
namespace {

const std::string kExample = VTB_EXAMPLE_DEVICE_PLUGIN;
const std::string kOtherAbi = VTB_OTHER_ABI_PLUGIN;

/// The example plug-in's one-line log: "commands N max_force F nonfinite K max_stiffness S".
struct ExampleLog {
  long commands = -1, nonfinite = -1;
  double max_force = -1, max_stiffness = -1;
};
ExampleLog read_log(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string w;
  ExampleLog l;
  in >> w >> l.commands >> w >> l.max_force >> w >> l.nonfinite >> w >> l.max_stiffness;
  return l;
}

TEST(DevicePlugin, AnotherAbiVersionIsRefusedInOneLineBeforeAnyCall) {
  try {
    PluginDevice::load(kOtherAbi, "", DeviceSpec{}); // every function of it aborts if called
    FAIL() << "a plug-in of ABI version 2 was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(kOtherAbi), std::string::npos) << what;
    EXPECT_NE(what.find("ABI version " + std::to_string(VTB_DEVICE_ABI_VERSION + 1)), std::string::npos) << what;
    EXPECT_NE(what.find("speaks version " + std::to_string(VTB_DEVICE_ABI_VERSION)), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_THROW(PluginDevice::load("/no/such/driver.so", "", DeviceSpec{}), InputError);
}

TEST(DevicePlugin, TheHostClampsEveryForceAndSendsZeroAtClose) {
  const test::FreshDir dir;
  const auto log = dir / "log.txt";
  DeviceSpec host;
  host.max_force = 4.0;
  {
    auto d = PluginDevice::load(kExample, "from=0.1,0.06 to=0.1,0.05 seconds=1 log=" + log.string(), host);
    EXPECT_EQ(d->name(), "example-press");
    EXPECT_EQ(d->spec().max_force, 3.0) << "the device's own 3 N limit is below the scene's 4 N";
    Eigen::Vector2d p, v;
    d->read(p, v);
    EXPECT_EQ(p, Eigen::Vector2d(0.1, 0.06));
    d->command(Eigen::Vector2d(1e9, 0.0), 1e12, p, 0.0); // huge: clamped to 3 N and to the device's stiffness
    d->command(Eigen::Vector2d(NAN, 1.0), NAN, p, 0.001);
    d->command(Eigen::Vector2d(INFINITY, 0.0), 400.0, p, 0.002);
    d->command(Eigen::Vector2d(0.0, -2.0), 400.0, p, 0.003);
  }
  const ExampleLog l = read_log(log);
  EXPECT_EQ(l.commands, 5) << "four commands and the zero force before close";
  EXPECT_EQ(l.nonfinite, 0) << "a non-finite force reaches the device as 0 N";
  EXPECT_DOUBLE_EQ(l.max_force, 3.0);
  EXPECT_DOUBLE_EQ(l.max_stiffness, host.max_stiffness);
}

TEST(DevicePlugin, ANonFiniteReadLatchesAFaultAfterWhichZeroIsSent) {
  const test::FreshDir dir;
  const auto log = dir / "log.txt";
  DeviceLinkStats stats;
  {
    auto d = PluginDevice::load(kExample, "nan_after=1 log=" + log.string(), DeviceSpec{});
    Eigen::Vector2d p, v;
    d->read(p, v); // good
    d->command(Eigen::Vector2d(0.0, 0.0), 0.0, p, 0.0);
    EXPECT_FALSE(d->zeroed()) << "a live plug-in gets what it is commanded";
    d->read(p, v); // NaN: the fault latches; the last good position is held
    EXPECT_TRUE(p.allFinite());
    EXPECT_EQ(v, Eigen::Vector2d::Zero());
    d->command(Eigen::Vector2d(1.0, 0.0), 400.0, p, 0.0);
    EXPECT_TRUE(d->zeroed()) << "the session's record logs the 0 N sent";
    stats = d->link_stats();
  }
  EXPECT_EQ(stats.faults, 1);
  EXPECT_DOUBLE_EQ(read_log(log).max_force, 0.0) << "nothing but 0 N after the fault";
}

TEST(DevicePlugin, TheNullDeviceHoldsStillOutOfReach) {
  PluginDevice d(builtin_device_api("null"), "null", null_config({0.3, 0.2}), DeviceSpec{});
  Eigen::Vector2d p, v;
  d.read(p, v);
  EXPECT_EQ(p, Eigen::Vector2d(0.3, 0.2));
  EXPECT_EQ(v, Eigen::Vector2d::Zero());
  EXPECT_EQ(d.name(), "null");
  EXPECT_EQ(builtin_device_api("falcon"), nullptr);
}

TEST(DevicePlugin, ANullSessionRendersNothingAndTheExamplePluginPressesThePlate) {
  Scene s = read_scene(std::filesystem::path(VTB_SOURCE_DIR) / "experiments/scenes/haptic_press.toml");
  s.duration = 0.5;
  HapticsOptions o;
  o.lockstep = true;
  o.device = "null";
  const HapticsReport r = run_haptics(s, o);
  EXPECT_EQ(r.device, "null");
  EXPECT_EQ(r.max_force, 0.0);
  // The plate's top edge is at y = 0.05: the example's press from 1 cm above to 3 mm into it.
  s.duration = 1.5;
  s.haptics->plugin_config = "from=0.1,0.06 to=0.1,0.047 seconds=1";
  o.device = "plugin:" + kExample;
  const HapticsReport p = run_haptics(s, o);
  EXPECT_EQ(p.device, "example-press");
  EXPECT_GT(p.max_force, 0.0) << "3 mm into the plate pushes back";
  EXPECT_LE(p.max_force, 3.0) << "the plug-in's own limit";
  EXPECT_THROW(run_haptics(s,
                           [&] {
                             HapticsOptions x = o;
                             x.device = "falcon";
                             return x;
                           }()),
               InputError);
}

// --- the UDP bridge -----------------------------------------------------------------------

/// A port free on loopback now (bound to 0, read back, released).
int free_port() {
  const int s = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  inet_pton(AF_INET, "127.0.0.1", &a.sin_addr);
  bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t n = sizeof a;
  getsockname(s, reinterpret_cast<sockaddr*>(&a), &n);
  close(s);
  return ntohs(a.sin_port);
}

/// The device's side of the link, in the test: sends states, receives commands.
struct FakeDevice {
  int sock = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in vtb{};
  explicit FakeDevice(int port) {
    vtb.sin_family = AF_INET;
    vtb.sin_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET, "127.0.0.1", &vtb.sin_addr);
    timeval tv{1, 0};
    setsockopt(sock, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~FakeDevice() { close(sock); }
  void state(std::uint32_t seq, double x, double y) {
    udp::Packet p;
    p.sequence = seq;
    p.time_ns = 1;
    p.a[0] = x;
    p.a[1] = y;
    raw(udp::encode(p).data(), udp::kSize);
  }
  void raw(const void* bytes, std::size_t n) {
    sendto(sock, bytes, n, 0, reinterpret_cast<const sockaddr*>(&vtb), sizeof vtb);
  }
  udp::Packet command() {
    std::uint8_t buf[128];
    const ssize_t n = recv(sock, buf, sizeof buf, 0);
    EXPECT_EQ(n, static_cast<ssize_t>(udp::kSize));
    const auto p = udp::decode(buf, static_cast<std::size_t>(std::max<ssize_t>(n, 0)));
    EXPECT_TRUE(p.has_value());
    return p.value_or(udp::Packet{});
  }
};

/// A UdpDevice bound to a free port, opened by the fake device's first packet (seq 1 at (0, 0)).
std::unique_ptr<UdpDevice> open_link(FakeDevice*& fake, std::unique_ptr<FakeDevice>& owner) {
  UdpDevice::Options o;
  o.endpoint.port = free_port();
  o.connect_timeout = 5;
  owner = std::make_unique<FakeDevice>(o.endpoint.port);
  fake = owner.get();
  auto opened = std::async(std::launch::async, [o] { return std::make_unique<UdpDevice>(DeviceSpec{}, o); });
  while (opened.wait_for(std::chrono::milliseconds(10)) != std::future_status::ready) fake->state(1, 0.0, 0.0);
  return opened.get();
}

TEST(UdpBridge, PacketsRoundTripByteByByte) {
  udp::Packet p;
  p.kind = udp::Kind::command;
  p.sequence = 7;
  p.echo_sequence = 6;
  p.time_ns = 123456789012345ull;
  p.echo_time_ns = 42;
  p.echo_hold_ns = 9;
  p.a[0] = -0.25;
  p.b[1] = 1e-300;
  p.c = 400;
  const auto bytes = udp::encode(p);
  EXPECT_EQ(bytes[0], 'V');
  EXPECT_EQ(bytes[3], 'D');
  EXPECT_EQ(bytes[6], 2) << "the kind, little-endian";
  const auto q = udp::decode(bytes.data(), bytes.size());
  ASSERT_TRUE(q);
  EXPECT_EQ(q->sequence, 7u);
  EXPECT_EQ(q->time_ns, p.time_ns);
  EXPECT_EQ(q->a[0], -0.25);
  EXPECT_EQ(q->b[1], 1e-300);
  EXPECT_FALSE(udp::decode(bytes.data(), bytes.size() - 1));
  auto bad = bytes;
  bad[4] = 9; // another version
  EXPECT_FALSE(udp::decode(bad.data(), bad.size()));
}

TEST(UdpBridge, TheNewestPacketWinsAndLossReorderingAndGarbageAreCounted) {
  FakeDevice* fake = nullptr;
  std::unique_ptr<FakeDevice> owner;
  auto dev = open_link(fake, owner);
  Eigen::Vector2d p, v;
  dev->read(p, v); // the connect packets still queued
  const long first = dev->link_stats().received;
  fake->state(100, 0.01, 0.02);
  fake->state(97, 9.0, 9.0); // out of order: dropped
  fake->state(103, 0.03, 0.04);
  fake->raw("garbage", 7);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  dev->read(p, v);
  EXPECT_EQ(p, Eigen::Vector2d(0.03, 0.04)) << "the newest state";
  const DeviceLinkStats s = dev->link_stats();
  EXPECT_EQ(s.received, first + 2);
  EXPECT_GE(s.stale, 1);
  EXPECT_EQ(s.malformed, 1);
  EXPECT_EQ(s.lost, 98 + 2) << "2..99 between the first run and 100, then 101 and 102";
  dev->command(Eigen::Vector2d(100.0, 0.0), 400.0, p, 0.5);
  const udp::Packet c = fake->command();
  EXPECT_EQ(c.kind, udp::Kind::command);
  EXPECT_EQ(c.echo_sequence, 103u);
  EXPECT_DOUBLE_EQ(std::hypot(c.a[0], c.a[1]), DeviceSpec{}.max_force) << "clamped to the device's limit";
  dev->command(Eigen::Vector2d(NAN, 0.0), 400.0, p, 0.501);
  EXPECT_EQ(fake->command().a[0], 0.0) << "a non-finite force is sent as 0 N";
}

TEST(UdpBridge, ASilentLinkGetsZeroForceAfterItsWatchdog) {
  FakeDevice* fake = nullptr;
  std::unique_ptr<FakeDevice> owner;
  auto dev = open_link(fake, owner);
  Eigen::Vector2d p, v;
  fake->state(50, 0.0, 0.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  dev->read(p, v);
  dev->command(Eigen::Vector2d(1.0, 0.0), 0.0, p, 1.0);
  EXPECT_EQ(fake->command().a[0], 1.0) << "a live link renders the force";
  EXPECT_FALSE(dev->zeroed());
  std::this_thread::sleep_for(std::chrono::milliseconds(80)); // past the 50 ms watchdog
  dev->read(p, v);
  dev->command(Eigen::Vector2d(1.0, 0.0), 400.0, p, 1.08);
  const udp::Packet c = fake->command();
  EXPECT_EQ(c.a[0], 0.0);
  EXPECT_EQ(c.c, 0.0) << "nor any stiffness";
  EXPECT_TRUE(dev->zeroed()) << "the session's record logs the 0 N sent";
  const DeviceLinkStats s = dev->link_stats();
  EXPECT_EQ(s.silent_cycles, 1);
  EXPECT_DOUBLE_EQ(s.first_silent_time, 1.08);
}

TEST(UdpBridge, AnEndpointIsHostColonPortOrAOneLineError) {
  EXPECT_EQ(parse_endpoint("localhost:47000", "x").host, "127.0.0.1");
  EXPECT_EQ(parse_endpoint("127.0.0.1:1", "x").port, 1);
  for (const char* bad : {"47000", "127.0.0.1:", "127.0.0.1:70000", "example.org:4000", "127.0.0.1:4x"})
    EXPECT_THROW(parse_endpoint(bad, "--device udp"), InputError) << bad;
  UdpDevice::Options o;
  o.endpoint.port = free_port();
  o.connect_timeout = 0.2;
  try {
    UdpDevice d(DeviceSpec{}, o);
    FAIL() << "no device spoke";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no device packet within"), std::string::npos) << e.what();
  }
}

} // namespace
} // namespace vtb
