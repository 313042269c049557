// Host side of the processor-in-the-loop link: starts the firmware (qemu-system-arm with the
// image, or any program speaking osc/link/frames.hpp on its standard input/output), and exchanges
// one sensor frame and one actuator frame per tick. Every wait is bounded; errors are reported as
// text and counted by kind. exchange() is the amplifiers' input: the codes it returns are those of
// a valid, in-range answer to the tick's sensor frame, or all zero.
//
// The command protocol (docs/protocol.md): send() takes command and setpoint frames too, and the
// firmware's answer, state and trace frames, interleaved with its actuator frames, are collected
// (replies(), take_replies()) instead of being errors. When the session's first sensor frame asked
// for trace frames (pil::kConfigTrace), exchange() waits for the tick's trace frame as well, the last
// frame the firmware writes for a tick: every frame of the tick is then in replies().
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "osc/link/frames.hpp"

namespace sim {

enum class RxResult { kNeedMore, kFrame, kError };

/// How the frames reach a PIL firmware image in QEMU (PilClient::qemu_command).
enum class PilLink {
  kSemihosting,  ///< QEMU's semihosting console: a frame per read or write
  kUart,         ///< the board's UART0 through QEMU's UART model: a byte at a time, as on a board
};
const char* name(PilLink link);
bool parse_pil_link(const std::string& text, PilLink& link);

/// The QEMU machine for an ARM ELF image, from its build attributes (Tag_CPU_arch): mps2-an385
/// (Cortex-M3) for ARMv7-M, mps2-an386 (Cortex-M4F) for ARMv7E-M. Empty, with err, for a file that
/// is not a 32-bit little-endian ARM ELF image, or an architecture with no machine here.
std::string qemu_machine(const std::string& elf, std::string& err);

/// The command protocol's frames from the firmware (answer, state, trace), in the order each type
/// arrived.
struct PilReplies {
  std::vector<pil::AnswerFrame> answers;
  std::vector<pil::StateFrame> states;
  std::vector<pil::TraceFrame> traces;
  std::vector<pil::ParamAnswerFrame> params;    ///< the answers to param frames (sent as each was received)
  std::vector<pil::CaptureDataFrame> captures;  ///< the answers to capture frames (the same)
  std::vector<pil::IdentifyFrame> identifies;   ///< an identify run's estimate, after the tick its motion ended in
  std::vector<pil::IdentifyOffsetFrame> identify_offsets;    ///< its drives' torque offsets, right after
  std::vector<pil::IdentifyPayloadFrame> identify_payloads;  ///< its payload's, after those (the flag payload)
  bool empty() const {
    return answers.empty() && states.empty() && traces.empty() && params.empty() && captures.empty() &&
           identifies.empty() && identify_offsets.empty() && identify_payloads.empty();
  }
  void clear() {
    answers.clear(), states.clear(), traces.clear(), params.clear(), captures.clear(), identifies.clear();
    identify_offsets.clear(), identify_payloads.clear();
  }
};

/// A frame of a type the firmware sends: its type, and the frame of that type decoded.
struct FirmwareFrame {
  pil::FrameType type = pil::kActuatorFrame;
  pil::ActuatorFrame actuator;
  pil::AnswerFrame answer;
  pil::StateFrame state;
  pil::TraceFrame trace;
  pil::ParamAnswerFrame param_answer;
  pil::CaptureDataFrame capture_data;
  pil::IdentifyFrame identify;
  pil::IdentifyOffsetFrame identify_offset;
  pil::IdentifyPayloadFrame identify_payload;
};

/// The receive path's parsing, without I/O: feeds bytes[pos..len) to the parser until a frame of a
/// type the firmware sends completes (kFrame, decoded into f) or the link is corrupt (kError,
/// message in err: a bad frame, or a valid frame of a type the host sends); pos advances past the
/// bytes consumed, so bytes after a frame stay for the next call. Every error and every junk byte
/// is counted in counters, by kind.
RxResult parse_firmware_bytes(pil::Parser& parser, const std::uint8_t* bytes, int len, int& pos, FirmwareFrame& f,
                              pil::LinkCounters& counters, std::string& err);
/// The same up to an actuator frame (kFrame, decoded into f): the command protocol's frames before
/// it go to replies (when not null) and are no error.
RxResult parse_actuator_bytes(pil::Parser& parser, const std::uint8_t* bytes, int len, int& pos, pil::ActuatorFrame& f,
                              pil::LinkCounters& counters, std::string& err, PilReplies* replies = nullptr);

class PilClient {
 public:
  PilClient() = default;
  PilClient(const PilClient&) = delete;
  PilClient& operator=(const PilClient&) = delete;
  ~PilClient();

  /// Starts argv[0] with the given arguments (its stdin/stdout carry the link) and waits up to
  /// ready_timeout_s for the peer's hello frame.
  bool start(const std::vector<std::string>& argv, std::string& err, double ready_timeout_s = 30.0);
  /// The QEMU command line that runs a PIL firmware image deterministically (-icount shift=0) on the
  /// MPS2 machine of its core (qemu_machine), over the given transport (the image's
  /// boards/common/mps2/pil_firmware.cpp): UART0 on the process's stdin/stdout, or the semihosting
  /// console there (semihosting argument link=semihosting), which moves whole frames, not bytes.
  /// Empty, with err, when elf is not an ARM image of a core with a machine here.
  static std::vector<std::string> qemu_command(const std::string& qemu, const std::string& elf, PilLink link,
                                               std::string& err);

