// The controller's end of the command protocol (issue 23), the same on every transport (the PIL
// link under QEMU, a board's UART, the simulator's pseudo-terminal):
//
//   in   a command frame is prepared (prepare_frame_command, and a move_to's path checked:
//        prepare_checked_move) into the task's mailbox (ControlTask::pending), which the next tick
//        takes. The mailbox holds one command: one that arrives while it is full waits in a FIFO of
//        kCommandFifo frames and is prepared once the tick has taken the one before (a move is
//        planned from where the queue ends, which the one before may change). A command arriving
//        with the FIFO full is refused at once: queue_full.
//        A setpoint frame goes to the task's setpoint mailbox (offer_setpoint_frame).
//   out  after each tick: its answer when there is one (answer_due), and every state_period ticks
//        a state frame.
//
// Preparing a move costs a path check (docs/benchmarks.md: 165 000 instructions on the M4F): it runs
// where the port is called, which must be outside the control interrupt (a board's main loop, the
// host's driver). Header-only, allocation-free.
#pragma once

#include <cstdint>

#include "osc/link/commands.hpp"

namespace osc {

/// Command frames that can wait for the mailbox.
constexpr int kCommandFifo = 4;
/// The default period of the state frames [ticks]: 50 Hz.
constexpr std::uint32_t kStatePeriod = 20;

template <class S>
class CommandPort {
 public:
  /// A state frame every `period` ticks (0: none).
  std::uint32_t state_period = kStatePeriod;

  /// A complete frame from the parser. A command or a setpoint is taken (true); any other type is
  /// the caller's (false). `write(bytes, n)` sends an answer at once (a refusal that no tick gives:
  /// the FIFO full, a verb code outside the list).
  template <class Write>
  bool on_frame(ControlTask<S>& task, const pil::Parser& p, Write&& write) {
    pil::CommandFrame c;
    if (p.decode(c)) {
      if (count_ == kCommandFifo) {
        refuse_now(task, c, MotionReason::kQueueFull, write);
        return true;
      }
      fifo_[(head_ + count_++) % kCommandFifo] = c;
      prepare_next(task, write);
      return true;
    }
    pil::SetpointFrame s;
    if (p.decode(s)) {
      offer_setpoint_frame(task, s);
      return true;
    }
    return false;
  }

  /// After each tick (control_tick or a tick without a step): its answer, a state frame when due,
  /// then the next waiting command into the freed mailbox.
  template <class Write>
  void after_tick(ControlTask<S>& task, Write&& write) {
    std::uint8_t buf[pil::kMaxFrame];
    if (answer_due(task.report)) write(buf, pil::encode(answer_frame(task), buf));
    if (state_period != 0 && task.tick % state_period == 0) write(buf, pil::encode(state_frame_from_task(task), buf));
    prepare_next(task, write);
  }

  /// Commands waiting for the mailbox.
  int waiting() const { return count_; }

 private:
  /// The mailbox free: the oldest waiting command, prepared into it (a move_to's path checked too:
  /// check_prepared_move).
  template <class Write>
  void prepare_next(ControlTask<S>& task, Write&& write) {
    while (count_ > 0 && task.pending.verb == MotionVerb::kNone) {
      const pil::CommandFrame f = fifo_[head_];
      head_ = (head_ + 1) % kCommandFifo;
      --count_;
      TaskCommand<S> c = prepare_frame_command(task.gen, task.limits, task.tick, params::kControlHz, f);
      // Verb none is no command to the tick: a verb code outside the list is refused here.
      if (c.verb == MotionVerb::kNone) {
        refuse_now(task, f, c.refusal == MotionReason::kNone ? MotionReason::kBadCommand : c.refusal, write);
        continue;
      }
      if (c.verb == MotionVerb::kMoveTo) check_prepared_move(task, c);
      task.pending = c;
    }
  }

  template <class Write>
  void refuse_now(const ControlTask<S>& task, const pil::CommandFrame& c, MotionReason why, Write&& write) {
    MotionReport r;
    r.id = c.id;
    r.verb = c.verb < MotionNames<MotionVerb>::kCount ? static_cast<MotionVerb>(c.verb) : MotionVerb::kNone;
    r.outcome = CommandOutcome::kRefused;
    r.refusal = why;
    std::uint8_t buf[pil::kMaxFrame];
    write(buf, pil::encode(frame_from_report(r, task.machine.state, task.gen.queued(), task.tick - 1), buf));
  }

  pil::CommandFrame fifo_[kCommandFifo] = {};
  int head_ = 0, count_ = 0;
};

}  // namespace osc
