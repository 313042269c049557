// The motion sources: where each control step's desired state d = (x_d, x_d dot, x_d ddot) comes
// from. control_step() tracks whatever d it is given; the MotionGenerator computes d for the tick
// from one of three sources:
//   hold    the pose captured on enable or where the last motion came to rest, at rest;
//   move    queued point-to-point moves (CartesianMove, cartesian_move.hpp), one after another;
//   paper   the paper's motion (68) about the position at which it started (PaperMotion);
//   stream  streamed setpoints through the jerk-limited follower (StreamFollower, stream.hpp);
// and stops any of them along its path (category 2): a move by its profiles' hardest stops, the
// paper's motion by a jerk-limited slow-down of its time, a stream by braking every axis together.
#pragma once

#include <cstdint>

#include "osc/control/cartesian_move.hpp"
#include "osc/control/excitation.hpp"
#include "osc/control/stream.hpp"
#include "osc/control/trajectory.hpp"

namespace osc {

/// The paper's motion (68) about p0, the tip position when it started (the measured pose: the
/// motion starts where the arm is), its time counted from the sample it started at.
template <class S>
struct PaperMotion {
  TrajectorySpec<S> spec;
  Vec3<S> p0;                    ///< the centre of (68): the tip position at the start [m]
  std::uint64_t start_tick = 0;  ///< the sample the motion started at
  /// The orientation it keeps, as coordinates relative to R_ref (0 in the paper's experiment, which
  /// starts at R_ref; after a move with a rotation, where that move left it).
  Vec3<S> phi0 = Vec3<S>::Zero();

  /// d at time t [s] since the start.
  Desired<S> at_time(S t) const {
    Desired<S> d = trajectory(spec, p0, t);
    d.x.template tail<3>() = phi0;
    return d;
  }
  /// The time since the start at sample `tick` of a clock of rate_hz samples per second, from the
  /// integer sample count (trajectory_time: exact over any uptime).
  S time_at_tick(std::uint64_t tick, std::uint32_t rate_hz) const {
    return trajectory_time<S>(spec, tick - start_tick, rate_hz);
  }
  /// d at sample `tick`.
  Desired<S> at_tick(std::uint64_t tick, std::uint32_t rate_hz) const { return at_time(time_at_tick(tick, rate_hz)); }
};

/// The category-2 stop of the paper's motion: its own time tau slowed from rate 1 to rest along a
/// jerk-limited profile (tau_dot from 1 to 0, |tau_ddot| <= kPaperStopRate, |tau_dddot| <=
/// kPaperStopJerk), so that the reference decelerates along the paper's path:
///   x = x(tau), x_dot = x'(tau) tau_dot, x_ddot = x''(tau) tau_dot^2 + x'(tau) tau_ddot.
/// (68)'s peak speed 0.063 m/s and acceleration 0.079 m/s^2 per axis bound the stop's reference to
/// 0.079 + 0.063 * 0.5 m/s^2 per axis.
constexpr double kPaperStopRate = 0.5;  ///< [1/s]: tau_dot falls from 1 to 0 in about 2 s
constexpr double kPaperStopJerk = 1.0;  ///< [1/s^2]

/// What a tick of the generator reports to the motion state machine (osc/runtime/motion_states.hpp).
struct MotionEvents {
  bool finished = false;  ///< the motion ended at rest with nothing queued (not after a stop)
  bool stopped = false;   ///< a category-2 stop reached rest
  /// A move that reached its target at rest in this tick, or a stream that ended and settled (its
  /// id; not a braked one).
  std::uint32_t done_id = 0;
};

enum class MotionSource : std::uint8_t { kHold, kMove, kPaper, kStream, kExcitation };

/// A tick of an identification run's excitation motion: its joint reference, and whether the motion is
/// at rest for good (its last period ended, or a brake reached rest).
template <class S>
struct ExcitationStep {
  JointSample<S> ref;
  bool at_rest_end = false;
};

template <class S>
class MotionGenerator {
 public:
  static constexpr int kQueueLength = params::kMoveQueueLength;
  /// Moves that can wait at once (not started): kQueueLength behind a running move, or every slot
  /// of the queue behind the paper's slow-down.
  static constexpr int kMaxWaiting = kQueueLength + 1;

