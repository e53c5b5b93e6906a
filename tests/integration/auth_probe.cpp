// The authenticated-rig test's foreign publisher and recorder (udpm inside tools/netns-run):
//
//   auth_probe commands --count N [--key-file F]   N valid 20-tick command blocks (50 V, linear
//                                                  mode, ticks from 0 on), unsigned unless keyed
//   auth_probe capture --channel C --out FILE       the first message on channel C, raw (trailer and
//                                                  all), written to FILE
//   auth_probe replay --channel C --in FILE         publishes FILE's bytes on C as they are
//   auth_probe sensor-jump --ahead N --count K      waits for a sensor block, then sends K unsigned
//                                                  20-tick blocks back to back from N ticks after
//                                                  it (what the sequence guard would confirm as a jump)
// Common: --url URL (default udpm ttl=0), --prefix P (default HX_; channel C is the suffix).
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "core/cli.hpp"
#include "core/clock.hpp"
#include "lcm/blocks.hpp"
#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "lcm/publisher.hpp"
#include "lcm/rig_auth.hpp"
#include "lcm/wire_layout.hpp"

namespace {

using namespace hystloop;

int send_commands(lcm::LCM& lcm, const ChannelNames& ch, int count, const std::string& key_file) {
  const std::shared_ptr<const RigAuth> auth =
      key_file.empty() ? nullptr : rig_auth_from_key_file(key_file, "--key-file");
  Publisher<command_block_t> pub(lcm, ch.command, default_message_check<command_block_t>(), auth);
  command_block_t block{};
  reserve_storage(block);
  for (int k = 0; k < count; ++k) {
    const std::int64_t first = std::int64_t{20} * k;
    begin_block(block, first, wall_utime(), -1);
    for (std::int64_t t = first; t < first + 20; ++t) {
      append_tick(block, CommandTick{t, 50.0, 1e-6, 0, command_block_t::MODE_LINEAR});
    }
    if (!pub.publish(block)) return 1;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  std::printf("sent %d command blocks (%s)\n", count, pub.signs() ? "signed" : "unsigned");
  return 0;
}

int capture(lcm::LCM& lcm, const std::string& channel, const std::string& out) {
  std::vector<std::uint8_t> bytes;
  lcm_subscribe(
      lcm.getUnderlyingLCM(), channel.c_str(),
      [](const lcm_recv_buf_t* rbuf, const char*, void* into) {
        auto* v = static_cast<std::vector<std::uint8_t>*>(into);
        if (v->empty())
          v->assign(static_cast<const std::uint8_t*>(rbuf->data),
                    static_cast<const std::uint8_t*>(rbuf->data) + rbuf->data_size);
      },
      &bytes);
  for (int i = 0; i < 100 && bytes.empty(); ++i) lcm.handleTimeout(50);
  if (bytes.empty()) {
    std::fprintf(stderr, "auth_probe: nothing on %s within 5 s\n", channel.c_str());
    return 1;
  }
  std::ofstream(out, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  std::printf("captured %zu bytes of %s\n", bytes.size(), channel.c_str());
  return 0;
}

int replay(lcm::LCM& lcm, const std::string& channel, const std::string& in) {
  std::ifstream file(in, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (bytes.empty()) return 1;
  return lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size())) == 0 ? 0 : 1;
}

int sensor_jump(lcm::LCM& lcm, const ChannelNames& ch, std::int64_t ahead, int count) {
  std::int64_t next = -1;
  lcm_subscribe(
      lcm.getUnderlyingLCM(), ch.sensor.c_str(),
      [](const lcm_recv_buf_t* rbuf, const char*, void* into) {
        sensor_block_t b;
        const std::int64_t body = lcm_body_size(wire_layout_of<sensor_block_t>(), rbuf->data, rbuf->data_size);
        if (body > 0 && b.decode(rbuf->data, 0, static_cast<int>(body)) == body && b.n_ticks > 0) {
          *static_cast<std::int64_t*>(into) = b.seq + b.n_ticks;
        }
      },
      &next);
  for (int i = 0; i < 100 && next < 0; ++i) lcm.handleTimeout(50);
  if (next < 0) {
    std::fprintf(stderr, "auth_probe: no sensor block within 5 s\n");
    return 1;
  }
  Publisher<sensor_block_t> pub(lcm, ch.sensor, default_message_check<sensor_block_t>(), nullptr);
  sensor_block_t block{};
  reserve_storage(block);
  for (int k = 0; k < count; ++k) {
    const std::int64_t first = next + ahead + std::int64_t{20} * k;
    begin_block(block, first, wall_utime(), 1e-4);
    for (std::int64_t t = first; t < first + 20; ++t) {
      SensorTick tick;
      tick.utime = wall_utime();
      tick.seq = t;
      tick.y_ref_m = 0.0;
      append_tick(block, tick);
    }
    if (!pub.publish(block)) return 1;
  }
  const long long first = next + ahead;
  std::printf("sent %d unsigned sensor blocks from tick %lld (%lld ahead)\n", count, first,
              static_cast<long long>(ahead));
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"auth_probe: foreign publisher and raw capture/replay for the authenticated-rig test"};
  app.require_subcommand(1);
  std::string url = "udpm://239.255.76.67:7667?ttl=0", prefix = "HX_", key_file, channel, file;
  int count = 10;
  std::int64_t ahead = 5000;
  app.add_option("--url", url);
  app.add_option("--prefix", prefix);
  auto* cmd = app.add_subcommand("commands");
  cmd->add_option("--count", count);
  cmd->add_option("--key-file", key_file);
  auto* cap = app.add_subcommand("capture");
  cap->add_option("--channel", channel)->required();
  cap->add_option("--out", file)->required();
  auto* rep = app.add_subcommand("replay");
  rep->add_option("--channel", channel)->required();
  rep->add_option("--in", file)->required();
  auto* jump = app.add_subcommand("sensor-jump");
  jump->add_option("--ahead", ahead);
  jump->add_option("--count", count);
  if (const auto exit_code = parse_cli(app, argc, argv)) return *exit_code;
  try {
    const ChannelNames ch(prefix);
    auto lcm = open_lcm(url);
    if (*cmd) return send_commands(*lcm, ch, count, key_file);
    if (*cap) return capture(*lcm, prefix + channel, file);
    if (*rep) return replay(*lcm, prefix + channel, file);
    if (*jump) return sensor_jump(*lcm, ch, ahead, count);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "auth_probe: %s\n", e.what());
    return 2;
  }
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {  // CLI11's set-up; nothing may escape main
    std::fprintf(stderr, "auth_probe: %s\n", e.what());
    return 1;
  }
}
