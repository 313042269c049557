// A client of the command protocol (docs/protocol.md, "The command protocol"; docs/motion.md,
// "Clients"): commands to a controller, its answers and state frames back, over any byte transport
// (a serial line, the simulator's pseudo-terminal: osc_sim --pty). The frames, their encoding and
// the names of every code are the firmware's own (osc/link/frames.hpp, commands.hpp,
// osc/runtime/motion_states.hpp): nothing is declared twice.
//
//   auto t = osc::client::SerialTransport::open("/dev/pts/7", 115200, err);
//   osc::client::Client c(std::move(t));
//   c.wait_answer(c.enable(), 10);
//   osc::MoveRequest<double> m;
//   m.position = {0, 0.02, 0};
//   m.relative = true;
//   const osc::client::Outcome o = c.wait_done(c.move_to(m), 60);   // o.text(): "done", "aborted: stop_command"
//
// No function throws: a transport that fails gives Status::kError with the transport's message
// (error()), a command not sent gives id 0.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "osc/link/commands.hpp"
#include "osc/link/param_frames.hpp"
#include "stream_path.hpp"  // StreamPoint, resample_path

namespace osc::client {

/// A byte stream to the controller.
class Transport {
 public:
  virtual ~Transport() = default;
  /// Reads up to n bytes, waiting at most timeout_s for the first: the count, 0 when none came in
  /// time, -1 on an error (error() names it).
  virtual int read(std::uint8_t* buf, int n, double timeout_s) = 0;
  /// Writes all n bytes; false on an error (error() names it).
  virtual bool write(const std::uint8_t* buf, int n) = 0;
  const std::string& error() const { return error_; }

 protected:
  std::string error_;
};

/// A serial device or a pseudo-terminal in raw mode: 8 data bits, no parity, one stop bit, no flow
/// control, any baud rate (the standard ones through termios, others through termios2). Bytes
/// waiting when it opens are dropped (an earlier client's).
class SerialTransport : public Transport {
 public:
  /// nullptr on failure, with err naming the path and the reason.
  static std::unique_ptr<SerialTransport> open(const std::string& path, int baud, std::string& err);
  ~SerialTransport() override;
  SerialTransport(const SerialTransport&) = delete;
  SerialTransport& operator=(const SerialTransport&) = delete;
  int read(std::uint8_t* buf, int n, double timeout_s) override;
  bool write(const std::uint8_t* buf, int n) override;

 private:
  SerialTransport(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  int fd_;
  std::string path_;
};

/// What became of a command.
enum class Status : std::uint8_t {
  kAccepted,  ///< answered: accepted (wait_answer)
  kDone,      ///< a motion reached its target at rest; any other command accepted (and at rest after a stop)
  kRefused,   ///< refused: reason (cause: the fault bits behind faulted)
  kAborted,   ///< its motion was aborted: reason
  kTimeout,   ///< no decision within the time
  kError,     ///< the transport failed, or the request was bad (error)
};
const char* status_name(Status s);

struct Outcome {
  Status status = Status::kTimeout;
  std::uint32_t id = 0;
  MotionReason reason = MotionReason::kNone;
  std::uint32_t cause = 0;
  std::string error;
  pil::AnswerFrame answer{};  ///< the answer that decided it (kAccepted, kDone, kRefused, kAborted)
  /// A stream's setpoints not sent because the client fell behind its schedule (a busy machine): a
  /// setpoint whose successor was due already. The board keeps only the newest setpoint it has not
  /// taken (docs/protocol.md), so sent late together they would only be overwritten and counted in
  /// the state frame's `dropped`; the last setpoint (the end) is always sent.
  std::uint32_t skipped = 0;
  bool ok() const { return status == Status::kAccepted || status == Status::kDone; }
  /// "accepted", "done", "refused: not_enabled", "aborted: stop_command", "timeout", "error: ...".
  std::string text() const;
};

/// The names of fault bits ("none", or "tracking,estop"; a bit outside the catalogue "bitN").
std::string fault_names(std::uint32_t bits);
/// A state frame as lines: state, stop, faults, queued, running id, reference and measured pose.
std::string state_text(const pil::StateFrame& s);
/// "J1 fits, J2 stale, J3 -, ...": each joint's friction as set, checked by the momentum law (fits, stale) or not yet
/// (-): the state frame's friction_checked and friction_stale.
std::string friction_fit_text(std::uint8_t checked, std::uint8_t stale);
/// An answer frame as one line: the command answered, a motion done or aborted, a completion.
std::string answer_text(const pil::AnswerFrame& a);

class Client {
 public:
  explicit Client(std::unique_ptr<Transport> transport);

