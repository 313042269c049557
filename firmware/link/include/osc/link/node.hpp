// The firmware side of the processor-in-the-loop link: a HAL binding (hal::ControlHal, hal::CurrentHal)
// of the control task whose encoders, amplifier currents and fault lines, and DACs are the frames of
// osc/link/frames.hpp. Board-independent; a board supplies the static functions of the concept PilBoard
// below, calls on_byte() for every received byte, and runs tick() from the control interrupt, paced in
// one of two ways:
//
//   lockstep (the host paces the ticks; pil_firmware under QEMU, pil_peer): a tick whenever
//     on_byte() calls its `due` (a frame ended, valid or not: each sensor frame is answered by exactly
//     one actuator frame), and after on_timeout(), which the board calls when no byte came for
//     params::kLinkTimeout of its time (the link's in-frame timeout: a frame cut short is scanned
//     again for the frames after its start, pil::Parser);
//   timer-paced (a board's control timer): a tick every period, whatever arrived; a tick with no
//     frame and no error since the last one keeps the previous codes, for at most
//     params::kLinkSilenceTicks ticks in a row; the next such tick is a silence error.
//
// Link supervision (both ways): any link error since the last tick (bad CRC, header or length, junk
// or lost-sync bytes, a frame cut short, a wrong sequence number, silence) makes the tick one
// without a sample: zero codes, no control step, no latch. params::kLinkErrorLimit such error ticks
// within params::kLinkErrorWindow ticks latch link_corrupt (link_lost if the last was a silence).
// Every error is counted by kind in the actuator frame's telemetry.
//
// The command protocol (docs/protocol.md): command and setpoint frames go to the node's CommandPort
// (osc/link/command_port.hpp), prepared in on_byte() (the board's main loop): they are neither a tick
// nor a link error. After each tick's actuator frame the port writes the tick's answer (once a
// command has come), a state frame when one is due (none unless the first sensor frame asked:
// kConfigStateFrames), then, when the first sensor frame asked for it (kConfigTrace), the tick's
// trace frame, always the last of the tick's frames. kConfigStartDisabled starts the task disabled,
// waiting for an enable, instead of running the paper's motion: a host that plays commands. A host
// that sends sensor frames only gets actuator frames only, as before the command protocol.
#pragma once

#include <cstdint>

#include "osc/link/command_port.hpp"
#include "osc/link/frames.hpp"
#include "osc/link/telemetry.hpp"
#include "osc/runtime/control_task.hpp"

namespace osc {

/// What the link node needs from a board (all static).
template <class B>
concept PilBoard = requires(const std::uint8_t* bytes, int n, std::uint32_t cycles, bool active) {
  { B::link_write(bytes, n) } -> std::same_as<void>;   // blocking write of n bytes
  { B::cycles() } -> std::same_as<std::uint32_t>;      // free-running cycle counter
  { B::stack_used() } -> std::same_as<std::uint32_t>;  // main-stack high-water mark [bytes], per tick
  { B::burn(cycles) } -> std::same_as<void>;           // busy-wait (fault injection only)
  { B::fault_output(active) } -> std::same_as<void>;   // the board's fault line
};

template <class S, PilBoard Board>
class PilNode {
 public:
  ControlTask<S> task;
  CommandPort<S> port;  // the command protocol's frames

  void init(const Vec6In<S>& q_start, FrictionMode mode, std::uint32_t period_cycles) {
    task.init(Model<S>::of(robot::kArm), Gains<S>::paper(), mode, q_start, period_cycles);
    port = {};
    port.capture.attach(capture_ring_, pil::kCaptureValues);
    port.state_period = 0;  // none unless the first sensor frame asks (kConfigStateFrames)
    trace_ = false;
    parser_.reset();
    frame_ = {};
    counters_ = {};
    expected_seq_ = 0;
    answer_seq_ = pil::kHelloSeq;
    errors_ = 0;
    fresh_ = synced_ = sample_ = false;
    configured_ = false;
    expire_due_ = false;
    silent_ticks_ = 0;
    latch_ = 0;
    error_count_ = error_next_ = 0;
    have_rx_ = false;
    rx_last_ = rx_gap_max_ = rx_long_gaps_ = 0;
  }

