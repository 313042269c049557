// An identification run's estimate (issue 57; docs/adaptation.md, "The identify command"): the tick's
// side (IdentifySampler, in the task: each tick of the run's raw signals into a ring) and the main loop's
// (IdentifyRun: the run's filter over the ring's ticks, a sample every params::kRunSampleTicks, each sample's
// regression rows into the weighted least squares of osc/control/identify_estimate.hpp, and the report at the end).
//
// The regression of a sample (identify_estimate.hpp's file comment), per joint i:
//   y_i = F tau_i - tau_rb,i(q_f, qd_f, qdd_f) = w_i^T theta_i + dI_i qdd_i - b_i + Y_i pi,
// tau the torque the controller commanded, tau_rb the model's rigid-body torque (rnea, armature included) at
// the filtered angles and their derivatives, w_i the filtered friction columns, dI_i the drive's armature correction,
// b_i the torque its drive adds to the one commanded (an amplifier's offset; a constant through F, whose DC gain is
// 1), Y the payload regressor (osc/kernels/payload.hpp) there. With the payload estimated the model is the arm's own,
// link 6 without the payload parameters set (so that pi is the whole payload, not a correction to the one set);
// without, the model as it is, the payload set included, and the friction alone is estimated. A joint's row is left out
// about its reversals (identify::moving_rows, params::kIdentifyMinRowSpeed says why).
//
// The drives' space. On an arm whose drive train couples the joints (the PUMA's wrist: q = C e, e the motors'
// angles referred to their joints; osc/runtime/io.hpp), each motor has its own friction and rotor, at its own rate
// e' = C^-1 q'. The regression is then written per motor: the rows C^T y (the motors' torques), the friction and
// armature columns at the motors' rates and accelerations (the sampler records e', which F keeps linear: the joints'
// q_f' = C e_f'), and the payload's rows C^T Y. Each motor's row is again its own coefficients' alone, and the
// coefficients are the drives' (the joints' on an uncoupled arm, where C = I). On the simulated PUMA with the wrist
// coupled, J5's torque-prediction error was 29 % in the joints' space and is 2.4 % in the drives'.
// The rotors. The model's armature holds each drive's G^2 J_m (with its correction) on A(q)'s diagonal, but coupled
// rotors turn at e' = C^-1 q': their inertia in the joints' space is C^-T D C^-1, and in the drives' space D itself,
// diagonal. So on a coupled arm the regression takes the links' torque from rnea without the armature, and each
// motor's rotor torque D_k e_k'' in its own row (rotors_): the armature column's correction is then a correction
// to D_k alone. Fed the plant's own angles and rates, the coupled run's worst coefficient is 0.61 of issue 57's bar
// with this, 1.66 with the diagonal armature (J5's prediction error 1.7 %; test_identify_sim, "*PlantsOwnSignals*").
//
// Pairing. The torque commanded in tick n acts from the DAC's update (params::kActuationDelay after the
// sample) to the next one; the angle of tick n is sampled at its start. Fed with the angle of tick n, the
// torque of tick n lags it by about 0.7 ms; the torque of tick n - 1 leads it by about 0.3 ms. The
// sampler records the angle of tick n with the torque of tick n - 1.
//
// The ring. The filter (osc/control/identify_filter.hpp: 30 channels of two updates and six exponentials a tick) is
// the main loop's, not the tick's: the tick writes three vectors into a ring of params::kRunRingTicks entries and
// counts it, and the main loop filters every entry it has not yet read (the tick pre-empts the main loop, never the
// reverse: an entry it read is checked still unwritten after the read). A main loop that falls more than the ring
// behind loses the entries overwritten: the filter starts again at the oldest entry left (primed there, as at rest)
// and takes no sample for params::kRunSettleTicks, and the samples not taken are counted lost (IdentifyRun::lost).
// Lockstep boards (the virtual board, the QEMU images) read after every tick.
#pragma once

#include <cstdint>

#include "osc/control/identify_estimate.hpp"
#include "osc/control/identify_filter.hpp"
#include "osc/kernels/dynamics.hpp"
#include "osc/kernels/payload.hpp"
#include "osc/runtime/io.hpp"