  /// Sends a sensor frame. The session's first one sets what the exchanges wait for: with
  /// pil::kConfigTrace in its inject byte, every exchange also waits for the tick's trace frame.
  bool send(const pil::SensorFrame& f, std::string& err);
  /// Sends a command or a setpoint frame (the command protocol: before the sensor frame of the tick
  /// that is to take it).
  bool send(const pil::CommandFrame& f, std::string& err);
  bool send(const pil::SetpointFrame& f, std::string& err);
  bool send(const pil::SetpointVelocityFrame& f, std::string& err);
  bool send(const pil::ParamFrame& f, std::string& err);
  bool send(const pil::CaptureFrame& f, std::string& err);
  bool send_raw(const std::uint8_t* p, int n, std::string& err);
  /// Waits up to timeout_s (wall clock) for one actuator frame; false on a corrupt frame (bad CRC,
  /// header or length), on silence and when the peer is gone. Junk between frames is skipped; the
  /// command protocol's frames before it are collected in replies().
  ///
  /// A peer that is computing is not silent: at the end of a wait, a peer whose process used at least a tenth of the
  /// wait's time on a CPU (a QEMU image's long main-loop work in lockstep, e.g. an identify command's check:
  /// docs/firmware.md, "Watchdog") is waited for a further kComputingWait, up to kComputingWaits times the
  /// call's timeout in all. A peer that sleeps, is stopped, or waits for a frame is silent at timeout_s.
  bool receive(pil::ActuatorFrame& f, double timeout_s, std::string& err);

  enum class Exchange {
    kApplied,  ///< a valid answer to the sensor frame, every code within the DAC range
    kZeroed,   ///< a corrupt, out-of-sequence or out-of-range answer: zero codes, the link goes on
    kLost,     ///< no answer in time or the peer is gone: zero codes, the link is down
  };
  /// One tick: sends s and waits up to timeout_s for its answer; earlier answers still in the pipe
  /// (e.g. to a silence) are skipped. a.codes are what the amplifiers apply: the answer's if it is
  /// kApplied, otherwise all zero (err says why; the counters count it). The rest of a is the
  /// answer's telemetry when a readable answer came, else untouched. The command protocol's frames
  /// that came with it are in replies(); in a traced session (send) the exchange ends with the
  /// tick's trace frame, and a trace that does not come in time makes it kLost.
  Exchange exchange(const pil::SensorFrame& s, pil::ActuatorFrame& a, double timeout_s, std::string& err);
  /// The command protocol's frames received so far (since the last take_replies()).
  const PilReplies& replies() const { return replies_; }
  /// Hands them over and starts collecting anew.
  PilReplies take_replies() {
    PilReplies r = std::move(replies_);
    replies_.clear();
    return r;
  }
  /// Every code of a within the DAC range [-kDacMaxCode, kDacMaxCode].
  static bool codes_in_range(const pil::ActuatorFrame& a);

  /// Errors on the actuator frames received so far, by kind.
  const pil::LinkCounters& link_counters() const { return counters_; }
  /// Answers whose codes were out of the DAC range (applied as zero).
  std::uint32_t code_range_errors() const { return code_range_errors_; }
  /// Stops the peer (SIGKILL after a grace period) and returns its exit status (-1 if killed).
  int stop();
  bool running() const { return pid_ > 0 && !reaped_; }
  /// Stops the peer's process for `seconds` of wall-clock time (SIGSTOP, then SIGCONT), as a busy
  /// machine's scheduler may: for tests of a peer that is descheduled while it waits.
  bool freeze_peer(double seconds, std::string& err);

 private:
  /// Once the peer has closed the link: waits up to a second for it to end and says how it ended
  /// ("exit status N", with the firmware's meaning where it has one, or "killed by signal N").
  std::string exit_description();

  /// A wait's view of the peer's process: when, and the CPU time it had used then (-1: /proc does not tell).
  struct CpuMark {
    std::chrono::steady_clock::time_point at;
    double cpu_s;
  };
  static constexpr double kComputingWait = 1.0;  ///< [s] a computing peer's further wait
  static constexpr double kComputingWaits = 60;  ///< the further waits' cap, in the call's timeouts
  CpuMark cpu_mark() const;
  /// At a wait's end: whether the peer computed since `m` (a tenth of the time on a CPU) and the call's cap is not
  /// reached; `m` moves to now.
  bool peer_computing(CpuMark& m);

  int pid_ = -1;
  double computed_s_ = 0, computing_cap_s_ = 0;  // the call's further waits so far, and their cap
  bool reaped_ = false;  // the peer ended and was waited for (exit_description); stop() only tidies up
  int wait_status_ = 0;
  int to_child_ = -1, from_child_ = -1;
  enum class Rx { kFrame, kCorrupt, kSilent, kGone };
  /// The next frame of a type the firmware sends.
  Rx receive_frame(FirmwareFrame& f, double timeout_s, std::string& err);
  /// The next actuator frame; the command protocol's frames before it into replies_.
  Rx receive_actuator(pil::ActuatorFrame& f, double timeout_s, std::string& err);
  /// Files a frame of the command protocol into replies_.
  void keep(const FirmwareFrame& f);
  template <class F>
  bool send_frame(const F& f, std::string& err);

  pil::Parser parser_;
  PilReplies replies_;
  bool sensor_sent_ = false;  // the session's first sensor frame has gone
  bool traced_ = false;       // it asked for trace frames: an exchange ends with the tick's trace
  pil::LinkCounters counters_;
  std::uint32_t code_range_errors_ = 0;
  std::uint8_t rx_[512];
  int rx_len_ = 0, rx_pos_ = 0;  // bytes read from the peer but not parsed yet
};

}  // namespace sim
