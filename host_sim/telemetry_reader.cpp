// osc_telemetry: reads a board's telemetry stream (boards/stm32f4: an actuator frame every 10th tick
// over its USART) with the PIL link's parser (osc/link/frames.hpp), from a capture file or a serial
// device, and prints one line a frame and a summary. Bytes between frames (the boot line) are
// counted as junk, not errors. With --json, each frame is a JSON line (its keys the actuator frame's field
// names, host_sim/frame_json.hpp) and the summary goes to stderr. Exit status 0 when at least one frame came and none
// was bad (and the
// --expect-* conditions hold), 1 otherwise, 2 on a bad command line or an unreadable source.
//
//   osc_telemetry build/m4f/boards/stm32f4/stm32f4_qemu_usart2.bin
//   osc_telemetry --baud 460800 --frames 500 /dev/ttyUSB0
//   osc_telemetry --json capture.bin | python3 -c 'import json,sys; [print(json.loads(l)["stage_cycles"]) for l in
//   sys.stdin]'
#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "cli_parse.hpp"
#include "frame_json.hpp"
#include "osc/control/faults.hpp"
#include "osc/link/frames.hpp"
#include "osc/runtime/supervisor.hpp"

namespace {

std::string fault_names(std::uint32_t bits) {
  if (bits == 0) return "none";
  std::string s;
  for (int i = 0; i < 32; ++i) {
    if (!(bits & (1u << i))) continue;
    if (!s.empty()) s += ",";
    s += i < osc::kFaultCount ? osc::kFaultNames[i] : "bit" + std::to_string(i);
  }
  return s;
}
const char* state_name(std::uint8_t s) { return osc::supervisor_state_name(s); }

/// Raw mode at `baud` for a serial device; false if the rate is not one of the usual ones.
bool set_serial(int fd, int baud) {
  const struct {
    int baud;
    speed_t code;
  } rates[] = {{115200, B115200}, {230400, B230400}, {460800, B460800}, {921600, B921600}};
  for (const auto& r : rates) {
    if (r.baud != baud) continue;
    termios t{};
    if (tcgetattr(fd, &t) != 0) return false;
    cfmakeraw(&t);
    cfsetispeed(&t, r.code);
    cfsetospeed(&t, r.code);
    return tcsetattr(fd, TCSANOW, &t) == 0;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Reads a board's telemetry frames (the PIL actuator frame) from a capture file or a serial device"};
  std::string source;
  int baud = 460800;
  long max_frames = 0;
  bool quiet = false, as_json = false;
  std::string expect_faults;
  long expect_frames = -1;
  app.add_option("source", source, "capture file, or serial device (e.g. /dev/ttyUSB0)")->required();
  app.add_option("--baud", baud, "baud rate of a serial device")
      ->check(CLI::IsMember({115200, 230400, 460800, 921600}));
  app.add_option("--frames", max_frames, "stop after this many frames (0: at the end of the file)");
  app.add_flag("--quiet", quiet, "the summary only");
  app.add_flag("--json", as_json,
               "each frame as a line of JSON (keys: the frame's field names); the summary on stderr");
  app.add_option("--expect-faults", expect_faults,
                 "fail unless the last frame's latched faults are these (e.g. estop)");
  app.add_option("--expect-frames", expect_frames, "fail unless exactly this many frames came");
  if (const int status = sim::parse_command_line(app, argc, argv, "osc_telemetry"); status >= 0) return status;

  const int fd = open(source.c_str(), O_RDONLY | O_NOCTTY);
  if (fd < 0) {
    std::fprintf(stderr, "osc_telemetry: cannot open %s\n", source.c_str());
    return 2;
  }
  if (isatty(fd) && !set_serial(fd, baud)) {
    std::fprintf(stderr, "osc_telemetry: cannot set %s to %d baud\n", source.c_str(), baud);
    return 2;
  }
  pil::Parser parser;
  long frames = 0, bad = 0, junk = 0, other_type = 0;
  pil::ActuatorFrame first{}, last{};
  std::uint8_t buf[256];
  for (ssize_t n; (max_frames == 0 || frames < max_frames) && (n = read(fd, buf, sizeof buf)) > 0;) {
    for (ssize_t i = 0; i < n; ++i)
      for (pil::Parser::Result r = parser.feed(buf[i]); r != pil::Parser::kPending; r = parser.next()) {
        if (r == pil::Parser::kJunk) {
          junk += parser.junk();
          continue;
        }
        pil::ActuatorFrame a;
        if (r != pil::Parser::kFrame) {
          ++bad;
        } else if (!parser.decode(a)) {
          ++other_type;
        } else {
          if (frames++ == 0) first = a;
          last = a;
          if (as_json && !quiet) {
            std::printf("%s\n", sim::frame_json(a).dump().c_str());
          } else if (!quiet) {
            std::printf("seq %u %s faults %s codes", a.seq, state_name(a.state), fault_names(a.faults).c_str());
            for (std::int32_t c : a.codes) std::printf(" %d", c);
            std::printf(" step %u max %u tick_max %u stack %u\n", a.step_cycles, a.max_cycles, a.tick_max_cycles,
                        a.stack_used);
          }
        }
      }
  }
  close(fd);
  std::fprintf(as_json ? stderr : stdout,
               "frames %ld (seq %u..%u), bad %ld, other type %ld, junk bytes %ld; last: state %s, faults %s\n", frames,
               first.seq, last.seq, bad, other_type, junk, state_name(last.state), fault_names(last.faults).c_str());
  bool ok = frames > 0 && bad == 0 && other_type == 0;
  if (expect_frames >= 0 && frames != expect_frames) {
    std::printf("expected %ld frames\n", expect_frames);
    ok = false;
  }
  if (!expect_faults.empty() && fault_names(last.faults) != expect_faults) {
    std::printf("expected the last frame's faults to be %s\n", expect_faults.c_str());
    ok = false;
  }
  return ok ? 0 : 1;
}