namespace osc {

namespace params {
/// A sample of the run every 5 ticks (200 Hz): 16 000 over the 80 s, at most a 40th of the filter's
/// bandwidth apart; the samples' noise is correlated through the filter, which the estimate's factor
/// identify::noise_correlation_factor(kRunSampleTicks) (12.7) accounts for.
constexpr unsigned kRunSampleTicks = 5;
/// The ring of the run's ticks between the tick and the main loop: 64 ms of slack for the main loop (a lockstep
/// board reads after every tick; a timer-paced one's main loop runs between its ticks).
constexpr unsigned kRunRingTicks = 64;
/// After a gap (entries overwritten before the main loop read them) the filter starts again primed at rest and
/// takes no sample for this many ticks: eight of its time constants (1 / kIdentifyFilterOmega = 16 ms), where the
/// prime's error has fallen below 3e-3 of itself.
constexpr unsigned kRunSettleTicks = 128;
}  // namespace params

/// One tick of a run as the tick saw it: the measured angles, the torque commanded the tick before, the observed
/// motors' rates.
template <class S>
struct IdentifyTick {
  Vec6<S> q, tau, qd;
};

/// The tick's side of a run: each tick's signals into the ring (the file comment's "The ring").
template <class S>
struct IdentifySampler {
  IdentifyTick<S> ring[params::kRunRingTicks];
  volatile std::uint32_t ticks;  // ticks of the run recorded (the next entry: ticks % kRunRingTicks)
  std::uint32_t run_id;          // the run being recorded (0: none since the last reset)
  Vec6<S> dec;                   // the friction model's Stribeck decays at the run's first tick (the filter's prime)
  Vec6<S> tau_before;            // the torque commanded the tick before
  // A run's accept and end, for a main loop that does not see every tick (osc/link/identify_port.hpp): the tick
  // writes each event's fields before its count.
  std::uint32_t accepted_id;        // the identify command accepted last
  std::uint16_t accepted_payload;   // ... and the payload's entries it estimates too (payload_mask)
  volatile std::uint32_t accepted;  // identify commands accepted since the reset
  volatile std::uint32_t ended;     // the run (its `accepted` count) whose end was reported last; 0: none
  bool ended_done;                  // that end: done (its motion complete), else aborted

  void reset() {
    ticks = 0;
    run_id = 0;
    accepted_id = 0;
    accepted_payload = payload_mask::kNone;
    accepted = 0;
    ended = 0;
    ended_done = false;
  }
  /// An identify command `id` accepted, estimating the payload's entries `payload` (payload_mask) too: its run starts
  /// at the next tick it records, whatever the id.
  void accept(std::uint32_t id, std::uint16_t payload = payload_mask::kNone) {
    ticks = 0;
    run_id = 0;
    accepted_id = id;
    accepted_payload = payload;
    accepted = accepted + 1;
  }
  /// The tick's report of the motions it ended (MotionReport's done_id and aborted_id): the accepted run's end, once.
  void note_end(std::uint32_t done_id, std::uint32_t aborted_id) {
    if (accepted == 0 || ended == accepted || (done_id != accepted_id && aborted_id != accepted_id)) return;
    ended_done = done_id == accepted_id;
    ended = accepted;
  }
  /// One tick of run `id`: q measured, tau the step's torque, qd the observed motors' rates (C^-1 of the joints':
  /// motor_rates), dec the friction model's Stribeck decay. The first tick of a run starts its count (the motion
  /// starts at rest: its torque is the tick before's too).
  void tick(std::uint32_t id, const Vec6<S>& q, const Vec6<S>& tau, const Vec6<S>& qd, const Vec6<S>& dec_now) {
    if (id != run_id) {
      run_id = id;
      ticks = 0;
      dec = dec_now;
      tau_before = tau;
    }
    const std::uint32_t n = ticks;
    IdentifyTick<S>& e = ring[n % params::kRunRingTicks];
    e.q = q;
    e.tau = tau_before;
    e.qd = qd;
    tau_before = tau;
    ticks = n + 1;
  }
};

/// The main loop's side of a run: the estimate's sums, the samples taken, the report.
template <class S>
class IdentifyRun {
 public:
  /// A run `id` starts: the estimate cleared, the payload's entries `payload` (payload_mask) estimated too, and
  /// every drive's armature correction and torque offset. bare: the arm's model without a payload (the task's own with
  /// payload_empty), for the payload's run. io: the drive train's coupling (the task's; none: uncoupled).
  void start(std::uint32_t id, std::uint16_t payload, const Model<S>& model, const Model<S>& bare,
             const IoMap<S>* io = nullptr) {
    coupled_ = io != nullptr && io->coupled();
    if (coupled_) io_ = *io;
    id_ = id;
    taken_ = 0;
    lost_ = 0;
    next_ = 0;
    restart_at_ = 0;
    settled_ = 0;
    estimate_.reset(payload, identify::kAllRows, identify::kAllRows);
    model_ = payload != payload_mask::kNone ? bare : model;
    with_payload_ = payload != payload_mask::kNone;
    rotors_ = model_.armature;
    if (coupled_) model_.armature.setZero();
  }
  /// The ring's ticks of this run not read yet, through the run's filter, a sample into the estimate every
  /// params::kRunSampleTicks (the file comment's "The ring"): the samples taken in this call.
  int poll(const IdentifySampler<S>& sampler) {
    if (sampler.run_id != id_ || id_ == 0) return 0;
    int took = 0;
    for (;;) {
      const std::uint32_t end = sampler.ticks;
      if (next_ == end) return took;
      if (end - next_ > params::kRunRingTicks) restart(end - params::kRunRingTicks);  // a gap: entries overwritten
      const IdentifyTick<S> e = sampler.ring[next_ % params::kRunRingTicks];
      if (sampler.ticks - next_ > params::kRunRingTicks) continue;  // overwritten while it was copied: a gap
      took += step(e, sampler.dec);
    }
  }
  /// The report of the run (the estimate's solve, with the filter's correlation factor).
  IdentifyReport finish() { return estimate_.solve(identify::noise_correlation_factor(params::kRunSampleTicks)); }
  std::uint32_t id() const { return id_; }
  /// The payload's entries the run estimates (payload_mask).
  std::uint16_t payload() const { return estimate_.mask(); }
  /// The run's filter (its newest outputs: filter().signals()).
  const IdentifyFilter<S>& filter() const { return filter_; }
  /// The samples summed, and those a gap cost (the main loop's polls more than the ring apart).
  std::uint32_t taken() const { return taken_; }
  std::uint32_t lost() const { return lost_; }

