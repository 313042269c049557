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
//        frames), an answer frame more for each move the tick dropped from the queue (aborted
//        `dropped`), and every state_period ticks a state frame.
//
// The calls, for the two contexts of a board: receive() (a complete frame from the parser) and
// poll() (prepares the waiting commands) where the link is read, outside the control interrupt:
// preparing a move costs a path check (docs/benchmarks.md: 165 000 instructions on the M4F, soft
// double on the M3); after_tick() (frames only, no preparation) after the tick, in the control
// interrupt if the tick runs there. on_frame() is receive() then poll(). In lockstep (the host paces
// the ticks: the PIL link) nothing else runs between them; a timer-paced board must keep receive()
// and poll() from racing the tick over the mailbox: it calls receive() with the control interrupt
// masked and poll_paced() instead of poll() (below: the mailbox hand-over masked, never the path
// check), and watches the link's silence with CommandLinkWatch. Header-only, allocation-free.
#pragma once

#include <cstdint>

#include "osc/link/capture.hpp"
#include "osc/link/commands.hpp"
#include "osc/link/param_frames.hpp"

namespace osc {

/// Command frames that can wait for the mailbox.
constexpr int kCommandFifo = 4;
/// The command link's in-frame timeout in ticks, for a board that counts it so (params::kFrameTimeout).
constexpr std::uint32_t kFrameTimeoutTicks = stream::ticks(params::kFrameTimeout);
static_assert(kFrameTimeoutTicks >= 2, "a frame's bytes may straddle a tick");

/// The default period of the state frames [ticks]: 50 Hz.
constexpr std::uint32_t kStatePeriod = 20;
/// A timer-paced board (poll_paced): a move that brakes the running motion (a re-target, a move
/// after the paper's motion) is planned for the tick this many ticks after its inputs were taken,
/// and handed to the task just before that tick: enough for its path check (about 188 000
/// instructions on the M4F, 1.1 ms at 168 MHz, 1.2 ms with the ticks' 13 000 of every 168 000
/// cycles pre-empting it; flash wait states may double that), and short enough that such a
/// command changes the setpoint within issue 23's 10 ms of its arrival (at the tick after the
/// planned one: 6 ms).
constexpr std::uint32_t kPacedLeadTicks = 5;

template <class S>
class CommandPort {
 public:
  /// A state frame every `period` ticks (0: none).
  std::uint32_t state_period = kStatePeriod;

  /// What poll_paced() prepares a command from: copied from the task with the control interrupt
  /// masked.
  struct PacedInputs {
    pil::CommandFrame frame;
    MotionGenerator<S> gen;
    CartesianLimits<S> limits;
    CartesianLimits<S> home_limits;  // a home's (home_limits)
    std::uint64_t tick = 0;
    Vec6<S> q_measured, q_queue_end;  // the path check's seeds: a braked move's, a queued one's
  };

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
  /// refused at once, queue_full), a setpoint goes to the task (offer_setpoint_frame), a param frame
  /// is handled and answered at once (param_answer: a set of a gain evaluates the observer's margin,
  /// an operational-space update and a 6x6 factorisation, in the caller's context). True for those
  /// types; any other is the caller's (false).
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
    pil::SetpointVelocityFrame sv;
    if (p.decode(sv)) {
      offer_setpoint_frame(task, sv);
      return true;
    }
    pil::ParamFrame pf;
    if (p.decode(pf)) {
      std::uint8_t buf[pil::kMaxFrame];
      write(buf,
            pil::encode(param_answer(task, pf, param_storage_.save ? param_storage_ : ram_params_.storage()), buf));
      return true;
    }
    pil::CaptureFrame cf;
    if (p.decode(cf)) {
      std::uint8_t buf[pil::kMaxFrame];
      write(buf, pil::encode(capture.handle(task, cf), buf));
      return true;
    }
    return false;
  }

  /// The board's parameter store (save, load); without one, the port keeps the record in RAM.
  void set_param_storage(const ParamStorage& s) { param_storage_ = s; }
  /// The board's store's newest record applied to the task as a whole (param_apply: checked, the gains' margins
  /// too), as a board's boot applies it: ok, or why not (no_record without a board's store, or none in it). Outside
  /// the tick, with the torque off.
  ParamStatus apply_stored(ControlTask<S>& task) const {
    if (!param_storage_.load) return ParamStatus::kNoRecord;
    ParamRecord r;
    const ParamStatus st = param_storage_.load(param_storage_.ctx, r);
    return st == ParamStatus::kOk ? param_apply(task, r) : st;
  }