  /// Announces that the receiver is ready (call once, after enabling reception).
  void hello() {
    const std::uint32_t seq = answer_seq_;
    answer_seq_ = pil::kHelloSeq;
    const std::int32_t zero[kDof] = {0, 0, 0, 0, 0, 0};
    write_dacs(zero);
    answer_seq_ = seq;
  }

  /// Feeds one received byte; calls due() for each frame that ended here, valid or not (in lockstep
  /// a tick follows each and answers it: due() runs it, or pends it to run at once). More than one
  /// when the parser, after an error, finds a frame in the bytes already received (pil::Parser's
  /// resynchronisation); the tick of the first must run before the next is handled.
  template <class Due>
  void on_byte(std::uint8_t b, Due&& due) {
    note_rx_gap();
    if (expire_due_) {  // a frame a timer-paced tick cut short (and counted): its bytes scanned again here
      expire_due_ = false;
      if (parser_.expire() != pil::Parser::kPending)
        for (pil::Parser::Result r = parser_.next(); r != pil::Parser::kPending; r = parser_.next())
          if (on_result(r)) due();
    }
    for (pil::Parser::Result r = parser_.feed(b); r != pil::Parser::kPending; r = parser_.next())
      if (on_result(r)) due();
  }
  /// on_byte() without ticks: the number of frames that ended.
  int on_byte(std::uint8_t b) {
    int ended = 0;
    on_byte(b, [&] { ++ended; });
    return ended;
  }

  /// Lockstep: no byte for params::kLinkTimeout (the PIL link's in-frame timeout). A frame had
  /// started: it is lost (a short frame), and the bytes after its start are scanned again (a frame
  /// found there ends too); junk came instead of one: lost; otherwise a silence. due() once for
  /// each (at least once: a tick must follow).
  template <class Due>
  void on_timeout(Due&& due) {
    if (parser_.in_frame()) {
      for (pil::Parser::Result r = parser_.expire(); r != pil::Parser::kPending; r = parser_.next())
        if (on_result(r)) due();
    } else if (errors_ & (1u << pil::kErrJunk)) {
      lost_frame(pil::kErrSilence);  // a frame whose sync was destroyed: junk, then nothing
      due();
    } else {
      error(pil::kErrSilence);
      due();
    }
  }
  void on_timeout() {
    on_timeout([] {});
  }

  /// One control tick on the latest sensor frame (runs in the control interrupt).
  void tick() {
    if (fresh_) silent_ticks_ = 0;
    if (!fresh_ && errors_ == 0) {  // timer-paced: nothing arrived since the last tick
      if (++silent_ticks_ <= params::kLinkSilenceTicks) {
        hold_tick(task, *this);  // the DACs keep their codes (sent again)
        tick_frames(0);
        return;
      }
      silence_in_tick();
    }
    sample_ = fresh_ && errors_ == 0;
    if (!sample_) latch_ |= count_error_tick();
    if (sample_ && (frame_.inject & pil::kInjectNonFinite)) task.inject_nonfinite();
    const std::uint32_t faults = control_tick(task, *this);
    frame_.inject = 0;
    fresh_ = false;
    errors_ = 0;
    tick_frames(faults);
  }

  /// The link errors counted so far, by kind.
  const pil::LinkCounters& link_counters() const { return counters_; }

  // HAL binding used by control_tick.
  bool read_encoders(std::int32_t counts[kDof]) {
    for (int i = 0; i < kDof; ++i) counts[i] = frame_.counts[i];
    if (sample_ && (frame_.inject & pil::kInjectOverrun)) Board::burn(2 * task.period_cycles + 1);
    return sample_;
  }
  /// hal::CurrentHal: the amplifiers' currents of this tick's sensor frame, when it carries a reading
  /// (pil::kDriveCurrentsValid); false in a tick without a valid frame (a link error: no sample).
  bool read_currents(std::int16_t currents[kDof]) {
    for (int i = 0; i < kDof; ++i) currents[i] = frame_.currents[i];
    return sample_ && (frame_.drive & pil::kDriveCurrentsValid) != 0;
  }
  /// The amplifiers' fault lines of the latest valid sensor frame (pil::kDriveFaultLines).
  std::uint32_t amp_faults() const { return frame_.drive & pil::kDriveFaultLines; }
  void write_dacs(const std::int32_t codes[kDof]) {
    pil::ActuatorFrame a = telemetry_frame(task, codes, answer_seq_, Board::stack_used());
    a.link = counters_;
    a.rx_gap_max = rx_gap_max_;
    a.rx_long_gaps = rx_long_gaps_;
    std::uint8_t buf[pil::kMaxFrame];
    Board::link_write(buf, pil::encode(a, buf));
  }
  std::uint32_t cycles() const { return Board::cycles(); }
  void fault_output(bool active) { Board::fault_output(active); }
  std::uint32_t io_faults() {
    const std::uint32_t f = latch_;
    latch_ = 0;
    return f;
  }

