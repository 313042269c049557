// The residual monitor (ResidualMonitor; docs/safety.md, "The residual monitor"): the torque the
// model does not explain, filtered per joint, against thresholds derived from the arm's stated error
// bounds, and the travel check beside it. Run by control_tick() after the control step
// (osc/runtime/monitors.hpp). Its parts: the arm's constants and its input from the step
// (osc/runtime/residual_constants.hpp), the type and its per-tick check (here), each joint's bound and
// thresholds (osc/runtime/residual_thresholds.hpp) and the travel check
// (osc/runtime/residual_travel.hpp), those two included at the end of this header.
#pragma once

#include <cstdint>

#include "osc/control/controller.hpp"
#include "osc/control/identification.hpp"
#include "osc/runtime/drive_monitor.hpp"
#include "osc/runtime/encoder_monitors.hpp"
#include "osc/runtime/io.hpp"
#include "osc/runtime/payload_check.hpp"
#include "osc/runtime/residual_constants.hpp"

namespace osc {

/// encoder_stuck, drive_fault, collision: a generalised-momentum residual (De Luca and Mattone; Haddadin, De Luca
/// and Albu-Schaeffer 2017) in its sampled, acceleration-free form. Per joint, the torque the model does not
/// explain, A(q) q^dot' + c + g + tau_f^ - tau, through a first-order filter of bandwidth K =
/// params::kResidualGain:
///   r_k = (1 - K dt) r_{k-1} + K [A_k (q^dot_k - q^dot_{k-1}) + dt (n_{k-1} - tau_{k-1})],
/// n = c + g + tau_f^, tau_{k-1} the torque applied over the last period, q^dot the observer's (no numerical
/// differentiation: the velocity difference is integrated). On a healthy arm r is the model's error, and each
/// joint's threshold bounds it from the arm's stated error bounds (robot::kModelErrorBounds): friction (a still
/// joint: anywhere in its static band; a moving one: the band's distance from theta^), link inertia, motor inertia,
/// the amplifiers, and the encoder quantum through the velocity estimate (docs/safety.md derives each term). r is
/// updated every tick, the thresholds on the monitor's turns (every params::kResidualTurnEvery ticks: turn_pass())
/// and held between. A residual beyond its threshold for params::kResidualQualifyTicks ticks in a row is a fault,
/// isolated by joint and kind:
///  - encoder_stuck: an encoder of the joint fell silent at once while its joint was counting (for more than
///    params::kStuckIntervals of its recent intervals between counts);
///  - with the drives checked (a HAL with current readback: DriveMonitor), drive_fault where the drive check
///    suspects the joint's drive, else collision (isolation by order: docs/safety.md, "The drive check");
///  - without: drive_fault when the residual is on this drive alone (every other joint below half its threshold);
///    collision: an external torque on several joints, as a contact gives.
/// Beside the residual, the travel check (travel()): a joint whose least motion since its encoder's last count,
/// from the torque applied and the same bounds, passes params::kResidualTravelCounts counts must have counted; it
/// is a fault at once (classify_travel() names it).
template <class S>
struct ResidualMonitor {
  /// The model error's regressors, each filtered as r, then slowly (the change channel): the
  /// friction model's three columns, gravity, the Coriolis torque, the applied torque and its size.
  enum Regressor { kVis, kCou, kSti, kEstimate, kGravity, kCoriolis, kTorque, kTorqueSize, kRegressors };
  /// One joint's friction against the band (robot::kModelErrorBounds): sliding, the band's distance
  /// from theta^ per coefficient; not sliding, the static band's extent plus |tau_f^| (still).
  struct FrictionError {
    S th_v, th_c, th_s;  // theta^'s coefficients of the joint (0 without compensation)
    S dv, dc, ds, still;
    bool moving;   // its direction known: counting one way, q^dot beyond its noise and lag
    bool sliding;  // ... and counting fast enough that its friction is on the model's curve
  };