 private:
  /// One tick of the ring through the filter (primed at the run's first tick and after a gap); 1 when it took a
  /// sample.
  int step(const IdentifyTick<S>& e, const Vec6<S>& dec) {
    if (next_ == restart_at_) filter_.prime(e.q, e.tau, e.qd, dec);
    filter_.update(e.q, e.tau, e.qd);
    ++next_;
    if (next_ % params::kRunSampleTicks != 0) return 0;
    if (next_ < settled_) {
      ++lost_;
      return 0;
    }
    add(filter_.signals());
    ++taken_;
    return 1;
  }
  /// The ticks before `from` are gone: their samples lost, the filter primed again at `from`, no sample until it
  /// settles.
  void restart(std::uint32_t from) {
    lost_ += from / params::kRunSampleTicks - next_ / params::kRunSampleTicks;
    next_ = from;
    restart_at_ = from;
    settled_ = from + params::kRunSettleTicks;
  }
  /// A sample's rows, in the drives' space (the file comment): s.qd and s.qdd are the motors'.
  void add(const IdentifySignals<S>& s) {
    const Vec6<S> qd = joint(s.qd), qdd = joint(s.qdd);
    forward_kinematics(model_, data_, s.q);
    Vec6<S> y = motors(Vec6<S>(s.tau - rnea(model_, data_, qd, qdd, true).tau));
    if (coupled_) y -= rotors_.cwiseProduct(s.qdd);
    const std::uint8_t rows = identify::moving_rows(s.qd);  // each drive away from its reversals
    if (!with_payload_) return estimate_.add(y, s.w, rows, s.qdd);
    geometric_jacobian(data_);
    PayloadRegressor<S> Y = payload_regressor(model_, data_, qd, qdd);
    for (int k = 0; k < Y.cols() && coupled_; ++k) Y.col(k) = motor_torques(io_, Vec6<S>(Y.col(k)));
    estimate_.add(y, s.w, Y, rows, s.qdd);
  }
  Vec6<S> joint(const Vec6<S>& motor) const { return coupled_ ? joint_from_motor(io_, motor) : motor; }
  Vec6<S> motors(const Vec6<S>& tau) const { return coupled_ ? motor_torques(io_, tau) : tau; }

  IdentifyEstimate estimate_;
  IdentifyFilter<S> filter_;
  Model<S> model_{};
  Data<S> data_{};
  std::uint32_t id_ = 0, taken_ = 0, lost_ = 0;
  std::uint32_t next_ = 0;        // the run's next tick to read from the ring
  std::uint32_t restart_at_ = 0;  // the tick the filter was last primed at (the run's first, or after a gap)
  std::uint32_t settled_ = 0;     // no sample before this tick (a gap's filter settling)
  bool with_payload_ = false;
  bool coupled_ = false;
  IoMap<S> io_{};                     // the drive train's coupling, where coupled_
  Vec6<S> rotors_ = Vec6<S>::Zero();  // each drive's rotor inertia D_k (the model's armature), where coupled_
};

}  // namespace osc