 private:
  /// Timer-paced: the silence rule fired in the tick (the control interrupt), which parses nothing:
  /// a frame begun is a short frame, and the main loop's next on_byte() scans its bytes again.
  void silence_in_tick() {
    if (parser_.in_frame()) {
      lost_frame(pil::kErrShortFrame);
      expire_due_ = true;
    } else if (errors_ & (1u << pil::kErrJunk)) {
      lost_frame(pil::kErrSilence);
    } else {
      error(pil::kErrSilence);
    }
  }

  /// One parser event: 1 when a frame ended (a tick is due in lockstep), 0 otherwise.
  int on_result(pil::Parser::Result r) {
    if (r == pil::Parser::kJunk) {
      counters_[pil::kErrJunk] += static_cast<std::uint32_t>(parser_.junk());
      // Junk after a valid frame is a new error; junk after an error (the rest of a frame whose
      // header or length was bad, or that lost sync) belongs to that error and is only counted.
      if (synced_) errors_ |= 1u << pil::kErrJunk;
      synced_ = false;
      return 0;
    }
    if (r != pil::Parser::kFrame) return lost_frame(pil::Parser::error_of(r));
    pil::SensorFrame f;
    if (!parser_.decode(f)) {
      // A command or a setpoint: the port's (prepared at once once the first sensor frame has
      // configured the task). Any other valid frame is of the wrong type.
      bool taken = false;
      computing([&] {
        taken = port.receive(task, parser_, LinkWrite{});
        if (taken && configured_) port.poll(task, LinkWrite{});
      });
      if (!taken) return lost_frame(pil::kErrHeader);
      synced_ = true;
      return 0;
    }
    if (f.seq != expected_seq_) error(pil::kErrSeq);
    if (!configured_) configure(f.inject);                                     // the first valid frame configures, once
    if (port.waiting() > 0) computing([&] { port.poll(task, LinkWrite{}); });  // into the free mailbox, before the tick
    expected_seq_ = f.seq + 1;
    answer_seq_ = f.seq;
    frame_ = f;
    fresh_ = synced_ = true;
    return 1;
  }

  /// Work of the main loop's outside the tick that may take long: a command's preparation (a move's path check; an
  /// identify run's excitation check, up to four scales of 140 million instructions each on the M4F) and a param
  /// frame's (a gain's loop check). In lockstep no tick is due meanwhile: the host waits for this frame's answer. A
  /// board that must know (pil_firmware.cpp: its watchdog, paused as while it waits for the host) defines
  /// Board::computing(bool).
  template <class F>
  static void computing(F&& work) {
    if constexpr (requires { Board::computing(true); }) {
      Board::computing(true);
      work();
      Board::computing(false);
    } else {
      work();
    }
  }

  /// Board::link_write as the port's writer.
  struct LinkWrite {
    void operator()(const std::uint8_t* bytes, int n) const { Board::link_write(bytes, n); }
  };

  /// The command protocol's frames after the tick's actuator frame: the port's answer and state
  /// frames, then the trace (faults: those the tick detected).
  void tick_frames(std::uint32_t faults) {
    port.link = counters_;  // the state frames carry the PIL link's counters
    port.after_tick(task, LinkWrite{});
    if (!trace_) return;
    std::uint8_t buf[pil::kMaxFrame];
    Board::link_write(buf, pil::encode(trace_frame_from_task(task, answer_seq_, faults), buf));
  }