  Vec6<S> r;                             // the residual [N m]
  Vec6<S> bound;                         // the model-error bound's filtered pointwise terms [N m]
  Vec6<S> acc;                           // the joint accelerations, filtered as r [rad/s^2]
  Vec6<S> threshold;                     // this tick's thresholds [N m]
  Vec6<S> d;                             // the change residual r - r_slow [N m]
  Vec6<S> change_threshold;              // its thresholds [N m]
  Vec6<S> r_slow, acc_slow;              // r and acc through the slow filter (params::kResidualSlowGain)
  Vec6<S> reg[kRegressors];              // the regressors filtered as r
  Vec6<S> reg_slow[kRegressors];         // ... then slowly
  Vec6<S> stillness;                     // 1 while a joint does not move, then decaying at the slow rate
  Vec6<S> qd_prev, bias_prev, tau_prev;  // the previous step's q^dot and n, the torque applied since
  Vec6<S> qd_turn;                       // q^dot at the last turn (check())
  Vec6<S> r_last, tau_last;              // r of the step before, the torque applied the period before tau_prev's
  Vec6<S> travel_error;                  // the travel check's bound on the model's error, from the last turn [N m]
  Vec6<S> velocity_noise;                // the velocity estimate's quantisation noise per joint [rad/s] (wrist_noise())
  Vec6<S> noise_base;    // set-up: ... through its own row, its quantum times k_max / 2 (J5: and the arm's share)
  S wrist_mix;           // set-up: the gains' spread times the arm's quanta / 2 (wrist_noise()) [rad/s]
  Vec6<S> half_quantum;  // set-up: the encoders' quanta / 2 [rad] (mixed_noise())
  Vec6<S> pose_noise;    // set-up: k times the pose's rounding, 0 but in fixed point [m/s, rad/s] (mixed_noise())
  Vec6<S> gain_excess;   // set-up: the observer's gains k less their least, k_min [1/s] (mixed_noise())
  Vec6<S> cross_friction = Vec6<S>::Zero();  // set-up: the other motors' static friction a coupling adds [N m]
  /// Each joint's floor of the model's error: amplifier offset, cross_friction, in contact |r| at its start [N m].
  Vec6<S> error_floor = Vec6<S>::Zero();
  S k_max, k_min, lag;             // set-up: the observer's largest gain, its least, 1 / its least [1/s, s]
  Vec6<S> peak_ratio;              // the largest |r| / threshold seen per joint
  EncoderActivity activity;        // each encoder's changes
  std::uint8_t over[kDof];         // consecutive ticks beyond the threshold
  std::uint64_t over_since[kDof];  // the tick the current run of them began
  std::uint32_t detected;          // the first detection's fault (kept while not armed too)
  std::uint64_t detected_tick;     // ... its tick
  std::int8_t joint;               // ... its joint (0-based), -1 none
  bool primed;                     // a previous step is on record
  std::uint64_t primed_at = 0;     // the tick it primed at (an enable): payload_mismatch's window
  FlangeWeight<S> flange{};        // the first detection's residual as a weight at the flange (payload_check.hpp)
  /// Its detections are faults, in place of StuckEncoderMonitor's (else only recorded).
  bool armed = params::kResidualMonitorArmed;
  /// The user's collision thresholds [N m] (ControlTask::set_collision): a collision is reported
  /// only once some joint's qualified residual is beyond its own too; 0, the default, leaves the derived
  /// thresholds alone. They never lower a derived threshold, nor touch the sensor and drive faults.
  Vec6<S> collision_floor = Vec6<S>::Zero();
  /// The friction identification's sample (osc/control/identification.hpp): the joint whose sample
  /// the next check takes (-1: none), and the sample it took.
  int sample_joint = -1;
  FrictionSample<S> sample{};
  Vec6<S> noise_bound;  // this tick's bound on the velocity estimate's quantisation noise in r [N m]
  /// The travel check (travel()), one way: per joint, lower bounds on its speed and on its travel
  /// that way since its encoder's last count [rad/s, rad], and the least drive that way over the ticks
  /// of the check's current step [N m] (the torque may alternate tick by tick, the friction
  /// compensation's sign term at a joint that hunts about rest, and the step holds for a turn,
  /// params::kResidualTurnEvery ticks, not only its last).
  struct Way {
    Vec6<S> v, p, drive;
  };
  /// ahead: the way of the encoder's last count, toward its next edge; back: against it, toward the
  /// edge it just crossed (a joint that reverses must count back).
  Way ahead, back;
  /// Per joint: the travel that must have made it count (kResidualTravelCounts quanta; 0: the check is
  /// off, a joint whose encoder reads other joints too), and the largest least travel seen either way
  /// (the check's peak; against travel_limit, its headroom).
  Vec6<S> travel_limit, travel_peak;
  static constexpr S kNoDrive = lit<S>(1000);  // none yet this step [N m]
  /// Set-up: each encoder's least and largest edge spacing, quantum -+ 2 encoder_edge quanta [rad at the joint].
  Vec6<S> spacing_lo, spacing_hi;
  /// Set by the task each tick: the arm yields, or holds against a contact it reacted to, whose
  /// force the model does not know: the travel check waits (it restarts every tick).
  bool contact = false;
  bool contact_noted = false;  // the contact error_floor holds (note_contact())
  S allowance_mass = S(0);     // the payload allowance [kg] (set_allowance()); each joint's torque of it [N m], its
  Vec6<S> allowance = Vec6<S>::Zero(), allowance_reach = Vec6<S>::Zero();  // farthest lever over g [s^2]
  /// Set by the task each tick: the arm holds a pose, no motion commanded (MotionState::kHolding).
  bool holding = false;
  bool held = false;  // ... at every step since the prime: a stuck encoder has had nothing to show (decide())
  /// Set by the task on a HAL with current readback (DriveMonitor): the drive check ran, the channels it suspects.
  bool drives_checked = false;
  std::uint8_t drive_suspect = 0;
  std::int32_t primed_counts[kDof] = {};  // the encoders' readings at the prime (off_reference())

