// The controller's end of the command protocol (issue 23), the same on every transport (the PIL
// link under QEMU, a board's UART, the simulator's pseudo-terminal):
//
//   in   a command frame waits in a FIFO of kCommandFifo frames and is prepared
//        (prepare_frame_command, and a move_to's path checked: check_prepared_move) into the task's
//        mailbox (ControlTask::pending) once the mailbox is free, which the next tick takes. The
//        mailbox holds one command: a command is prepared once the tick has taken the one before it
//        (a move is planned from where the queue ends, which the one before may change). A command
//        arriving with the FIFO full is refused at once: queue_full.
//        A setpoint frame goes to the task's setpoint mailbox (offer_setpoint_frame).
//   out  after each tick: its answer when there is one (answer_due) and the port has had a command
//        (a host that never commands, e.g. the paper's experiment over the PIL link, gets no answer
//        frames), and every state_period ticks a state frame.
//
// The calls, for the two contexts of a board: receive() (a complete frame from the parser) and
// poll() (prepares the waiting commands) where the link is read, outside the control interrupt:
// preparing a move costs a path check (docs/benchmarks.md: 165 000 instructions on the M4F, soft
// double on the M3); after_tick() (frames only, no preparation) after the tick, in the control
// interrupt if the tick runs there. on_frame() is receive() then poll(). In lockstep (the host paces
// the ticks: the PIL link) nothing else runs between them; a timer-paced board must keep receive()
// and poll() from racing the tick over the mailbox. Header-only, allocation-free.
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

  /// after_tick(), then poll(): for a transport that ticks and prepares in one thread (the simulator,
  /// a lockstep loop), the frames of the tick just run and the next waiting command into the freed
  /// mailbox.
  template <class Write>
  void after_tick_and_poll(ControlTask<S>& task, Write&& write) {
    after_tick(task, write);
    poll(task, write);
  }

  /// A complete frame from the parser: receive() it, then poll(). A command or a setpoint is taken
  /// (true); any other type is the caller's (false). `write(bytes, n)` sends an answer at once (a
  /// refusal that no tick gives: the FIFO full, a verb code outside the list).
  template <class Write>
  bool on_frame(ControlTask<S>& task, const pil::Parser& p, Write&& write) {
    if (!receive(task, p, write)) return false;
    poll(task, write);
    return true;
  }

  /// A complete frame from the parser, taken but not prepared: a command waits in the FIFO (or is
  /// refused at once, queue_full), a setpoint goes to the task (offer_setpoint_frame). True for
  /// those two types; any other is the caller's (false).
  template <class Write>
  bool receive(ControlTask<S>& task, const pil::Parser& p, Write&& write) {
    pil::CommandFrame c;
    if (p.decode(c)) {
      enqueue(task, c, write);
      return true;
    }
    pil::SetpointFrame s;
    if (p.decode(s)) {
      offer_setpoint_frame(task, s);
      return true;
    }
    return false;
  }

  /// A command frame into the FIFO; refused at once (queue_full) when it is full.
  template <class Write>
  void enqueue(const ControlTask<S>& task, const pil::CommandFrame& c, Write&& write) {
    commanded_ = true;
    if (count_ == kCommandFifo) return refuse_now(task, c, MotionReason::kQueueFull, write);
    fifo_[(head_ + count_++) % kCommandFifo] = c;
  }

  /// The mailbox free: the oldest waiting command, prepared into it (a move_to's path checked too:
  /// check_prepared_move). A verb outside the list is refused at once (bad_command).
  template <class Write>
  void poll(ControlTask<S>& task, Write&& write) {
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

  /// After each tick (control_tick or a tick without a step): its answer (once a command has come),
  /// then a state frame when due. Prepares nothing (safe in the control interrupt): poll() does.
  template <class Write>
  void after_tick(const ControlTask<S>& task, Write&& write) const {
    std::uint8_t buf[pil::kMaxFrame];
    if (commanded_ && answer_due(task.report)) write(buf, pil::encode(answer_frame(task), buf));
    if (state_period != 0 && task.tick % state_period == 0) write(buf, pil::encode(state_frame_from_task(task), buf));
  }

  /// Commands waiting for the mailbox.
  int waiting() const { return count_; }
  /// Whether a command frame has come (answers are sent from then on).
  bool commanded() const { return commanded_; }

 private:
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
  bool commanded_ = false;
};

}  // namespace osc
