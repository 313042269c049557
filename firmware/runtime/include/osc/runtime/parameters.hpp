// The runtime parameters' access: reading (param_get), writing unchecked (param_put) and checked
// (param_set, param load), over the table of osc/runtime/param_table.hpp.
//
// Setting a value (param_set) checks, in this order: the index and element, a finite number within
// the range, torque off where the parameter asks it, and for a gain of (69) the observer's
// discrete-time stability at the pose the controller last computed (gain_margins; the margin that
// osc/control/observer.hpp states), then the sampled closed loop's (osc/control/sampled_loop.hpp).
// A refusal names its reason (ParamStatus) and changes nothing.
// The paper's sufficient condition (37) is evaluated as far as it can be and only warns.
//
// Header-only, allocation-free; the checks run in double outside the control interrupt.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "osc/control/sampled_loop.hpp"
#include "osc/runtime/control_task.hpp"
#include "osc/runtime/param_table.hpp"

namespace osc {

namespace detail {
/// Element e of a gain field, read or written in double (a number's only element is 0; a field of
/// form kEvery is written to every element and read from its first).
template <class F>
double field_get(const F& f, int e) {
  if constexpr (requires { F::RowsAtCompileTime; })
    return static_cast<double>(f(e));
  else if constexpr (std::is_enum_v<F>)
    return static_cast<double>(f);
  else if constexpr (std::is_floating_point_v<F> || fixed::is_q_v<F>)
    return static_cast<double>(f);
  else
    return 0;
}
template <class F>
void field_set(F& f, int e, double v, bool every) {
  if constexpr (requires { F::RowsAtCompileTime; }) {
    using S = typename F::Scalar;
    if (every)
      f.setConstant(static_cast<S>(v));
    else
      f(e) = static_cast<S>(v);
  } else if constexpr (std::is_enum_v<F>) {
    f = static_cast<F>(static_cast<int>(v));
  } else if constexpr (std::is_floating_point_v<F> || fixed::is_q_v<F>) {
    f = static_cast<F>(v);
  }
}
/// Calls fn(field) with the gain of index i of g (a Gains<S>, const or not).
template <class G, class Fn>
void visit_gain(G& g, int i, Fn&& fn) {
  int k = 0;
#define OSC_PARAM_VISIT(type, name, paper, doc, param) \
  if (k++ == i) return fn(g.name);
  OSC_GAINS_FIELDS(OSC_PARAM_VISIT)
#undef OSC_PARAM_VISIT
}
/// Element e of gain i of g set to v (a gain of form kEvery: every element of its vector).
template <class S>
void gain_put(Gains<S>& g, int i, int e, double v) {
  const bool every = kGainInfo[i].param.form == GainForm::kEvery;
  visit_gain(g, i, [&](auto& f) { field_set(f, e, v, every); });
}
template <class S>
double limit_get(const JerkLimits<S>& l, int e) {
  return static_cast<double>(e == 0 ? l.v : e == 1 ? l.a : l.j);
}
template <class S>
void limit_set(JerkLimits<S>& l, int e, double v) {
  (e == 0 ? l.v : e == 1 ? l.a : l.j) = static_cast<S>(v);
}
/// The payload p with element e of parameter `which` (payload_mass, _com or _inertia) set to v.
inline Payload payload_with(Payload p, RuntimeParam which, int e, double v) {
  if (which == RuntimeParam::kParamPayloadMass) p.mass = v;
  if (which == RuntimeParam::kParamPayloadCom) p.com[e] = v;
  if (which == RuntimeParam::kParamPayloadInertia) p.inertia[e] = v;
  return p;
}
/// The index in theta^ = [vis; cou; sti] of element e of friction_vis, _cou or _sti.
constexpr int theta_index(RuntimeParam which, int e) {
  return (static_cast<int>(which) - static_cast<int>(RuntimeParam::kParamFrictionVis)) * kDof + e;
}
/// Writes element e of a parameter of what the arm is known to be (the payload, the drives' armature, the
/// friction law's estimate) into the task.
template <class S>
void model_put(ControlTask<S>& task, RuntimeParam which, int e, double v) {
  if (which == RuntimeParam::kParamArmatureCorrection) return task.set_armature(e, v);
  if (which == RuntimeParam::kParamFrictionVis || which == RuntimeParam::kParamFrictionCou ||
      which == RuntimeParam::kParamFrictionSti) {
    AdaptationState<S>& ad = task.state.adapt;  // the momentum law goes on from it, and checks it (seed)
    ad.theta_hat(theta_index(which, e)) = static_cast<S>(v);
    return ad.identifier.seed(e, ad.theta_hat);
  }
  task.set_payload(payload_with(task.payload, which, e, v));
}
/// Writes a monitor's parameter (the residual monitor's, the drive check's and its dither) into the task.
template <class S>
void monitor_put(ControlTask<S>& task, RuntimeParam which, int e, double v) {
  switch (which) {
    case RuntimeParam::kParamCollisionThreshold:
      task.residual.collision_floor(e) = static_cast<S>(v);
      break;
    case RuntimeParam::kParamResidualMonitor:
      task.residual.armed = v != 0;
      break;
    case RuntimeParam::kParamPayloadAllowance:
      task.residual.set_allowance(v);
      break;
    case RuntimeParam::kParamDriveCheck:
      if ((v != 0) != task.drive_check) task.drive.reset(), task.set_dither(task.dither_fraction);
      task.drive_check = v != 0;
      if (!task.drive_check) task.residual.drives_checked = false;
      break;
    case RuntimeParam::kParamDitherAmplitude:
      task.set_dither(v);
      break;
    case RuntimeParam::kParamDitherHalfPeriod:
      task.dither_half = static_cast<std::uint8_t>(v);
      break;
    default:  // not a monitor's (param_put)
      break;
  }
}
}  // namespace detail

/// Element e of parameter i's default: a gain's paper value (Gains::paper), a runtime parameter's
/// from its list.
inline double param_default(int i, int e) {
  const ParamInfo& p = kParams[i];
  if (p.gain < 0) return p.def_each ? p.def_each[e] : p.def;
  Gains<double> g = Gains<double>::paper();
  double v = 0;
  detail::visit_gain(g, p.gain, [&](const auto& f) { v = detail::field_get(f, e); });
  return v;
}

/// Element e of parameter i as the task has it now.
template <class S>
double param_get(const ControlTask<S>& task, int i, int e) {
  const ParamInfo& p = kParams[i];
  if (p.gain >= 0) {
    double v = 0;
    detail::visit_gain(task.gains, p.gain, [&](const auto& f) { v = detail::field_get(f, e); });
    return v;
  }
  switch (p.runtime) {
    case RuntimeParam::kParamAdaptation:
      return static_cast<double>(task.gains.adaptation);
    case RuntimeParam::kParamMoveLinear:
      return detail::limit_get(task.limits.linear, e);
    case RuntimeParam::kParamMoveAngular:
      return detail::limit_get(task.limits.angular, e);
    case RuntimeParam::kParamCollisionReaction:
      return static_cast<double>(task.collision_reaction);
    case RuntimeParam::kParamCollisionThreshold:
      return static_cast<double>(task.residual.collision_floor(e));
    case RuntimeParam::kParamStreamTimeout:
      return static_cast<double>(task.stream_timeout_ticks) / params::kControlHz;
    case RuntimeParam::kParamPots:
      return task.pots ? 1.0 : 0.0;
    case RuntimeParam::kParamHomeSpeed:
      return static_cast<double>(task.home_speed[e]);
    case RuntimeParam::kParamResidualMonitor:
      return task.residual.armed ? 1.0 : 0.0;
    case RuntimeParam::kParamDriveCheck:
      return task.drive_check ? 1.0 : 0.0;
    case RuntimeParam::kParamDitherAmplitude:
      return task.dither_fraction;
    case RuntimeParam::kParamDitherHalfPeriod:
      return task.dither_half;
    case RuntimeParam::kParamPayloadMass:
      return task.payload.mass;
    case RuntimeParam::kParamPayloadCom:
      return task.payload.com[e];
    case RuntimeParam::kParamPayloadInertia:
      return task.payload.inertia[e];
    case RuntimeParam::kParamPayloadAllowance:
      return static_cast<double>(task.residual.allowance_mass);
    case RuntimeParam::kParamArmatureCorrection:
      return task.armature_correction[e];
    case RuntimeParam::kParamFrictionVis:
    case RuntimeParam::kParamFrictionCou:
    case RuntimeParam::kParamFrictionSti:
      return static_cast<double>(task.state.adapt.theta_hat(detail::theta_index(p.runtime, e)));
    case RuntimeParam::kCount:
      break;
  }
  return 0;
}

/// Writes element e of parameter i into the task, unchecked (param_set checks).
template <class S>
void param_put(ControlTask<S>& task, int i, int e, double v) {
  const ParamInfo& p = kParams[i];
  if (p.gain >= 0) return detail::gain_put(task.gains, p.gain, e, v);
  switch (p.runtime) {
    case RuntimeParam::kParamAdaptation: {
      const auto law = static_cast<AdaptationLaw>(static_cast<int>(v));
      if (law != task.gains.adaptation) task.state.adapt.identifier.reset();  // the momentum law: from its prior
      task.gains.adaptation = law;
      break;
    }
    case RuntimeParam::kParamMoveLinear:
      detail::limit_set(task.limits.linear, e, v);
      break;
    case RuntimeParam::kParamMoveAngular:
      detail::limit_set(task.limits.angular, e, v);
      break;
    case RuntimeParam::kParamCollisionReaction:
      task.collision_reaction = static_cast<CollisionReaction>(static_cast<int>(v));
      break;
    case RuntimeParam::kParamStreamTimeout:
      task.stream_timeout_ticks = static_cast<std::uint32_t>(std::lround(v * params::kControlHz));
      break;
    case RuntimeParam::kParamPots:
      if ((v != 0) != task.pots) task.position.reset();  // learnt again from the next sample
      task.pots = v != 0;
      break;
    case RuntimeParam::kParamHomeSpeed:
      task.home_speed[e] = static_cast<S>(v);
      break;
    case RuntimeParam::kParamCollisionThreshold:
    case RuntimeParam::kParamResidualMonitor:
    case RuntimeParam::kParamPayloadAllowance:
    case RuntimeParam::kParamDriveCheck:
    case RuntimeParam::kParamDitherAmplitude:
    case RuntimeParam::kParamDitherHalfPeriod:
      detail::monitor_put(task, p.runtime, e, v);
      break;
    case RuntimeParam::kParamPayloadMass:
    case RuntimeParam::kParamPayloadCom:
    case RuntimeParam::kParamPayloadInertia:
    case RuntimeParam::kParamArmatureCorrection:
    case RuntimeParam::kParamFrictionVis:
    case RuntimeParam::kParamFrictionCou:
    case RuntimeParam::kParamFrictionSti:
      detail::model_put(task, p.runtime, e, v);
      break;
    case RuntimeParam::kCount:
      break;
  }
}

/// Whether the task's torque is off (a torque_off parameter, a save, a load or a reset may be written).
template <class S>
bool param_torque_off(const ControlTask<S>& task) {
  return motion_torque_off(task.machine.state);
}

/// The largest magnitude the build's scalar holds: a fixed-point build (Q12.19: 4096) refuses a
/// value its scalar would saturate (a k_i of 1e4), out_of_range.
template <class S>
constexpr double param_scalar_max() {
  if constexpr (fixed::is_q_v<S>)
    return static_cast<double>(S::max());
  else
    return std::numeric_limits<double>::max();
}

/// Whether parameter i has an element e: unknown_param, bad_element, or ok.
constexpr ParamStatus param_address_status(int i, int e) {
  if (i < 0 || i >= kParamCount) return ParamStatus::kUnknownParam;
  return e < 0 || e >= kParams[i].count ? ParamStatus::kBadElement : ParamStatus::kOk;
}

/// Whether parameter p's values are the codes of an enumeration or a switch (whole numbers).
constexpr bool param_is_code(const ParamInfo& p) {
  return p.gain < 0 &&
         (p.runtime == RuntimeParam::kParamAdaptation || p.runtime == RuntimeParam::kParamCollisionReaction ||
          p.runtime == RuntimeParam::kParamPots || p.runtime == RuntimeParam::kParamResidualMonitor ||
          p.runtime == RuntimeParam::kParamDriveCheck || p.runtime == RuntimeParam::kParamDitherHalfPeriod);
}

/// Whether v is a valid value of element e of parameter i (finite, in range and within the scalar
/// S, a whole number for an enumeration's code).
template <class S = double>
ParamStatus param_value_status(int i, int e, double v) {
  if (const ParamStatus a = param_address_status(i, e); a != ParamStatus::kOk) return a;
  const ParamInfo& p = kParams[i];
  if (!std::isfinite(v)) return ParamStatus::kNotFinite;
  if (v < p.lo_of(e) || v > p.hi_of(e) || std::fabs(v) >= param_scalar_max<S>()) return ParamStatus::kOutOfRange;
  if (param_is_code(p) && v != std::floor(v)) return ParamStatus::kOutOfRange;
  return ParamStatus::kOk;
}

/// Lambda^-1 at the pose the controller last measured (q(t - dt) of its adaptation state), computed in
/// the path check's workspace (outside the tick, as command preparation is).
/// With `model` in place of the task's (a candidate's armature).
template <class S>
Mat6<double> task_lambda_inverse(ControlTask<S>& task, const Model<S>& model) {
  ArmOpSpace<S> os;
  opspace_update(model, task.check_data, os, task.state.adapt.q_prev, task.state.R_ref);
  return lambda_inverse<double>(task.check_data.A.template cast<double>(), os.Ja.template cast<double>());
}

template <class S>
Mat6<double> task_lambda_inverse(ControlTask<S>& task) {
  return task_lambda_inverse(task, task.model);
}

/// Whether gains of these margins may run (GainMargins' rules), and which check fails first.
inline ParamStatus gain_status(const GainMargins& m) {
  if (!m.observer_stable()) return ParamStatus::kUnstableObserver;
  if (!m.loop_stable()) return ParamStatus::kUnstableLoop;
  return ParamStatus::kOk;
}

/// The margins of the task's gains with element e of parameter i set to v (i < 0: as they are): a
/// gain's, or the model's armature's (the loop's inverse masses).
template <class S>
GainMargins param_margins(ControlTask<S>& task, int i = -1, int e = 0, double v = 0) {
  Gains<double> g = task.gains.template cast<double>();
  if (i >= 0 && kParams[i].gain >= 0) detail::gain_put(g, kParams[i].gain, e, v);
  if (i < 0 || kParams[i].runtime != RuntimeParam::kParamArmatureCorrection)
    return gain_margins(g, task_lambda_inverse(task));
  double correction[kDof];
  for (int k = 0; k < kDof; ++k) correction[k] = k == e ? v : task.armature_correction[k];
  return gain_margins(g, task_lambda_inverse(task, task.with_armature(correction)));
}

/// Whether a change of parameter p is judged by the sampled loop's margins: a gain's, the armature's.
constexpr bool param_moves_margins(const ParamInfo& p) {
  return p.gain >= 0 || p.runtime == RuntimeParam::kParamArmatureCorrection;
}

/// Sets element e of parameter i to v, or refuses with the reason (nothing changed). For a gain,
/// `margins` (when given) receives the margins the change was judged by: (37) unmet
/// (condition37 <= 1) only warns.
template <class S>
ParamStatus param_set(ControlTask<S>& task, int i, int e, double v, GainMargins* margins = nullptr) {
  const ParamStatus s = param_value_status<S>(i, e, v);
  if (s != ParamStatus::kOk) return s;
  const ParamInfo& p = kParams[i];
  if (p.access == ParamAccess::kTorqueOff && !param_torque_off(task)) return ParamStatus::kTorqueOn;
  if (p.runtime == RuntimeParam::kParamPayloadInertia &&
      !inertia_semidefinite(detail::payload_with(task.payload, p.runtime, e, v).inertia))
    return ParamStatus::kNotPhysical;
  if (param_moves_margins(p)) {
    const GainMargins m = param_margins(task, i, e, v);
    if (margins) *margins = m;
    if (const ParamStatus g = gain_status(m); g != ParamStatus::kOk) return g;
  }
  param_put(task, i, e, v);
  return ParamStatus::kOk;
}

/// Every parameter's value in one record (the slots in table order), as a store keeps it: a parameter that does not
/// persist (ParamInfo::persists) at its default.
struct ParamRecord {
  float value[kParamSlots];
};

template <class S>
ParamRecord param_capture(const ControlTask<S>& task) {
  ParamRecord r{};
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e)
      r.value[param_slot(i) + e] =
          static_cast<float>(kParams[i].persists ? param_get(task, i, e) : param_default(i, e));
  return r;
}