  // Each sends one command frame and returns its id (nonzero); 0 when it could not be sent (error()).
  std::uint32_t enable() { return command(MotionVerb::kEnable); }
  std::uint32_t disable() { return command(MotionVerb::kDisable); }
  std::uint32_t stop() { return command(MotionVerb::kStop); }
  std::uint32_t clear() { return command(MotionVerb::kClear); }
  std::uint32_t paper() { return command(MotionVerb::kPaper); }
  std::uint32_t move_to(const MoveRequest<double>& req) { return command(MotionVerb::kMoveTo, req); }
  /// An identify run; with `payload` (the flag payload) its estimate of the payload at the flange too.
  std::uint32_t identify(bool payload = false) {
    return command(MotionVerb::kIdentify, {}, payload ? pil::kFlagPayload : std::uint8_t{0});
  }
  /// A command frame of `verb` from `req`, with the command flags `flags` added (Command flags).
  std::uint32_t command(MotionVerb verb, const MoveRequest<double>& req = {}, std::uint8_t flags = 0);

  /// A stream: the stream command (period 1000 / rate_hz ms, a whole number from 1 to 100; relative;
  /// limits when given), its answer awaited, then one setpoint frame per period paced by the wall
  /// clock, the last with the end flag (rpy sent when has_rpy; with `velocity`, setpoint_velocity
  /// frames with each point's velocity: no delay of one period). Returns the stream command's answer
  /// once every setpoint is sent (kAccepted: wait_done(outcome.id) for its end), or its refusal, its
  /// abort while the setpoints went out (e.g. a stop), a timeout or an error.
  Outcome stream(const std::vector<StreamPoint>& points, bool has_rpy, double rate_hz, bool relative,
                 const CartesianLimits<double>* limits = nullptr, double answer_timeout_s = 10, bool velocity = false);

  /// The latest state frame, received after this call (waiting up to timeout_s); nullopt on a
  /// timeout or an error (error()).
  std::optional<pil::StateFrame> state(double timeout_s = 5);
  /// The command's answer: kAccepted or kRefused (or kTimeout, kError). Without an answer within
  /// kResendS the command is sent again, the same frame (the recovery rule of docs/protocol.md: the
  /// controller runs a command once and answers a repeat with the answer it gave).
  Outcome wait_answer(std::uint32_t id, double timeout_s);
  static constexpr double kResendS = 0.5;
  /// The command's end: a motion (move_to, paper, stream, home, identify) kDone when it reached its target at
  /// rest, kAborted with the reason when it was aborted (`dropped`: a move still queued when the
  /// motion ahead of it was stopped, re-targeted or faulted), each from the one answer frame that
  /// names its id; a stop or a disable that stops a motion kDone at rest; any other command kDone
  /// once accepted; kRefused with the reason; or kTimeout, kError.
  Outcome wait_done(std::uint32_t id, double timeout_s);

  /// A parameter request (osc/link/param_frames.hpp): the param frame sent, its param_answer awaited
  /// up to timeout_s; nullopt on a timeout or an error (error()). The answer's layout is checked
  /// against this client's table (osc::kParamLayout): another firmware's table is an error.
  std::optional<pil::ParamAnswerFrame> param(std::uint8_t op, int index = 0, int element = 0, double value = 0,
                                             double timeout_s = 5);