  /// A command frame into the FIFO; refused at once (queue_full) when it is full. A resend (the same
  /// frame again, nonzero id: a client that missed the answer) is not executed twice: answered
  /// again with the answer it had, or, still waiting for its tick, left to the answer to come.
  template <class Write>
  void enqueue(const ControlTask<S>& task, const pil::CommandFrame& c, Write&& write) {
    commanded_ = true;
    if (c.id != 0 && resend(task, c, write)) return;
    if (count_ == kCommandFifo) return refuse_now(task, c, MotionReason::kQueueFull, write);
    fifo_[(head_ + count_++) % kCommandFifo] = c;
  }

  /// The link errors the transport's parser found in the client's bytes, into the state frames'
  /// counters (pil::Parser results other than kPending and kFrame).
  void count_link_error(pil::Parser::Result r, const pil::Parser& p) {
    link[pil::Parser::error_of(r)] += r == pil::Parser::kJunk ? static_cast<std::uint32_t>(p.junk()) : 1u;
  }
  /// The link's error counters that the state frames carry (count_link_error, or the transport's).
  pil::LinkCounters link;

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
      if (c.verb == MotionVerb::kHome && c.refusal == MotionReason::kNone) c = prepare_checked_home(task, f.id);
      if (c.verb == MotionVerb::kIdentify)
        c = prepare_identify(task, f.id, static_cast<ExcitationCheck<S>*>(nullptr), identify_payload_mask(f));
      if (c.verb == MotionVerb::kMoveTo) check_prepared_move(task, c);
      task.pending = c;
      pending_print_ = fingerprint(f);
    }
  }

  /// poll() for a board whose timer paces the ticks: the control interrupt pre-empts this call at
  /// any instruction, and the tick reads the mailbox (task.pending) and changes what a preparation
  /// reads (the generator, the limits, the tick count, the measured angles). So each command goes
  /// in three steps:
  ///   1. masked: the mailbox free, the oldest command out of the FIFO, and a copy of what its
  ///      preparation reads (PacedInputs: the generator, a few kB: microseconds);
  ///   2. unmasked: prepared on the copy, a move_to's path checked (about a millisecond; ticks run
  ///      meanwhile, the task's own state untouched: the check's workspace is the main loop's);
  ///   3. masked: into the mailbox. A move planned from the copy's queue carries its epoch: the tick
  ///      refuses it (superseded) when the queue changed meanwhile, as in lockstep. A move that
  ///      brakes the running motion is planned for the tick kPacedLeadTicks after step 1 and goes in
  ///      just before that tick (calling `wait()` meanwhile: the board pumps its transmitter), or,
  ///      when the check took longer, is refused superseded by the tick that takes it.
  /// `masked(f)` runs f with the control interrupt held off; `write` is called only inside it.
  /// `in`: the copy's room (the board's: a few kB, static rather than on the main stack).
  template <class Write, class Masked, class Wait>
  void poll_paced(ControlTask<S>& task, PacedInputs& in, Write&& write, Masked&& masked, Wait&& wait) {
    for (;;) {
      bool got = false;
      masked([&] { got = take_inputs(task, in); });
      if (!got) return;
      const std::uint64_t planned = in.tick + kPacedLeadTicks;
      TaskCommand<S> c = prepare_frame_command(in.gen, in.limits, planned, params::kControlHz, in.frame);
      if (c.verb == MotionVerb::kNone) {
        const MotionReason why = c.refusal == MotionReason::kNone ? MotionReason::kBadCommand : c.refusal;
        masked([&] {
          refuse_now(task, in.frame, why, write);
          preparing_ = false;
        });
        continue;
      }
      if (c.verb == MotionVerb::kHome && c.refusal == MotionReason::kNone)
        c = prepare_home(in.gen, in.home_limits, task.model, task.check_data, task.io, in.q_measured, in.frame.id);
      if (c.verb == MotionVerb::kIdentify)
        c = prepare_identify_at(task.model, task.gains, task.check_data, in.q_measured, in.frame.id,
                                static_cast<ExcitationCheck<S>*>(nullptr), identify_payload_mask(in.frame));
      const bool has_path = c.verb == MotionVerb::kMoveTo || c.verb == MotionVerb::kHome;
      if (has_path && c.refusal == MotionReason::kNone) {
        const Vec6<S>& seed = c.brake ? in.q_measured : in.q_queue_end;
        const PathCheck<S> pc = check_path(task.model, task.check_data, c.move, in.gen.reference_orientation(), seed);
        c.refusal = path_refusal(pc.status);
        c.q_end = pc.q_end;
      }
      const bool timed = c.verb == MotionVerb::kMoveTo && c.brake && c.refusal == MotionReason::kNone;
      const std::uint16_t print = fingerprint(in.frame);
      bool placed = false;
      for (;;) {
        masked([&] {
          placed = hand_over(task, c, timed ? planned : task.tick);
          if (placed) pending_print_ = print, preparing_ = false;
        });
        if (placed) break;
        wait();
      }
    }
  }

  /// After each tick (control_tick or a tick without a step): its answer (once a command has come),
  /// then one answer frame for each move the tick dropped from the queue (dropped_answer_frame: only
  /// in the ticks that drop moves), then a state frame when due. Prepares nothing (safe in the
  /// control interrupt): poll() does.
  template <class Write>
  void after_tick(const ControlTask<S>& task, Write&& write) {
    capture.sample(task);
    std::uint8_t buf[pil::kMaxFrame];
    if (commanded_ && answer_due(task.report)) {
      const pil::AnswerFrame a = answer_frame(task);
      if (task.report.outcome != CommandOutcome::kNone) remember(a);
      write(buf, pil::encode(a, buf));
      for (int k = 0; k < task.report.dropped_moves; ++k) write(buf, pil::encode(dropped_answer_frame(task, k), buf));
    }
    if (state_period != 0 && task.tick % state_period == 0) {
      pil::StateFrame f = state_frame_from_task(task);
      f.link = link;
      write(buf, pil::encode(f, buf));
    }
  }

  /// Commands waiting for the mailbox.
  int waiting() const { return count_; }
  /// Resent commands (the same frame again) answered again or left to their answer, not executed.
  std::uint32_t resends = 0;
  /// Whether a command frame has come (answers are sent from then on).
  bool commanded() const { return commanded_; }
  /// The on-board capture (osc/link/capture.hpp): its frames answered in receive(), sampled in after_tick().
  SignalCapture capture;

 private:
  template <class Write>
  void refuse_now(const ControlTask<S>& task, const pil::CommandFrame& c, MotionReason why, Write&& write) {
    MotionReport r;
    r.id = c.id;
    r.verb = c.verb < MotionNames<MotionVerb>::kCount ? static_cast<MotionVerb>(c.verb) : MotionVerb::kNone;
    r.outcome = CommandOutcome::kRefused;
    r.refusal = why;
    const pil::AnswerFrame a = frame_from_report(r, task.machine.state, task.gen.queued(), task.tick - 1);
    remember(a, &c);
    std::uint8_t buf[pil::kMaxFrame];
    write(buf, pil::encode(a, buf));
  }

  /// A command's fingerprint: the CRC of its encoding (a resend repeats the frame exactly).
  static std::uint16_t fingerprint(const pil::CommandFrame& c) {
    std::uint8_t buf[pil::kMaxFrame];
    const int n = pil::encode(c, buf);
    return pil::crc16(buf + 2, n - 2);
  }
  /// An answered command (its answer frame; `c`, the command when at hand, else the one the tick
  /// took from the mailbox, whose fingerprint was kept), for resend().
  void remember(const pil::AnswerFrame& a, const pil::CommandFrame* c = nullptr) {
    if (a.id == 0) return;
    Answered& e = answered_[answered_next_];
    answered_next_ = (answered_next_ + 1) % kAnswersKept;
    e.answer = a;
    e.print = c ? fingerprint(*c) : pending_print_;
  }
  /// A resend of a command answered, waiting or in the mailbox: answered again as before (true),
  /// or left to the answer to come (true); false for a new command.
  template <class Write>
  bool resend(const ControlTask<S>& task, const pil::CommandFrame& c, Write&& write) {
    const std::uint16_t print = fingerprint(c);
    for (const Answered& e : answered_) {
      if (e.answer.id != c.id || e.print != print) continue;
      std::uint8_t buf[pil::kMaxFrame];
      write(buf, pil::encode(e.answer, buf));
      ++resends;
      return true;
    }
    bool waiting = (task.pending.verb != MotionVerb::kNone && task.pending.id == c.id && pending_print_ == print) ||
                   (preparing_ && in_.id == c.id && in_.print == print);
    for (int i = 0; i < count_ && !waiting; ++i) {
      const pil::CommandFrame& f = fifo_[(head_ + i) % kCommandFifo];
      waiting = f.id == c.id && fingerprint(f) == print;
    }
    if (waiting) ++resends;
    return waiting;
  }

  /// poll_paced() step 1 (masked): the oldest waiting command and its inputs, when the mailbox is free.
  bool take_inputs(const ControlTask<S>& task, PacedInputs& in) {
    if (count_ == 0 || task.pending.verb != MotionVerb::kNone) return false;
    in.frame = fifo_[head_];
    head_ = (head_ + 1) % kCommandFifo;
    --count_;
    preparing_ = true;
    in_.id = in.frame.id;
    in_.print = fingerprint(in.frame);
    in.gen = task.gen;
    in.limits = task.limits;
    in.home_limits = home_limits(task);
    in.tick = task.tick;
    in.q_measured = task.state.adapt.q_prev;
    in.q_queue_end = task.q_queue_end;
    return true;
  }

  /// poll_paced() step 3 (masked): the command into the mailbox now, if the tick about to run is
  /// `due` (true); not yet before it (false); refused superseded after it (true: the tick answers).
  static bool hand_over(ControlTask<S>& task, TaskCommand<S>& c, std::uint64_t due) {
    if (task.tick < due) return false;
    if (task.tick > due) c.refusal = MotionReason::kSuperseded;
    task.pending = c;
    return true;
  }

  /// Answers kept for resends: a client that resends within this many other commands' answers
  /// gets its own again.
  static constexpr int kAnswersKept = 8;
  struct Answered {
    pil::AnswerFrame answer{};  // id 0: empty
    std::uint16_t print = 0;
  };

  ParamStorage param_storage_{};
  RamParamStore ram_params_;
  pil::CommandFrame fifo_[kCommandFifo] = {};
  int head_ = 0, count_ = 0;
  bool commanded_ = false;
  Answered answered_[kAnswersKept] = {};
  int answered_next_ = 0;
  std::uint16_t pending_print_ = 0;  // the fingerprint of the command in the task's mailbox (or just taken)
  bool preparing_ = false;           // poll_paced: a command out of the FIFO, not yet in the mailbox
  struct {
    std::uint32_t id = 0;
    std::uint16_t print = 0;
  } in_;  // ... that command
};

