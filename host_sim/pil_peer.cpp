// pil_peer: the firmware's PIL node (osc/link/node.hpp, float) built for the host, speaking the link
// on stdin/stdout. It stands in for the QEMU image in tests of the host side and of the protocol,
// and runs exactly the firmware's board-independent code.
#include <poll.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <memory>

#include "osc/control/params.hpp"
#include "osc/link/node.hpp"
#include "osc/robot.hpp"

namespace {

struct StdioBoard {
  static inline std::uint32_t clock = 0;
  static void link_write(const std::uint8_t* p, int n) {
    while (n > 0) {
      const ssize_t w = write(STDOUT_FILENO, p, static_cast<size_t>(n));
      if (w <= 0) _exit(3);
      p += w;
      n -= static_cast<int>(w);
    }
  }
  static std::uint32_t cycles() { return clock += 1000; }  // a nominal 1000 cycles per call
  static std::uint32_t stack_used() { return 0; }
  static void burn(std::uint32_t c) { clock += c; }
  static void fault_output(bool) {}  // the frame's state carries it
};
static_assert(osc::PilBoard<StdioBoard>);

}  // namespace

int main() {
  auto node = std::make_unique<osc::PilNode<float, StdioBoard>>();
  node->init(osc::joint_vector<float>(osc::robot::kQStart), osc::FrictionMode::kAdaptive, 1000000);
  node->hello();
  // The firmware's silence timeout, in wall-clock time here. OSC_PIL_PEER_TIMEOUT_MS overrides it for
  // tests that do not exercise silence (the closed loop): on a loaded machine a scheduling stall of
  // the host process would otherwise read as a silent link and zero a tick.
  int timeout_ms = static_cast<int>(osc::params::kLinkTimeout * 1000);
  if (const char* t = std::getenv("OSC_PIL_PEER_TIMEOUT_MS")) timeout_ms = std::atoi(t) > 0 ? std::atoi(t) : timeout_ms;
  for (;;) {
    pollfd p{STDIN_FILENO, POLLIN, 0};
    const int r = poll(&p, 1, timeout_ms);
    if (r == 0) {
      node->on_timeout([&] { node->tick(); });
      continue;
    }
    std::uint8_t b;
    const ssize_t n = read(STDIN_FILENO, &b, 1);
    if (n <= 0) return 0;  // host closed the link
    node->on_byte(b, [&] { node->tick(); });
  }
}