  /// Holds `pose` (orientation coordinates relative to R_ref, the controller's), clears the queue.
  void hold(const Pose<S>& pose, const Mat3<S>& R_ref) {
    R_ref_ = R_ref;
    set_hold(pose);
    ++epoch_;
  }
  /// Starts the paper's motion at sample `tick` about the held position, keeping the orientation
  /// coordinates phi0 (the held ones: held_orientation(); the paper's experiment: 0, R_ref).
  void start_paper(const TrajectorySpec<S>& spec, std::uint64_t tick, std::uint32_t id = 0,
                   const Vec3<S>& phi0 = Vec3<S>::Zero()) {
    paper_ = {spec, hold_pose_.p, tick, phi0};
    paper_id_ = id;
    begin(MotionSource::kPaper);
  }
  /// Starts following a stream from the held pose at rest (its setpoints every `period` ticks; with
  /// `relative`, offsets from the held pose: prepare_setpoint), keeping `lim`.
  void start_stream(std::uint32_t period, bool relative, const CartesianLimits<S>& lim, std::uint32_t id,
                    std::uint32_t timeout_min = StreamFollower<S>::kTimeoutMinTicks) {
    stream_.set_limits(lim);
    stream_.start(hold_d_.x, period, timeout_min);
    stream_relative_ = relative;
    stream_id_ = id;
    begin(MotionSource::kStream);
  }
  /// Starts an identification run's excitation motion (osc/control/excitation.hpp: planned and checked about
  /// the joint angles where the arm holds) at sample `tick`. Its reference is in joint space
  /// (excitation_at); the runtime maps it to the controller's coordinates (excitation_reference,
  /// osc/runtime/motion_stage.hpp) and ends it there (excitation_end).
  void start_excitation(const ExcitationMotion<S>& m, std::uint64_t tick, std::uint32_t id) {
    excitation_ = m;
    excitation_id_ = id;
    excitation_start_ = tick;
    begin(MotionSource::kExcitation);
  }
  /// The excitation's joint reference at sample `tick`: its own, or, braking, its time slowed to rest
  /// along its path (as the paper's motion: q(tau), qd tau_dot, qdd tau_dot^2 + qd tau_ddot), which
  /// keeps to the positions and speeds the check passed (the path is one period's, repeated).
  ExcitationStep<S> excitation_at(std::uint64_t tick, std::uint32_t rate_hz) const {
    ExcitationStep<S> e;
    if (!braking_) {
      e.ref = excitation_.at_tick(tick - excitation_start_);
      e.at_rest_end = tick - excitation_start_ >= excitation_.ticks();
      return e;
    }
    const S t = math::ratio<S>(tick - start_tick_, rate_hz);
    const ProfileState<S> tau = stop_tau_.at(t);
    e.ref = excitation_.at(tau.p);
    e.ref.qdd = e.ref.qdd * (tau.v * tau.v) + e.ref.qd * tau.a;
    e.ref.qd = e.ref.qd * tau.v;
    e.at_rest_end = !(t < stop_tau_.duration());
    return e;
  }
  /// The excitation at rest for good at `d` (the controller's coordinates of its last reference): done
  /// (its last period; MotionEvents::done_id) or stopped (a brake), holding there.
  Desired<S> excitation_end(const Desired<S>& d, MotionEvents& ev) {
    if (!braking_) ev.done_id = excitation_id_;
    return end_at_rest({d.x.template head<3>(), Mat3<S>(rpy_rotation<S>(d.x.template tail<3>()) * R_ref_)},
                       d.x.template tail<3>(), ev);
  }
  /// A setpoint of the running stream (the follower's target x, in the controller's coordinates,
  /// with its rates v or none), for this tick; `end`: its last.
  void stream_setpoint(const Vec6<S>& x, bool end, const Vec6<S>* v = nullptr) {
    if (source_ != MotionSource::kStream) return;
    if (v)
      stream_.push(x, *v);
    else
      stream_.push(x);
    if (end) stream_.end();
  }
  /// The running stream has gone stale (no setpoint for max(2 periods, 20 ms), not ended, not
  /// braking): the runtime stops it (category 2, stale_stream).
  bool stream_stale() const { return source_ == MotionSource::kStream && !braking_ && stream_.stale(); }
  /// A running stream's stop lead (StreamFollower::stop_lead); none for any other motion (a move's
  /// and the paper's paths are checked before they start) and once braking.
  StopLead<S> stream_stop_lead() const {
    return source_ == MotionSource::kStream && !braking_ ? stream_.stop_lead() : StopLead<S>{};
  }
  /// The running stream's setpoints are offsets from the held pose.
  bool stream_relative() const { return stream_relative_; }
  /// Appends a move planned from queue_end() (CartesianMove::plan). false: the queue is full. While
  /// the paper's motion runs, brake() it first: the moves start where its slow-down ends.
  bool push(const CartesianMove<S>& m, std::uint32_t id = 0) {
    if (queue_full()) return false;
    queue_[(head_ + count_) % kQueueSlots] = m;
    ids_[(head_ + count_) % kQueueSlots] = id;
    ++count_;
    return true;
  }
  /// Where the next move pushed starts: the last queued move's end (the running one's, or where its
  /// brake ends), where the paper's slow-down ends, or the held pose.
  Pose<S> queue_end() const {
    if (count_ > 0) return queue_[(head_ + count_ - 1) % kQueueSlots].end();
    if (source_ == MotionSource::kPaper) return paper_pose(stop_tau_.target());
    return hold_pose_;
  }
  /// Where the running motion would come to rest if brake() ran at sample `tick` (the start of a
  /// re-target's move), or comes to rest when it brakes already (the moves waiting behind it are not
  /// counted: brake() drops them); the held pose when holding.
  Pose<S> brake_end(std::uint64_t tick, std::uint32_t rate_hz, const CartesianLimits<S>& lim) const {
    if (source_ == MotionSource::kMove) {
      if (braking_) return queue_[head_].end();
      CartesianMove<S> m = queue_[head_];
      m.stop(math::ratio<S>(tick - start_tick_, rate_hz), lim);
      return m.end();
    }
    if (source_ == MotionSource::kPaper)
      return paper_pose(braking_ ? stop_tau_.target() : paper_slow_down(tick, rate_hz).target());
    return queue_end();  // holding; a stream is not re-targeted (a move while it runs is busy)
  }
  /// Counts the changes of queue_end() other than a push (hold, paper, brake, stop; a motion that
  /// comes to rest ends where queue_end() said it would): a move planned
  /// from queue_end() under one epoch is pushed only under the same one.
  std::uint32_t epoch() const { return epoch_; }
  /// No room for another move: the running one and kQueueLength waiting.
  bool queue_full() const { return count_ >= kQueueSlots; }
  /// Starts the queued moves at sample `tick` (from the held pose, at rest).
  void start_moves(std::uint64_t tick) {
    if (source_ != MotionSource::kHold || count_ == 0) return;
    source_ = MotionSource::kMove;
    start_tick_ = tick;
  }
  /// Decelerates the running motion along its path from sample `tick` on and drops the moves
  /// waiting (waiting_ids() names them): a move by its profiles' hardest stops, the paper's motion by
  /// slowing its time. Moves pushed afterwards start where it comes to rest (brake_end(): a
  /// re-target); with none, it ends in a hold (MotionEvents::finished). Already braking: the moves
  /// waiting are dropped, the brake goes on. Holding: nothing changes.
  void brake(std::uint64_t tick, std::uint32_t rate_hz, const CartesianLimits<S>& lim) {
    if (source_ == MotionSource::kHold) return;
    count_ = source_ == MotionSource::kMove ? 1 : 0;  // the running move stays (a paper's or a stream's are none)
    ++epoch_;
    if (braking_) return;
    const S t = math::ratio<S>(tick - start_tick_, rate_hz);
    if (source_ == MotionSource::kStream)
      stream_.stop();
    else if (source_ == MotionSource::kMove)
      queue_[head_].stop(t, lim);
    else if (source_ == MotionSource::kExcitation)
      stop_tau_ = slow_down(math::ratio<S>(tick - excitation_start_, rate_hz));
    else
      stop_tau_ = paper_slow_down(tick, rate_hz);
    start_tick_ = tick;
    braking_ = true;
  }
  /// The category-2 stop: brake(), and the motion ends in a hold (MotionEvents::stopped) whatever is
  /// pushed afterwards (the state machine refuses moves while stopping).
  void stop(std::uint64_t tick, std::uint32_t rate_hz, const CartesianLimits<S>& lim) {
    brake(tick, rate_hz, lim);
    if (source_ != MotionSource::kHold) stopping_ = true;
  }
  /// The category-0 stop (a fault): the running motion and the moves waiting dropped at once (name
  /// these first: waiting_ids()); nothing runs (queued() and running_id() 0) until the next hold(),
  /// and the pose held last stays the held one.
  void halt() {
    source_ = MotionSource::kHold;
    stopping_ = braking_ = false;
    count_ = 0;
    ++epoch_;
  }
  /// The ids of the moves waiting, not started (behind the running move, or behind the paper's
  /// slow-down), in queue order, into out (at most max of them); returns how many. A brake(), a
  /// stop(), a hold() and a halt() drop them.
  int waiting_ids(std::uint32_t* out, int max) const {
    int n = 0;
    for (int i = source_ == MotionSource::kMove ? 1 : 0; i < count_ && n < max; ++i)
      out[n++] = ids_[(head_ + i) % kQueueSlots];
    return n;
  }