  /// The first sensor frame's configuration bits.
  void configure(std::uint8_t config) {
    configured_ = true;
    if (config & pil::kConfigStartDisabled) {  // before the mode and the law: init sets them
      // Ticks may have run before the first valid frame (link errors): their count and a fault they
      // latched stay (a configuration is no way out of a fault).
      const Supervisor sup = task.sup;
      const std::uint64_t tick = task.tick;
      task.init(Model<S>::of(robot::kArm), Gains<S>::paper(), task.mode, Vec6<S>(task.q_start), task.period_cycles,
                TaskStart::kDisabled);
      task.sup = sup;
      task.tick = tick;
      // The host's simulated arm stands at the start pose, which the host declares (as the in-process
      // simulator's arm does: sim::MotionSim): homed.
      task.homed = true;
      // The init undid what the boot applied from the board's store (pil_firmware.cpp: a power cycle's
      // parameters): applied again (nothing without a store).
      port.apply_stored(task);
      if (sup.state == SupervisorState::kFault) task.machine = {MotionState::kFault, false};
    }
    if (config & pil::kConfigStateFrames) port.state_period = kStatePeriod;
    trace_ = (config & pil::kConfigTrace) != 0;
    if (config & pil::kConfigNoCompensation) task.mode = FrictionMode::kNone;
    const unsigned law = (config & pil::kConfigAdaptationMask) >> pil::kConfigAdaptationShift;
    if (law != 0 && law <= static_cast<unsigned>(kAdaptationLawCount))
      task.gains.adaptation = static_cast<AdaptationLaw>(law - 1);
  }

  void error(pil::LinkError e) {
    ++counters_[e];
    errors_ |= 1u << e;
  }
  /// A frame ended unreadable (or never ended): presumed to be the expected one, so that its answer
  /// carries the sequence number the host is waiting for. Returns 1 (a tick is due).
  int lost_frame(pil::LinkError e) {
    error(e);
    synced_ = false;
    answer_seq_ = expected_seq_++;
    return 1;
  }

  /// Records a tick with link errors; returns the link fault to latch when it is the
  /// params::kLinkErrorLimit-th within params::kLinkErrorWindow ticks.
  std::uint32_t count_error_tick() {
    constexpr int kLimit = params::kLinkErrorLimit;
    error_ticks_[error_next_] = task.tick;
    error_next_ = (error_next_ + 1) % kLimit;
    if (error_count_ < kLimit) ++error_count_;
    const std::uint64_t oldest = error_ticks_[error_next_];  // when full, the slot after the newest
    if (error_count_ < kLimit || task.tick - oldest >= static_cast<std::uint64_t>(params::kLinkErrorWindow)) return 0;
    return errors_ == (1u << pil::kErrSilence) ? kFaultLinkLost : kFaultLinkCorrupt;
  }

  /// The longest gap between received bytes, and the gaps a tick-based silence watchdog would flag.
  void note_rx_gap() {
    const std::uint32_t now = Board::cycles();
    if (have_rx_) {
      const std::uint32_t gap = now - rx_last_;
      if (gap > rx_gap_max_) rx_gap_max_ = gap;
      if (task.period_cycles != 0 && gap > params::kLinkSilenceTicks * task.period_cycles) ++rx_long_gaps_;
    }
    have_rx_ = true;
    rx_last_ = now;
  }

  pil::Parser parser_;
  float capture_ring_[pil::kCaptureValues] = {};  // the capture's buffer (osc/link/capture.hpp), 16 KiB
  pil::SensorFrame frame_;                        // the latest valid sensor frame
  pil::LinkCounters counters_;
  std::uint32_t expected_seq_ = 0;
  std::uint32_t answer_seq_ = pil::kHelloSeq;  // sequence number of the next actuator frame
  std::uint32_t errors_ = 0;                   // 1 << pil::LinkError of the errors since the last tick
  bool fresh_ = false;                         // a valid sensor frame arrived since the last tick
  bool synced_ = false;                        // the last thing received was a valid frame (junk now is a new error)
  bool sample_ = false;                        // this tick has a valid sample
  bool configured_ = false;
  bool expire_due_ = false;  // timer-paced: a short frame counted by the tick, to be scanned again
  bool trace_ = false;       // a trace frame after every tick (kConfigTrace)
  int silent_ticks_ = 0;     // timer-paced: ticks in a row without a frame
  std::uint32_t latch_ = 0;  // link fault for io_faults()
  std::uint64_t error_ticks_[params::kLinkErrorLimit] = {};  // ticks of the latest error ticks
  int error_count_ = 0, error_next_ = 0;
  bool have_rx_ = false;
  std::uint32_t rx_last_ = 0, rx_gap_max_ = 0, rx_long_gaps_ = 0;
};

}  // namespace osc
