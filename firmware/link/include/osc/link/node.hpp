// The firmware side of the processor-in-the-loop link: a HAL binding (hal::ControlHal) of the
// control task whose encoders and DACs are the frames of osc/link/frames.hpp. Board-independent; a
// board supplies the static functions of the concept PilBoard below, and runs: on_byte() for every received byte, and tick() from the control interrupt when
// on_byte() asked for it or after on_timeout(), which it calls when no complete frame arrived
// within the link timeout.
#pragma once

#include <cstdint>

#include "osc/runtime/control_task.hpp"
#include "osc/link/frames.hpp"

namespace osc {

/// What the link node needs from a board (all static).
template <class B>
concept PilBoard = requires(const std::uint8_t* bytes, int n, std::uint32_t cycles, bool active) {
  { B::uart_write(bytes, n) } -> std::same_as<void>;       // blocking write of n bytes
  { B::cycles() } -> std::same_as<std::uint32_t>;          // free-running cycle counter
  { B::stack_used() } -> std::same_as<std::uint32_t>;      // main-stack high-water mark [bytes]
  { B::burn(cycles) } -> std::same_as<void>;               // busy-wait (fault injection only)
  { B::fault_output(active) } -> std::same_as<void>;       // the board's fault line
};

template <class S, PilBoard Board>
class PilNode {
 public:
  ControlTask<S> task;

  void init(const Vec6In<S>& q_start, FrictionMode mode, std::uint32_t period_cycles) {
    task.init(Model<S>::of(robot::kArm), Gains<S>::paper(), mode, q_start, period_cycles);
    expected_seq_ = 0;
    pending_faults_ = 0;
    configured_ = false;
    parser_.reset();
  }

  /// Announces that the receiver is ready (call once, after enabling reception).
  void hello() {
    const std::uint32_t seq = frame_.seq;
    frame_.seq = pil::kHelloSeq;
    const std::int32_t zero[kDof] = {0, 0, 0, 0, 0, 0};
    write_dacs(zero);
    frame_.seq = seq;
  }

  /// Feeds one received byte. Returns true when a tick is due (a sensor frame, valid or not, must
  /// be answered by exactly one actuator frame).
  bool on_byte(std::uint8_t b) {
    const pil::Parser::Result r = parser_.feed(b);
    if (r == pil::Parser::kPending) return false;
    if (r == pil::Parser::kFrame) {
      pil::SensorFrame f;
      if (!parser_.decode(f)) {
        pending_faults_ |= kFaultLinkCorrupt;
        return true;
      }
      if (f.seq != expected_seq_) pending_faults_ |= kFaultLinkCorrupt;
      if (!configured_) configure(f.inject);  // the first valid frame configures, once
      expected_seq_ = f.seq + 1;
      frame_ = f;
      return true;
    }
    // Bad checksum or header: the link is corrupt; answer so the host sees the fault at once.
    pending_faults_ |= kFaultLinkCorrupt;
    return r == pil::Parser::kBadChecksum;
  }

  /// Link timeout: no complete sensor frame in time (missing or short frame). A tick must follow,
  /// so that the fault and zero torque go out at once.
  void on_timeout() {
    pending_faults_ |= parser_.in_frame() ? kFaultLinkCorrupt : kFaultLinkLost;
    parser_.reset();
    frame_.inject = 0;
  }

  /// One control tick on the latest sensor frame (runs in the control interrupt).
  void tick() {
    if (frame_.inject & pil::kInjectNonFinite) task.inject_nonfinite();
    control_tick(task, *this);
    frame_.inject = 0;
  }

  // HAL binding used by control_tick.
  bool read_encoders(std::int32_t counts[kDof]) {
    for (int i = 0; i < kDof; ++i) counts[i] = frame_.counts[i];
    if (frame_.inject & pil::kInjectOverrun) Board::burn(2 * task.period_cycles + 1);
    return true;
  }
  void write_dacs(const std::int32_t codes[kDof]) {
    pil::ActuatorFrame a;
    a.seq = frame_.seq;
    for (int i = 0; i < kDof; ++i) a.codes[i] = codes[i];
    a.faults = task.sup.latched;
    a.state = static_cast<std::uint8_t>(task.sup.state);
    a.step_cycles = task.step_timing.last;
    a.max_cycles = task.step_timing.max;
    a.mean_cycles = task.step_timing.mean();
    a.tick_max_cycles = task.timing.max;
    a.stack_used = Board::stack_used();
    for (int i = 0; i < 3 * kDof; ++i) a.theta_hat[i] = static_cast<float>(task.state.adapt.theta_hat(i));
    for (int i = 0; i < kDof; ++i) a.tau_f_hat[i] = static_cast<float>(task.last.tau_f_hat(i));
    std::uint8_t buf[pil::kMaxFrame];
    Board::uart_write(buf, pil::encode(a, buf));
  }
  std::uint32_t cycles() const { return Board::cycles(); }
  void fault_output(bool active) { Board::fault_output(active); }
  std::uint32_t io_faults() {
    const std::uint32_t f = pending_faults_;
    pending_faults_ = 0;
    return f;
  }

 private:
  /// The configuration bits of the first sensor frame.
  void configure(std::uint8_t config) {
    configured_ = true;
    if (config & pil::kConfigNoCompensation) task.mode = FrictionMode::kNone;
    const unsigned law = (config & pil::kConfigAdaptationMask) >> pil::kConfigAdaptationShift;
    if (law != 0 && law <= static_cast<unsigned>(kAdaptationLawCount))
      task.gains.adaptation = static_cast<AdaptationLaw>(law - 1);
  }

  pil::Parser parser_;
  pil::SensorFrame frame_;
  std::uint32_t expected_seq_ = 0;
  std::uint32_t pending_faults_ = 0;
  bool configured_ = false;
};

}  // namespace osc