/// The table's defaults.
inline ParamRecord param_defaults() {
  ParamRecord r{};
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e) r.value[param_slot(i) + e] = static_cast<float>(param_default(i, e));
  return r;
}

/// The payload inertia's and the armature correction's indices in kParams.
constexpr int kPayloadInertiaParam = param_index("payload_inertia");
constexpr int kArmatureParam = param_index("armature_correction");

/// Applies a record when every value is valid and its gains and armature keep the sampled loop stable
/// (else nothing changes: bad_record, unstable_observer, unstable_loop). Needs the torque off.
template <class S>
ParamStatus param_apply(ControlTask<S>& task, const ParamRecord& r) {
  if (!param_torque_off(task)) return ParamStatus::kTorqueOn;
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e)
      if (param_value_status<S>(i, e, r.value[param_slot(i) + e]) != ParamStatus::kOk) return ParamStatus::kBadRecord;
  double inertia[6];
  for (int e = 0; e < 6; ++e) inertia[e] = r.value[param_slot(kPayloadInertiaParam) + e];
  if (!inertia_semidefinite(inertia)) return ParamStatus::kBadRecord;
  Gains<double> g = task.gains.template cast<double>();
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count && kParams[i].gain >= 0; ++e)
      detail::gain_put(g, kParams[i].gain, e, r.value[param_slot(i) + e]);
  double correction[kDof];
  for (int e = 0; e < kDof; ++e) correction[e] = r.value[param_slot(kArmatureParam) + e];
  const Mat6<double> lambda_inv = task_lambda_inverse(task, task.with_armature(correction));
  if (const ParamStatus st = gain_status(gain_margins(g, lambda_inv)); st != ParamStatus::kOk) return st;
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e) param_put(task, i, e, r.value[param_slot(i) + e]);
  return ParamStatus::kOk;
}

}  // namespace osc