  /// The encoders' quantum [rad at each joint] and the observer's gains k: the velocity estimate q^dot =
  /// J^-1 (y + k x~) carries each encoder's quantisation error (within half a count of its mean) times the largest k.
  /// With a coupled drive train (inverse = C^-1, the identity without one), each motor's friction
  /// reaches joint i as C^-T f_m: the model's per-joint friction leaves out the other motors'
  /// shares, sum over c != i of |C^-1_ci| times their static band, which a reversal of motor c flips.
  void set(const Vec6<S>& quantum, const Vec6<S>& k, const double (&inverse)[kDof][kDof]) {
    k_max = k.maxCoeff();
    k_min = k.minCoeff();
    lag = S(1) / k_min;
    wrist_mix = lit<S>(0.5) * (k_max - k_min) * (quantum(0) + quantum(1) + quantum(2));
    velocity_noise = noise_base = (lit<S>(0.5) * k_max) * quantum;
    if constexpr (kArmSphericalWrist) velocity_noise(4) = noise_base(4) += wrist_mix;  // J5's share (wrist_noise())
    half_quantum = lit<S>(0.5) * quantum;
    pose_noise = kResidualConstants<S>.pose_rounding * k;
    gain_excess = k - Vec6<S>::Constant(k_min);
    const ModelErrorBounds& b = robot::kModelErrorBounds;
    for (int i = 0; i < kDof; ++i) {
      double cross = 0;
      bool alone = true;  // encoder i reads joint i alone
      for (int c = 0; c < kDof; ++c) {
        if (c != i) cross += abs_of(inverse[c][i]) * (b.friction_hi.cou[c] + b.friction_hi.sti[c]);
        if (c != i && inverse[i][c] != 0) alone = false;
      }
      cross_friction(i) = lit<S>(cross);
      error_floor(i) = rest_floor(i);
      travel_limit(i) = alone ? lit<S>(params::kResidualTravelCounts) * quantum(i) : S(0);
      spacing_lo(i) = lit<S>(1 - 2 * b.encoder_edge) * quantum(i);
      spacing_hi(i) = lit<S>(1 + 2 * b.encoder_edge) * quantum(i);
      activity.set_slide(i, alone ? static_cast<double>(quantum(i)) : 0.0);
    }
  }
  /// Clears the filters and the record: the next check primes it (an enable, a restart).
  void reset() {
    r.setZero();
    noise_bound.setZero();
    bound.setZero();
    acc.setZero();
    threshold.setZero();
    prime_change();
    change_threshold.setZero();
    tau_prev.setZero();
    tau_last.setZero();
    r_last.setZero();
    travel_error.setZero();
    peak_ratio.setZero();
    travel_peak.setZero();
    ahead.drive.setConstant(kNoDrive);
    back.drive.setConstant(kNoDrive);
    for (int i = 0; i < kDof; ++i) over[i] = 0, over_since[i] = 0;
    activity.reset();
    joint = -1;
    detected = 0;
    flange = FlangeWeight<S>{};
    detected_tick = 0;
    primed = false;
    contact_noted = false;
    held = false;
    for (int i = 0; i < kDof; ++i) error_floor(i) = rest_floor(i);
  }
  /// The velocity estimate's noise on the wrist, this step. The observer's q^dot = J^-1 (y + k x~)
  /// carries the encoders' quantisation e (x~'s share J e) as J^-1 diag(k) J e. With the operational
  /// point at the wrist centre J is block-triangular, [J_11 0; J_21 J_22], and with equal gains per
  /// block (k_t, k_r) the arm's rows are k_t e_arm, the wrist's k_r e_wrist + (k_r - k_t) J_22^-1 J_21
  /// e_arm: an arm joint's quantum turns the wrist. J_21 e_arm is a rotation of at most the arm's
  /// quanta summed; J_22^-1 splits it over the wrist's axes, J5's share at most that, J4's and J6's
  /// at most that over |sin q5| (their axes are q5 apart: the dual basis of the plane they span has
  /// norm 1 / |sin q5|). J5's share does not change: set() adds it once. Near the wrist singularity that is 20 times
  /// J4's own noise (q5 = 0.08 rad: the 200-move sweep's J4 at 0.91 of its change threshold). |sin q5| is floored at
  /// kWristSinFloor (2.9 degrees: 20 times the arm's share). Other gains: their spread, max k - min k.
  void wrist_noise(const Mat6<S>& J) {
    static constexpr double kWristSinFloor = 0.05;
    static constexpr S kFloor = lit<S>(kWristSinFloor), kFloorSquared = lit<S>(kWristSinFloor * kWristSinFloor);
    const S c5 = J(3, 3) * J(3, 5) + J(4, 3) * J(4, 5) + J(5, 3) * J(5, 5);  // z4 . z6 = cos q5
    const S s2 = S(1) - c5 * c5;                                             // sin^2 q5
    const S turn = wrist_mix / (s2 > kFloorSquared ? math::sqrt(s2) : kFloor);
    velocity_noise(3) = noise_base(3) + turn;
    velocity_noise(5) = noise_base(5) + turn;
  }
  /// The velocity estimate's noise without a spherical wrist (wrist_noise() with one). The observer's q^dot =
  /// J^-1 (y + diag(k) x~) carries the encoders' quantisation e (x~'s share J e, J the analytic Jacobian) as M e,
  /// M = J^-1 diag(k) J; with |e_j| at most half a quantum, joint i's noise is at most sum_j |M_ij| quantum_j / 2,
  /// which e can reach (exact). M = k_min I + J^-1 diag(k - k_min) J: column j is k_min e_j plus, over the axes a
  /// whose gain exceeds the least (the paper's: the three of position), (k_a - k_min) J_aj times J^-1's column a,
  /// which the factor keeps (Jf.inverse_column). In fixed point x~ carries x's rounding r too (pose_rounding), as
  /// J^-1 diag(k) r: column j adds k_j r_j |J^-1 e_j|. Columns [first, last) added to velocity_noise (reset when
  /// first is 0): kMixedNoiseBefore on the step before a turn, the others on the turn (at most one period old; the
  /// turn's step computes A, the step before it the velocity products, the dearer of the two).
  static constexpr int kMixedNoiseBefore = 2;
  void mixed_noise(const Mat6<S>& J, const ArmJacobianFactor<S>& Jf, int first, int last);
  /// Joint i's floor out of contact: its amplifier's offset bound and the coupled motors' friction.
  S rest_floor(int i) const { return cross_friction(i) + kResidualConstants<S>.offset[i] + allowance(i); }
  /// The payload allowance, `mass` [kg] either way (the parameter payload_allowance, torque off): each joint's
  /// allowance_torque() in its floor (the absolute channel, the travel check), and the share of it the turn's motion
  /// can change in its change channel (allowance_change()).
  void set_allowance(double mass) {
    allowance_mass = static_cast<S>(mass);
    for (int i = 0; i < kDof; ++i) allowance_reach(i) = static_cast<S>(flange_lever(i) / robot::kArm.gravity);
    for (int i = 0; i < kDof; ++i) allowance(i) = static_cast<S>(allowance_torque(mass, i));
    for (int i = 0; i < kDof; ++i) error_floor(i) = rest_floor(i);
  }
  /// The contact the task reports (contact) began or ended. Its push, which the model does not know,
  /// stays in r while it lasts and would be judged against thresholds meant for the model's error (a
  /// firm push on a yielding arm named a drive_fault). When it begins, each joint's floor, its
  /// filtered bound and the slow filter take |r| and r as they are: the absolute channel holds the
  /// push as noted (the threshold at once, not at the next turn), and the change channel judges what changes
  /// after it. When it ends, the floors drop back, and the bound decays at the filter's rate.
  void note_contact() {
    contact_noted = contact;
    for (int i = 0; i < kDof; ++i) {
      if (!contact) {
        error_floor(i) = rest_floor(i);
        continue;
      }
      const S push = math::abs(r(i));
      error_floor(i) = rest_floor(i) + push;
      bound(i) += push;
      threshold(i) = math::mul_add(kResidualConstants<S>.peak_margin[i], push, threshold(i));  // before the turn
      r_slow(i) = r(i);
      d(i) = S(0);
    }
  }
  void unprime() { primed = false; }  // the next step starts afresh (a tick without a step: the torque was off)
  /// The joint torque that reached the arm over the period that follows this tick.
  void applied(const Vec6<S>& tau) {
    tau_last = tau_prev;
    tau_prev = tau;
  }

