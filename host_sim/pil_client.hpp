// Host side of the processor-in-the-loop link: starts the firmware (qemu-system-arm with the
// image, or any program speaking osc/pil.hpp on its standard input/output), and exchanges one
// sensor frame and one actuator frame per tick. Every wait is bounded; errors are reported as text.
#pragma once

#include <string>
#include <vector>

#include "osc/link/frames.hpp"

namespace sim {

enum class RxResult { kNeedMore, kFrame, kError };

/// The receive path's parsing, without I/O: feeds bytes[pos..len) to the parser until an actuator
/// frame completes (kFrame, decoded into f) or the link is corrupt (kError, message in err); pos
/// advances past the bytes consumed, so bytes after a frame stay for the next call.
RxResult parse_actuator_bytes(pil::Parser& parser, const std::uint8_t* bytes, int len, int& pos,
                              pil::ActuatorFrame& f, std::string& err);

class PilClient {
 public:
  PilClient() = default;
  PilClient(const PilClient&) = delete;
  PilClient& operator=(const PilClient&) = delete;
  ~PilClient();

  /// Starts argv[0] with the given arguments (its stdin/stdout carry the link) and waits up to
  /// ready_timeout_s for the peer's hello frame.
  bool start(const std::vector<std::string>& argv, std::string& err, double ready_timeout_s = 30.0);
  /// The QEMU command line that runs a firmware image on mps2-an386, deterministically (-icount).
  static std::vector<std::string> qemu_command(const std::string& qemu, const std::string& elf);

  bool send(const pil::SensorFrame& f, std::string& err);
  bool send_raw(const std::uint8_t* p, int n, std::string& err);
  /// Waits up to timeout_s (wall clock) for one actuator frame.
  bool receive(pil::ActuatorFrame& f, double timeout_s, std::string& err);
  /// Stops the peer (SIGKILL after a grace period) and returns its exit status (-1 if killed).
  int stop();
  bool running() const { return pid_ > 0; }

 private:
  int pid_ = -1;
  int to_child_ = -1, from_child_ = -1;
  pil::Parser parser_;
  std::uint8_t rx_[512];
  int rx_len_ = 0, rx_pos_ = 0;  // bytes read from the peer but not parsed yet
};

}  // namespace sim