  /// d at sample `tick`; reports a motion's end at rest (then holds where it ended).
  Desired<S> at_tick(std::uint64_t tick, std::uint32_t rate_hz, MotionEvents& ev) {
    if (source_ == MotionSource::kPaper) return paper_at(tick, rate_hz, ev);
    if (source_ == MotionSource::kHold) return hold_d_;
    if (source_ == MotionSource::kStream) return stream_at(ev);
    if (source_ == MotionSource::kExcitation) return hold_d_;  // in joint space: excitation_at
    S t = math::ratio<S>(tick - start_tick_, rate_hz);
    while (!(t < queue_[head_].duration())) {
      // The running move ended at rest: the next one starts from there in this tick.
      const Pose<S> end = queue_[head_].end();
      if (!braking_) ev.done_id = ids_[head_];
      head_ = (head_ + 1) % kQueueSlots;
      --count_;
      braking_ = false;
      if (count_ == 0 || stopping_) return end_at_rest(end, ev);
      start_tick_ = tick;
      t = S(0);
    }
    return queue_[head_].at(t);
  }

  MotionSource source() const { return source_; }
  bool stopping() const { return stopping_; }
  bool braking() const { return braking_; }
  int queued() const { return count_; }
  /// The id of the running motion (the running move's, the paper's, the stream's; 0 when holding).
  std::uint32_t running_id() const {
    if (source_ == MotionSource::kMove) return ids_[head_];
    if (source_ == MotionSource::kStream) return stream_id_;
    if (source_ == MotionSource::kExcitation) return excitation_id_;
    return source_ == MotionSource::kPaper ? paper_id_ : 0;
  }
  const Pose<S>& hold_pose() const { return hold_pose_; }
  /// The held orientation as the controller's coordinates (relative to R_ref).
  Vec3<S> held_orientation() const { return hold_d_.x.template tail<3>(); }
  const Mat3<S>& reference_orientation() const { return R_ref_; }