  /// The residual of this step and its faults (see the type's comment), a step every params::kDt. `turn`: the
  /// step is one of the monitor's turns (params::kResidualTurnEvery; the controller's even steps), on which each
  /// joint's bound, change channel and thresholds are updated and the travel check advances (turn_pass()); the
  /// residual, its qualification against the thresholds and the travel check's counts run every step. The
  /// monitor primes on a turn: a step between waits for the next.
  std::uint32_t check(const ResidualInput<S>& in, const IoMap<S>& io, const std::int32_t counts[kDof],
                      const bool moved[kDof], std::uint64_t tick, bool turn) {
    activity.track(counts, moved, tick);
    sample.settled = false;
    if (contact != contact_noted) note_contact();
    const bool prime = !primed;  // the first step after a reset: no previous step to difference
    held = (prime || held) && holding;
    if (prime) {
      if (!turn) return 0;
      qd_prev = qd_turn = in.qd;
      bias_prev = in.bias;
      r.setZero();
      acc.setZero();
      prime_change();
    } else {
      update_residual(in);
    }
    int moved_too_far = turn ? turn_pass(in, moved, prime, tick) : between_turns(in, moved);
    qd_prev = in.qd;
    bias_prev = in.bias;
    if (prime) {
      for (int i = 0; i < kDof; ++i) over[i] = 0, primed_counts[i] = counts[i];
      primed = true;
      primed_at = tick;
      return 0;
    }
    d = r - r_slow;
    int worst = -1;
    S worst_ratio = S(0);
    for (int i = 0; i < kDof; ++i) qualify_joint(i, tick, worst, worst_ratio);
    return worst < 0 && moved_too_far < 0 ? 0u : decide(worst, moved_too_far, io, tick, in, counts);  // a finding
  }