  /// The identify frame of run `id` (the estimate a board that estimates sends in the tick the run's motion ends,
  /// right after that tick's answer: docs/protocol.md, "Identify frame"), received so far or within timeout_s;
  /// nullopt when none came (a firmware from before the boards estimated, or the frame lost) or on an error
  /// (error()).
  std::optional<pil::IdentifyFrame> wait_identify(std::uint32_t id, double timeout_s);
  /// The identify_payload frame of run `id` (the payload's estimate of a run asked with the flag payload, right
  /// after its identify frame), received so far or within timeout_s; nullopt when none came or on an error.
  std::optional<pil::IdentifyPayloadFrame> wait_identify_payload(std::uint32_t id, double timeout_s);
  /// The identify_offset frame of run `id` (each drive's torque offset, right after its identify frame), received so
  /// far or within timeout_s; nullopt when none came (a firmware from before it was sent) or on an error.
  std::optional<pil::IdentifyOffsetFrame> wait_identify_offset(std::uint32_t id, double timeout_s);

  /// Reads and dispatches frames for timeout_s (on_answer, on_state); false on a transport error.
  bool pump(double timeout_s);
  std::function<void(const pil::AnswerFrame&)> on_answer;
  std::function<void(const pil::StateFrame&)> on_state;

  /// The last transport error ("" for none).
  const std::string& error() const { return error_; }
  /// The link errors this client's parser counted in what the controller sent, by kind.
  const pil::LinkCounters& link_errors() const { return link_errors_; }

  /// While it waits, a keep-alive frame (a state frame of zeros, which a controller takes as link
  /// activity and otherwise ignores) whenever nothing was sent for this long [s]; 0: none. A board
  /// whose encoders are local stops a motion when its command link is silent for
  /// params::kCommandLinkTimeout (0.5 s): the default, 0.1 s, keeps a waiting client's link alive.
  double keepalive_s = kKeepAliveDefault;
  static constexpr double kKeepAliveDefault = 0.1;

 private:
  bool send(const std::uint8_t* buf, int n);
  /// Reads frames until done() or the deadline (steady clock, seconds); false at the deadline or on
  /// an error.
  bool read_until(double deadline, const std::function<bool()>& done);
  void dispatch();
  /// The last frame of a run's kind (`last`) once it is run `id`'s, received so far or within timeout_s.
  template <class F>
  std::optional<F> wait_run_frame(const std::optional<F>& last, std::uint32_t id, double timeout_s);
  /// A parser result and the further events of the bytes already received: frames dispatched,
  /// errors counted.
  void take(pil::Parser::Result r);
  /// The command's answer and end as far as the answers so far tell (kTimeout: not yet).
  Outcome evaluate(std::uint32_t id, bool until_done) const;

  /// Sends the frame of command `id` again (true: sent, or no longer kept).
  bool resend(std::uint32_t id);

  static constexpr std::size_t kSentKept = 64;
  std::unique_ptr<Transport> t_;
  std::deque<std::pair<std::uint32_t, std::vector<std::uint8_t>>> sent_;  // the last kSentKept commands
  pil::Parser parser_;
  std::uint32_t next_id_;
  std::deque<pil::AnswerFrame> answers_;  // the last kHistory answers
  std::optional<pil::StateFrame> state_;
  std::optional<pil::ParamAnswerFrame> param_answer_;          // the last param_answer frame
  std::optional<pil::IdentifyFrame> identify_;                 // the last identify frame
  std::optional<pil::IdentifyPayloadFrame> identify_payload_;  // the last identify_payload frame
  std::optional<pil::IdentifyOffsetFrame> identify_offset_;    // the last identify_offset frame
  std::uint64_t states_seen_ = 0;
  std::string error_;
  double last_write_s_ = 0;  // steady clock [s] of the last frame sent (the keep-alive)
  double last_read_s_ = 0;   // steady clock [s] of the last byte received (the in-frame timeout)
  pil::LinkCounters link_errors_;
};

}  // namespace osc::client