 private:
  /// A new source takes over the reference: no stop or brake pending, its own tick count.
  void begin(MotionSource source) {
    ++epoch_;
    source_ = source;
    stopping_ = braking_ = false;
    count_ = 0;
  }
  static constexpr int kQueueSlots = kQueueLength + 1;  // the running move and those waiting

  void set_hold(const Pose<S>& pose) { set_hold(pose, orientation_coordinates<S>(pose.R, R_ref_)); }
  /// Holds `pose`, whose orientation coordinates (relative to R_ref) are `phi`.
  void set_hold(const Pose<S>& pose, const Vec3<S>& phi) {
    hold_pose_ = pose;
    hold_d_.x << pose.p, phi;
    hold_d_.xd.setZero();
    hold_d_.xdd.setZero();
    source_ = MotionSource::kHold;
    stopping_ = braking_ = false;
    count_ = 0;
  }
  /// The motion came to rest at `end`: stopped (a stop) or finished, holding there.
  Desired<S> end_at_rest(const Pose<S>& end, MotionEvents& ev) {
    return end_at_rest(end, orientation_coordinates<S>(end.R, R_ref_), ev);
  }
  /// The same, the end's orientation coordinates given (`phi`).
  Desired<S> end_at_rest(const Pose<S>& end, const Vec3<S>& phi, MotionEvents& ev) {
    (stopping_ ? ev.stopped : ev.finished) = true;
    set_hold(end, phi);
    return hold_d_;
  }