  /// r_k = (1 - K dt) r_{k-1} + K [A_k (q^dot_k - q^dot_{k-1}) + dt (n_{k-1} - tau_{k-1})], every joint; the
  /// last step's r kept (r_last: the change channel's mean over a turn).
  void update_residual(const ResidualInput<S>& in) {
    const ResidualConstants<S>& c = kResidualConstants<S>;
    static constexpr S kDt = lit<S>(params::kDt);
    S dqd[kDof];
    for (int j = 0; j < kDof; ++j) dqd[j] = in.qd(j) - qd_prev(j);
    for (int i = 0; i < kDof; ++i) {
      S u = S(0);  // A's row i against q^dot's change
      for (int j = 0; j < kDof; ++j) u = math::mul_add(in.A(i, j), dqd[j], u);
      r_last(i) = r(i);
      r(i) = math::mul_add(c.gain[i], math::mul_add(kDt, bias_prev(i) - tau_prev(i), u), c.keep[i] * r(i));
    }
  }

  int turn_pass(const ResidualInput<S>& in, const bool moved[kDof], bool prime, std::uint64_t tick);
  int between_turns(const ResidualInput<S>& in, const bool moved[kDof]);

  /// Joint i's residual against its thresholds after a step: its peak ratio, its run over them, and
  /// whether it is the worst joint so far that has been over them long enough (worst, worst_ratio).
  void qualify_joint(int i, std::uint64_t tick, int& worst, S& worst_ratio) {
    const S ratio = ratio_of(i);
    if (ratio > peak_ratio(i)) peak_ratio(i) = ratio;
    if (ratio > S(1) && over[i] == 0) over_since[i] = tick;
    over[i] = qualify(over[i], ratio > S(1));
    if (over[i] >= params::kResidualQualifyTicks && ratio > worst_ratio) worst = i, worst_ratio = ratio;
  }