/// The command link's silence on a board whose encoders are local (a board's UART: losing the
/// command link is a category-2 stop there; on the PIL link the frames carry the encoders and the
/// node's link supervision applies). The main loop notes every valid frame (heard(), any type); the
/// tick's context calls before_tick() before each tick: once a host has sent a command, a motion
/// that runs after params::kCommandLinkTimeout without a frame is stopped, category 2, aborted
/// link_silent (request_stop: the tick's own stop requests come first). It asks again every
/// silent tick of a motion; the machine ignores the request once it stops. Lock-free: heard() is
/// a byte store, and before_tick() runs where the main loop cannot pre-empt it.
class CommandLinkWatch {
 public:
  static constexpr std::uint32_t kTimeoutTicks = stream::ticks(params::kCommandLinkTimeout);
  static_assert(kTimeoutTicks > 1, "the command link timeout is longer than a tick");

  /// A board's watch: kTimeoutTicks. A simulated board that runs faster than real time counts the
  /// timeout in its client's time, kTimeoutTicks times its speed (the client paces its keep-alive
  /// by the wall clock).
  explicit CommandLinkWatch(std::uint32_t timeout_ticks = kTimeoutTicks)
      : timeout_(timeout_ticks > 1 ? timeout_ticks : 2) {}

  /// A valid frame came (main loop).
  void heard() { heard_ = true; }
  /// Before each tick (its context): counts the silence; true, and a stop requested, when the
  /// link has been silent for kTimeoutTicks while a commanded motion runs.
  template <class S>
  bool before_tick(ControlTask<S>& task, bool commanded) {
    if (heard_) {
      heard_ = false;
      silent_ = 0;
    } else if (silent_ < timeout_) {
      ++silent_;
    }
    if (!commanded || silent_ < timeout_ || !motion_running(task.machine.state)) return false;
    request_stop(task, MotionReason::kLinkSilent);
    ++stops_;
    return true;
  }
  /// Ticks since the last frame (up to the timeout).
  std::uint32_t silent_ticks() const { return silent_; }
  /// The timeout [ticks].
  std::uint32_t timeout_ticks() const { return timeout_; }
  /// Ticks that asked for a link_silent stop.
  std::uint32_t stops() const { return stops_; }

 private:
  volatile bool heard_ = false;
  std::uint32_t timeout_, silent_ = 0, stops_ = 0;
};

}  // namespace osc