  /// A motion's time slowed from rate 1 at its time t to rest (the paper's motion, an excitation).
  static JerkProfile<S> slow_down(S t) {
    JerkProfile<S> tau;
    tau.plan_stop(t, S(1), S(0), {S(1), lit<S>(kPaperStopRate), lit<S>(kPaperStopJerk)});
    return tau;
  }
  /// The slow-down of the paper's motion from sample `tick`: its time from rate 1 to rest.
  JerkProfile<S> paper_slow_down(std::uint64_t tick, std::uint32_t rate_hz) const {
    return slow_down(paper_.time_at_tick(tick, rate_hz));
  }
  /// The pose of the paper's motion at its time tau: (68) keeps the orientation it started with.
  Pose<S> paper_pose(S tau) const { return {paper_.at_time(tau).x.template head<3>(), hold_pose_.R}; }

  /// The stream's reference; it ends at rest where the follower is: stopped (brake(), stop()), or
  /// done (ended and settled: the last setpoint reached).
  Desired<S> stream_at(MotionEvents& ev) {
    const Desired<S> d = stream_.tick();
    const bool done = !braking_ && stream_.settled();
    if (!(braking_ ? stream_.stopped() : done)) return d;
    if (done) ev.done_id = stream_id_;
    // Holds exactly where the follower is (its coordinates, not their round trip through R).
    return end_at_rest({d.x.template head<3>(), Mat3<S>(rpy_rotation<S>(d.x.template tail<3>()) * R_ref_)},
                       d.x.template tail<3>(), ev);
  }

  Desired<S> paper_at(std::uint64_t tick, std::uint32_t rate_hz, MotionEvents& ev) {
    if (!braking_) return paper_.at_tick(tick, rate_hz);
    const S t = math::ratio<S>(tick - start_tick_, rate_hz);
    const ProfileState<S> tau = stop_tau_.at(t);
    Desired<S> d = paper_.at_time(tau.p);
    d.xdd = d.xdd * (tau.v * tau.v) + d.xd * tau.a;
    d.xd = d.xd * tau.v;
    if (t < stop_tau_.duration()) return d;
    // (68) keeps the orientation it started with (paper_pose, from d already evaluated).
    if (count_ == 0 || stopping_) return end_at_rest({d.x.template head<3>(), hold_pose_.R}, ev);
    // Moves pushed while braking start here, at rest.
    source_ = MotionSource::kMove;
    braking_ = false;
    start_tick_ = tick;
    return queue_[head_].at(S(0));
  }

  MotionSource source_ = MotionSource::kHold;
  bool stopping_ = false, braking_ = false;
  Pose<S> hold_pose_{Vec3<S>::Zero(), Mat3<S>::Identity()};
  Desired<S> hold_d_{};
  Mat3<S> R_ref_ = Mat3<S>::Identity();
  PaperMotion<S> paper_{};
  JerkProfile<S> stop_tau_;
  CartesianMove<S> queue_[kQueueSlots];
  std::uint32_t ids_[kQueueSlots] = {};
  std::uint32_t paper_id_ = 0;
  ExcitationMotion<S> excitation_{};
  std::uint32_t excitation_id_ = 0;
  std::uint64_t excitation_start_ = 0;
  StreamFollower<S> stream_;
  std::uint32_t stream_id_ = 0;
  bool stream_relative_ = false;
  int head_ = 0, count_ = 0;
  std::uint64_t start_tick_ = 0;
  std::uint32_t epoch_ = 0;
};

}  // namespace osc
