// The residual monitor's travel check (ResidualMonitor::travel(), osc/runtime/residual_monitor.hpp, which
// includes this header at its end; docs/safety.md): a joint whose least motion since its encoder's last
// count, from the torque applied and the model's error bounds, passes params::kResidualTravelCounts counts
// must have counted; classify_travel() names the finding, and classify() a qualified residual.
#pragma once

#include <cstdint>

#include "osc/runtime/residual_monitor.hpp"

namespace osc {

/// Joint i's bound on the model's error against its motion, a turn's (travel()): the other joints' inertial
/// torques with the link inertia's share, model_error()'s and the current loop's lag (`model`, `loop`: those
/// of update_thresholds()'s pass) [N m].
template <class S>
inline S ResidualMonitor<S>::motion_error(const ResidualInput<S>& in, const Motion& m, int i, S model, S loop) const {
  const S others = m.inertia[i] - in.A(i, i) * m.a[i];  // sum over j != i of |A_ij| |q^dd_j|
  return math::mul_add(kResidualConstants<S>.link_inertia, others, others) + model + loop;
}

/// Joint i's travel check: whether the joint must have counted, either way. At a count the joint
/// has just crossed an edge in the direction `way` of the count. Counting steadily, it crossed the
/// one before a count back, n ticks earlier: its mean speed that way since was at least the edges'
/// least spacing over n + 1 ticks and at most their largest over n - 1 (spacing_lo, spacing_hi), and its speed now
/// differs from that mean by at most the most it can have sped up or slowed down over them (after a reversal, the
/// same edge twice: a mean of 0). These bound its speed ahead from below, and back from below as minus its speed
/// ahead at most. Then, every params::kResidualTurnEvery ticks (`turn`: the even joints on the monitor's turns,
/// the odd ones in the steps between), each way
/// (advance()): the torque applied that way less gravity and Coriolis torques (the least of the turn's ticks),
/// with every error the model may have against the motion (travel_error, the last turn's motion_error()) and
/// friction at its strongest against it (at rest: the whole breakaway torque; the band's top, or what the
/// identification proves: `f`), over the diagonal inertia at its least or most, bounds its speed that way from
/// below, and its travel. Its least travel beyond travel_limit crosses the next edge ahead or the last one back: the
/// encoder should have counted. Before its first count (a prime, a contact) the direction is unknown and nothing is
/// bounded.
template <class S>
inline bool ResidualMonitor<S>::travel(const ResidualInput<S>& in, const Friction& f, int i, bool count, bool restart,
                                       bool turn) {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  using math::mul_add;
  const S limit = travel_limit(i);
  if (limit == S(0)) return false;
  if (restart) {
    ahead.p(i) = back.p(i) = -limit;  // nothing known: no bound until a count
    ahead.v(i) = S(0);
    back.v(i) = -c.speed_cap[i];
    ahead.drive(i) = back.drive(i) = kNoDrive;
    return false;
  }
  const S way = activity.direction[i] > 0 ? S(1) : S(-1);
  const S now = way * (tau_prev(i) - (in.bias(i) - in.tau_f(i)));  // beyond gravity and Coriolis
  // This tick's drive each way at a count (the direction it sets), else the least over the turn's ticks.
  const S drive = count || now < ahead.drive(i) ? now : ahead.drive(i);
  const S drive_back = count || -now < back.drive(i) ? -now : back.drive(i);
  if (!count && !turn) {
    ahead.drive(i) = drive;
    back.drive(i) = drive_back;
    return false;
  }
  ahead.drive(i) = back.drive(i) = kNoDrive;  // the next step starts
  const S aii = in.A(i, i);
  const S error = travel_error(i);
  const S a_min = mul_add(-c.link_inertia, aii, aii) - c.armature_delta[i];
  if (count) {
    count_bounds(i, (math::abs(drive) + error + f.breakaway) / a_min);
    return false;
  }
  const S a_max = mul_add(c.link_inertia, aii, aii) + c.armature_delta[i];
  const S p_ahead = advance(ahead, i, drive - error, f, a_min, a_max);
  const S p_back = advance(back, i, drive_back - error, f, a_min, a_max);
  const S p = p_ahead > p_back ? p_ahead : p_back;
  if (p > travel_peak(i)) travel_peak(i) = p;
  return p > limit;
}

/// Joint i's speed bounds at a count (travel()), from its pace and `change`, the most its speed can
/// change per second [rad/s^2]. Its spans are read up to kSpanMax ticks (slower, ahead is 0 and
/// back is its speed cap's).
template <class S>
inline void ResidualMonitor<S>::count_bounds(int i, S change) {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  static constexpr std::uint32_t kSpanMax = 250;
  static constexpr S kDt = lit<S>(params::kDt);
  const std::uint32_t n = activity.move_interval[i];
  S slow = S(0), fast = c.speed_cap[i];
  if (n <= kSpanMax) {
    const S span = kDt * S(static_cast<int>(n) + 1), drift = change * span;
    if (activity.steady[i] && n < static_cast<std::uint32_t>(params::kResidualSlideInterval))
      slow = spacing_lo(i) / span - drift;
    if (activity.reversed[i])
      fast = drift;  // it crossed the same edge back and forth: a mean speed of 0
    else if (activity.steady[i] && n >= 2)
      fast = spacing_hi(i) / (kDt * S(static_cast<int>(n) - 1)) + drift;
  }
  ahead.v(i) = slow > S(0) ? slow : S(0);
  back.v(i) = fast < c.speed_cap[i] ? -fast : -c.speed_cap[i];
  ahead.p(i) = back.p(i) = S(0);
}

/// One step of joint i's bounds one way: `force` is the least drive that way less the model's
/// error; friction is at its strongest against the motion (none when the joint may be going the
/// other way, where it pushes this way, until the bound reaches rest: from there on, against it).
/// Static friction holds a joint at rest against what cannot break it away (half the band's weakest
/// static friction). Returns the least travel (within a count either way after it: the joint did not
/// count).
template <class S>
inline S ResidualMonitor<S>::advance(Way& w, int i, S force, const Friction& f, S a_min, S a_max) {
  const ResidualConstants<S>& c = kResidualConstants<S>;
  using math::mul_add;
  static constexpr S kStep = lit<S>(params::kResidualTurnEvery * params::kDt);
  const S lo = w.v(i), limit = travel_limit(i);
  const S net = force - (lo >= S(0) ? mul_add(f.vis, lo, f.breakaway) : S(0));
  S next = mul_add(kStep, net / (net < S(0) ? a_min : a_max), lo);
  if (lo >= S(0) && next < S(0) && force + c.static_lo[i] > S(0)) next = S(0);
  // From below, it reached rest within the step (net = force > 0 at a constant rate, the step's last
  // next / (next - lo) of it left). From there friction is against it: the breakaway holds it at rest
  // unless the force exceeds it, and beyond it the rest of the step gains (force - breakaway) / a_max.
  if (lo < S(0) && next > S(0)) next = force > f.breakaway ? next * (force - f.breakaway) / force : S(0);
  const S cap = c.speed_cap[i];
  next = next < -cap ? -cap : (next > cap ? cap : next);
  w.v(i) = next;
  // Over the step the speed was at least the lesser of both ends.
  const S p = mul_add(kStep, lo < next ? lo : next, w.p(i));
  w.p(i) = p < -limit ? -limit : (p > limit ? limit : p);
  return p;
}

/// Channel c fell silent before joint i's residual rose, and not long before (what a frozen reading does); a
/// joint that came to rest after, under a contact that lasts, is no stuck encoder.
template <class S>
inline bool ResidualMonitor<S>::silent_first(int c, int i, std::uint64_t tick) const {
  constexpr std::uint64_t kWindow = params::kControlHz / 4;  // a residual rises within 250 ms of it
  const std::uint64_t last = activity.last_move_tick[c];
  return activity.silent(c, tick) && last <= over_since[i] && over_since[i] - last <= kWindow;
}

/// The kind of a qualified residual on joint i (the worst): encoder_stuck where its encoder (or one the coupling
/// adds to it) fell silent first; with the drives checked (isolation by order: docs/safety.md, "The drive
/// check"), drive_fault on a suspect drive's joint, else collision; without, drive_fault on one joint alone,
/// collision on several.
template <class S>
inline std::uint32_t ResidualMonitor<S>::classify(int i, const IoMap<S>& io, std::uint64_t tick) const {
  bool stuck = silent_first(i, i, tick);
  for (int k = 0; k < io.terms; ++k)
    if (io.row[k] == i && silent_first(io.col[k], i, tick)) stuck = true;
  if (stuck) return kFaultEncoderStuck;
  if (drives_checked) return drive_suspected(drive_suspect, i, io) ? kFaultDriveFault : kFaultCollision;
  for (int j = 0; j < kDof; ++j)
    if (j != i && ratio_of(j) > lit<S>(0.5)) return kFaultCollision;
  return kFaultDriveFault;
}

/// The kind of a travel check's finding on joint i: a joint that must have counted and did not.
/// Its encoder fell silent at once from counting fast (a joint that stops slows down first, its
/// intervals between counts growing): encoder_stuck. Otherwise something holds it, or its encoder
/// froze while it stood, which the same reading cannot tell apart: collision when the residual is
/// on other joints too (a contact at the tip loads several), else encoder_stuck.
template <class S>
inline std::uint32_t ResidualMonitor<S>::classify_travel(int i) const {
  if (activity.was_fast(i)) return kFaultEncoderStuck;
  for (int j = 0; j < kDof; ++j)
    if (j != i && ratio_of(j) > lit<S>(0.5)) return kFaultCollision;
  return kFaultEncoderStuck;
}

/// Joint i moved off its reference since the prime (decide(), params::kPayloadAwayCounts = n): its encoder has
/// counted m, more than n counts one way, and the reference lies more than n counts the other way from its reading
/// (the step's tracking error in joint space, J^-1 e through the step's factor: small in the first second). Where the
/// reference has gone since, p = m + J^-1 e, that puts the reading outside [min(0, p), max(0, p)] by more than n
/// counts. A stuck encoder reads a pose its joint had while it tracked the reference, within that range (a reference
/// that turned back within the second aside); a load the model has wrong, or a drive short of its torque, moves the
/// joint off it: it counted away, and the controller pushes it back. Not on a joint whose encoder reads other joints
/// too (a coupled wrist's: no travel check either), whose counts are no joint's.
template <class S>
inline bool ResidualMonitor<S>::off_reference(const ResidualInput<S>& in, const std::int32_t counts[kDof],
                                              int i) const {
  if (in.os == nullptr || in.e == nullptr || travel_limit(i) == S(0)) return false;  // 0: its encoder reads others
  const std::int32_t m = counts[i] - primed_counts[i];
  if (m <= params::kPayloadAwayCounts && m >= -params::kPayloadAwayCounts) return false;
  const S toward = in.os->Jf.solve(*in.e)(i);  // the reference from the reading [rad]
  const S margin = lit<S>(2.0 * params::kPayloadAwayCounts) * half_quantum(i);
  return m > 0 ? toward < -margin : toward > margin;
}

/// The step's fault: a joint that moved too far (the travel check) first, else the worst joint over its
/// thresholds, classified; a collision below the collision floor is none. Within params::kPayloadCheckTicks of the
/// prime (an enable), unless the drive check suspects the joint's drive, a finding is payload_mismatch:
///  - where the residual is the weight of a point mass at the flange (J: frame 6's Jacobian; payload_check.hpp). An
///    encoder that counted fast and fell silent is no evidence then: a weight the model does not know drops the arm
///    at the enable until the controller catches it, and a joint whose encoder froze while it moved would leave a
///    residual on its own joint, no weight's;
///  - or where it would be encoder_stuck and the arm has held its pose since the prime (held), or its joint has
///    moved off its reference since (off_reference(): the same evidence while a motion has gone nowhere). A stuck
///    encoder has nothing to show there: with the model's gravity the arm's, the torque that holds it holds it whatever
///    the encoder reads. A joint driven beyond that and held, or a residual after a silence, is a load the model has
///    wrong; static friction holds part of it, so that the residual is no clean weight (the weight found is less).
///    A residual on one joint alone (less than params::kPayloadSpread of its square off it) may be that joint's drive
///    as well: drive_fault. With the drives checked, the drive check decides (classify()'s rule).
/// The first fault is recorded (detected, joint, detected_tick, flange); reported only when armed. Out of line: a
/// finding is rare, and check()'s every tick carries none of it.
template <class S>
[[gnu::noinline]] inline std::uint32_t ResidualMonitor<S>::decide(int worst, int moved_too_far, const IoMap<S>& io,
                                                                  std::uint64_t tick, const ResidualInput<S>& in,
                                                                  const std::int32_t counts[kDof]) {
  const Mat6<S>* J = in.J;
  std::uint32_t kind;
  if (moved_too_far >= 0) {
    worst = moved_too_far;
    kind = classify_travel(worst);
  } else {
    if (worst < 0) return 0;
    kind = classify(worst, io, tick);
  }
  const bool drive = kind == kFaultDriveFault && drives_checked;  // the current readback's, not the residual's
  FlangeWeight<S> weight{};
  if (!drive && tick - primed_at <= static_cast<std::uint64_t>(params::kPayloadCheckTicks)) {
    if (J) weight = flange_weight(*J, r);
    if (payload_mismatch(weight)) {  // never without J: the weight is then not fitted
      kind = kFaultPayloadMismatch;
    } else if (kind == kFaultEncoderStuck && (held || off_reference(in, counts, worst))) {
      const bool one_joint = residual_spread(r) < lit<S>(params::kPayloadSpread);
      const bool its_drive = drives_checked ? drive_suspected(drive_suspect, worst, io) : one_joint;
      kind = its_drive ? kFaultDriveFault : kFaultPayloadMismatch;
    }
  }
  if (kind == kFaultCollision && !beyond_collision_floor(moved_too_far < 0)) return 0;
  if (detected == 0) detected = kind, joint = static_cast<std::int8_t>(worst), detected_tick = tick, flange = weight;
  return armed ? kind : 0u;
}

}  // namespace osc
