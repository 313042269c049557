// A program on the installed C++ client (docs/motion.md, "The C++ client installed"): on the
// controller at PORT, reads the state, enables, moves the wrist centre DY mm along y (default 20)
// relative to where it is, waits until the move is done, and disables, printing each step.
//
//   cpp_client PORT [DY]        e.g. cpp_client /dev/pts/7 -15
//
// Exit status 0 when every step succeeded, 1 when a command was refused, aborted or timed out, 2 for a
// bad argument or a port that does not open.
#include <osc_client.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

namespace {

using osc::client::Client;
using osc::client::Outcome;

/// Prints a step's outcome ("enable: accepted", "move: refused: not_enabled"); whether it succeeded.
bool step(const char* what, const Outcome& o) {
  std::printf("%s: %s\n", what, o.text().c_str());
  return o.ok();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: cpp_client PORT [DY]   (DY: the move along y in mm, default 20)\n");
    return 2;
  }
  double dy_mm = 20;
  if (argc == 3) {
    char* end = nullptr;
    dy_mm = std::strtod(argv[2], &end);
    if (end == argv[2] || *end != '\0' || !(std::fabs(dy_mm) > 0 && std::fabs(dy_mm) <= 100)) {
      std::fprintf(stderr, "cpp_client: DY '%s': a distance in mm, not 0, within -100 to 100\n", argv[2]);
      return 2;
    }
  }

  std::string err;
  auto port = osc::client::SerialTransport::open(argv[1], 115200, err);
  if (!port) {
    std::fprintf(stderr, "cpp_client: %s\n", err.c_str());
    return 2;
  }
  Client c(std::move(port));

  const auto state = c.state(10);
  if (!state) {
    std::fprintf(stderr, "cpp_client: no state frame from %s: %s\n", argv[1],
                 c.error().empty() ? "is a controller on the port?" : c.error().c_str());
    return 1;
  }
  std::printf("%s", osc::client::state_text(*state).c_str());

  if (!step("enable", c.wait_answer(c.enable(), 10))) return 1;

  osc::MoveRequest<double> move;  // the firmware's request: a position, and the limits of its defaults
  move.position = osc::Vec3<double>(0, dy_mm / 1000, 0);
  move.relative = true;
  char what[64];
  std::snprintf(what, sizeof what, "move %+g mm along y", dy_mm);
  const bool moved = step(what, c.wait_done(c.move_to(move), 60));

  // Disabled either way: the brakes on, the drives off.
  const bool disabled = step("disable", c.wait_done(c.disable(), 10));
  return moved && disabled ? 0 : 1;
}