  /// The step's fault (residual_travel.hpp): a joint that moved too far first, else the worst over its thresholds.
  std::uint32_t decide(int worst, int moved_too_far, const IoMap<S>& io, std::uint64_t tick, const ResidualInput<S>& in,
                       const std::int32_t counts[kDof]);

  /// Joint i's residual within `fraction` of its thresholds on both channels (ratio_of(i) <= fraction, undivided).
  bool within(int i, S fraction) const {
    return math::abs(r(i)) <= fraction * threshold(i) && math::abs(d(i)) <= fraction * change_threshold(i);
  }
  /// Joint i's residual against its threshold: the larger of the two channels' ratios.
  S ratio_of(int i) const {
    const S a = math::abs(r(i)) / threshold(i), c = math::abs(d(i)) / change_threshold(i);
    return a > c ? a : c;
  }

 private:
  /// A turn's joint motion and A's rows against it: per joint, the speed beyond which it may count as moving
  /// (its noise, and its lag at the acceleration filtered before this turn), the filtered acceleration's size
  /// and change (q^dot's change over the turn, filtered as r), and |A| times the accelerations, their changes
  /// and the velocity noise; the share of the payload allowance's torque the change channel can see.
  struct Motion {
    S moving_speed[kDof], a[kDof], da[kDof];
    S inertia[kDof], inertia_change[kDof], noise[kDof], allowance;  // allowance: allowance_change()
  };
  Motion motion(const ResidualInput<S>& in);
  S allowance_change(const ResidualInput<S>& in, const Motion& m) const;
  /// y filtered toward x at the gain g (K dt): y + g (x - y), one rounding.
  static void low_pass(S& y, S x, S g) { y = math::mul_add(g, x - y, y); }
  /// A joint's regressor changes (their filtered values less their slow parts), signed.
  struct Changes {
    S vis, cou, sti, estimate, gravity, coriolis, torque;
  };
  void prime_change() {
    d.setZero();
    r_slow.setZero();
    acc_slow.setZero();
    for (int k = 0; k < kRegressors; ++k) reg[k].setZero(), reg_slow[k].setZero();
    stillness.setOnes();  // until each joint is seen moving, its static friction may change at any time
  }
  /// Joint i's friction sample, on a turn (residual_thresholds.hpp).
  void take_sample(int i, const FrictionError& e, const IoMap<S>* io);
  /// The stillness envelope after kIdentifySettle / K seconds of motion: (1 - kSlow dt kTurn)^turns.
  static constexpr std::array<S, kDof> settled_stillness() {
    std::array<S, kDof> s{};
    constexpr double kTurnDt = params::kResidualTurnEvery * params::kDt;
    for (int i = 0; i < kDof; ++i) {
      const double turns = params::kIdentifySettle / (params::kResidualGain[i] * kTurnDt);
      double v = 1;
      for (int t = 0; t < turns; ++t) v *= 1 - params::kResidualSlowGain * kTurnDt;
      s[i] = lit<S>(v);
    }
    return s;
  }
  /// Some joint's residual beyond the user's collision threshold, qualified (the travel check's
  /// findings need no qualification of the residual).
  bool beyond_collision_floor(bool qualified) const {
    for (int j = 0; j < kDof; ++j)
      if ((!qualified || over[j] >= params::kResidualQualifyTicks) && math::abs(r(j)) > collision_floor(j)) return true;
    return false;
  }
  /// A joint's friction at its strongest, which the still joint's thresholds and the travel check
  /// take: its viscous coefficient [N m s/rad] and breakaway torque [N m].
  struct Friction {
    S vis, breakaway;
  };
  /// Friction at its strongest, per joint: the band's tops, or what the identification proves (in.proven), once a step.
  struct StrongestFriction {
    const S* vis;
    const S* breakaway;
    explicit StrongestFriction(const ResidualInput<S>& in)
        : vis(in.proven ? in.proven->vis.data() : kResidualConstants<S>.vis_hi),
          breakaway(in.proven ? in.proven->breakaway.data() : kResidualConstants<S>.static_band) {}
    Friction operator()(int i) const { return Friction{vis[i], breakaway[i]}; }
  };
  /// Joint i's Coriolis torque c = n - g - tau_f^ and the applied torque's size |tau| (the larger of the turn's
  /// two periods), which the bound and the change channel both take: computed once a joint.
  struct Torques {
    S coriolis, size;
  };
  Torques torques(const ResidualInput<S>& in, int i) const {
    const S now = math::abs(tau_prev(i)), before = math::abs(tau_last(i));
    return Torques{in.bias(i) - in.g(i) - in.tau_f(i), now > before ? now : before};
  }
  // Per joint: the friction error, the bound, the model error, the change channel and the thresholds
  // (osc/runtime/residual_thresholds.hpp).
  FrictionError friction_error(const ResidualInput<S>& in, const Friction& f, int i, std::uint64_t tick,
                               S moving) const;
  S pointwise_bound(const ResidualInput<S>& in, const FrictionError& e, int i, S model) const;
  S model_error(const ResidualInput<S>& in, const Torques& t, int i) const;
  Changes update_change(const ResidualInput<S>& in, const FrictionError& e, const Torques& t, int i);
  S update_thresholds(const FrictionError& e, const Changes& ch, const Motion& m, int i);
  // The travel check (osc/runtime/residual_travel.hpp).
  S motion_error(const ResidualInput<S>& in, const Motion& m, int i, S model, S loop) const;
  bool travel(const ResidualInput<S>& in, const Friction& f, int i, bool count, bool restart, bool turn);
  /// Joint i's travel bounds step in this tick: the even joints' on the monitor's turns, the odd ones' between.
  static bool travel_turn(int i, bool turn) { return (i % 2 == 0) == turn; }
  void count_bounds(int i, S change);
  S advance(Way& w, int i, S force, const Friction& f, S a_min, S a_max);
  std::uint32_t classify_travel(int i) const;
  bool off_reference(const ResidualInput<S>& in, const std::int32_t counts[kDof], int i) const;
  /// Channel c fell silent before joint i's residual rose, and not long before (residual_travel.hpp).
  bool silent_first(int c, int i, std::uint64_t tick) const;
  std::uint32_t classify(int i, const IoMap<S>& io, std::uint64_t tick) const;  // a qualified residual's kind
};

}  // namespace osc

#include "osc/runtime/residual_thresholds.hpp"
#include "osc/runtime/residual_travel.hpp"
