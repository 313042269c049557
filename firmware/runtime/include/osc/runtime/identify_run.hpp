// An identification run's estimate (issue 57; docs/adaptation.md, "The identify command"): the tick's
// side (IdentifySampler, in the task: the run's filter at 1 kHz and a sample every
// params::kRunSampleTicks into a mailbox) and the main loop's (IdentifyRun: each sample's regression
// rows into the weighted least squares of osc/control/identify_estimate.hpp, and the report at the end).
//
// The regression of a sample (identify_estimate.hpp's file comment), per joint i:
//   y_i = F tau_i - tau_rb,i(q_f, qd_f, qdd_f) = w_i^T theta_i + Y_i pi,
// tau the torque the controller commanded, tau_rb the model's rigid-body torque (rnea, armature included) at
// the filtered angles and their derivatives, w_i the filtered friction columns, Y the payload regressor
// (osc/kernels/payload.hpp) there. With the payload estimated the model is the arm's own, link 6 without
// the payload parameters set (so that pi is the whole payload, not a correction to the one set); without,
// the model as it is, the payload set included, and the friction alone is estimated. A joint's row is left out
// about its reversals (identify::moving_rows, params::kIdentifyMinRowSpeed says why).
//
// The drives' space. On an arm whose drive train couples the joints (the PUMA's wrist: q = C e, e the motors'
// angles referred to their joints; osc/runtime/io.hpp), each motor has its own friction and rotor, at its own rate
// e' = C^-1 q'. The regression is then written per motor: the rows C^T y (the motors' torques), the friction and
// armature columns at the motors' rates and accelerations (the sampler filters e', which F keeps linear: the joints'
// q_f' = C e_f'), and the payload's rows C^T Y. Each motor's row is again its own coefficients' alone, and the
// coefficients are the drives' (the joints' on an uncoupled arm, where C = I). On the simulated PUMA with the wrist
// coupled, J5's torque-prediction error was 29 % in the joints' space and is 2.4 % in the drives'.
//
// Pairing. The torque commanded in tick n acts from the DAC's update (params::kActuationDelay after the
// sample) to the next one; the angle of tick n is sampled at its start. Fed with the angle of tick n, the
// torque of tick n lags it by about 0.7 ms; the torque of tick n - 1 leads it by about 0.3 ms. The
// sampler filters the angle of tick n with the torque of tick n - 1.
//
// The mailbox is one sample and a count (a sequence lock): the tick writes both; the main loop copies the
// sample between two reads of the count and keeps the copy when they agree (the tick pre-empts the main
// loop, never the reverse). A sample the main loop was too slow for is counted lost (IdentifyRun::lost).
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
}  // namespace params

/// The tick's side of a run: filters every tick of the run's motion, a sample every kRunSampleTicks.
template <class S>
struct IdentifySampler {
  IdentifyFilter<S> filter;
  IdentifySignals<S> sample{};   // the newest sample (the mailbox)
  volatile std::uint32_t count;  // samples put since the run started (odd: none yet is no state)
  std::uint32_t run_id;          // the run being filtered (0: none since the last reset)
  std::uint32_t ticks;           // ticks of the run filtered
  Vec6<S> tau_before;            // the torque commanded the tick before

  void reset() {
    count = 0;
    run_id = 0;
    ticks = 0;
  }
  /// One tick of run `id`: q measured, tau the step's torque, qd the observed motors' rates (C^-1 of the joints':
  /// motor_rates), dec the friction model's Stribeck decay. The first tick of a run primes the filter (the motion
  /// starts at rest).
  void tick(std::uint32_t id, const Vec6<S>& q, const Vec6<S>& tau, const Vec6<S>& qd, const Vec6<S>& dec) {
    if (id != run_id) {
      run_id = id;
      ticks = 0;
      count = 0;
      filter.prime(q, tau, qd, dec);
      tau_before = tau;
    }
    filter.update(q, tau_before, qd);
    tau_before = tau;
    if (++ticks % params::kRunSampleTicks != 0) return;
    sample = filter.signals();
    count = count + 1;
  }
};

/// The main loop's side of a run: the estimate's sums, the samples taken, the report.
template <class S>
class IdentifyRun {
 public:
  /// A run `id` starts: the estimate cleared, the payload's entries `payload` (payload_mask) estimated too, and
  /// every drive's armature correction. bare: the arm's model without a payload (the task's own with
  /// payload_empty), for the payload's run. io: the drive train's coupling (the task's; none: uncoupled).
  void start(std::uint32_t id, std::uint16_t payload, const Model<S>& model, const Model<S>& bare,
             const IoMap<S>* io = nullptr) {
    coupled_ = io != nullptr && io->coupled();
    if (coupled_) io_ = *io;
    id_ = id;
    taken_ = 0;
    lost_ = 0;
    estimate_.reset(payload, identify::kAllRows);
    model_ = payload != payload_mask::kNone ? bare : model;
    with_payload_ = payload != payload_mask::kNone;
  }
  /// The sampler's newest sample into the estimate, if it is new and whole: true when one was taken.
  bool poll(const IdentifySampler<S>& sampler) {
    if (sampler.run_id != id_ || id_ == 0) return false;
    const std::uint32_t before = sampler.count;
    if (before == taken_) return false;
    const IdentifySignals<S> s = sampler.sample;
    if (sampler.count != before) return false;  // the tick wrote meanwhile: the next call takes the newer
    lost_ += before - taken_ - 1;
    taken_ = before;
    add(s);
    return true;
  }
  /// The report of the run (the estimate's solve, with the filter's correlation factor).
  IdentifyReport finish() { return estimate_.solve(identify::noise_correlation_factor(params::kRunSampleTicks)); }
  std::uint32_t id() const { return id_; }
  /// The samples summed, and those the tick put that the main loop missed (its polls too far apart).
  std::uint32_t taken() const { return taken_ - lost_; }
  std::uint32_t lost() const { return lost_; }

 private:
  /// A sample's rows, in the drives' space (the file comment): s.qd and s.qdd are the motors'.
  void add(const IdentifySignals<S>& s) {
    const Vec6<S> qd = joint(s.qd), qdd = joint(s.qdd);
    forward_kinematics(model_, data_, s.q);
    const Vec6<S> y = motors(Vec6<S>(s.tau - rnea(model_, data_, qd, qdd, true).tau));
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
  Model<S> model_{};
  Data<S> data_{};
  std::uint32_t id_ = 0, taken_ = 0, lost_ = 0;  // taken_: the sampler's count at the last sample taken
  bool with_payload_ = false;
  bool coupled_ = false;
  IoMap<S> io_{};  // the drive train's coupling, where coupled_
};

}  // namespace osc
