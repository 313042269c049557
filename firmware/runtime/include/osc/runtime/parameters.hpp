// The runtime parameters (issue 27): one flat, typed table of what a user may set on a running
// controller without rebuilding it, each with its name, unit, range, default, when it may be written
// and whether it persists. PX4's and Crazyflie's parameter tables are the model: a parameter is
// addressed by its index in the table and, for a vector, an element; every value travels as a number.
//
// One declaration: the gains with a key in OSC_GAINS_FIELDS (osc/control/gains.hpp: (69), K_ad,
// tau_dec, the leakage) come first, in that list's order, with that list's key, range and unit; then
// OSC_RUNTIME_PARAM_LIST below (the adaptation law, the motion limits, the collision reaction and
// thresholds, the stream timeout). From the two come kParams (this table), the link's param frames'
// indices (osc/link/command_frames.hpp), oscctl param and the Python client's names, the host
// configuration's keys (host_sim/config.cpp) and the table of docs/protocol.md (ctest
// docs_tables_protocol fails when it differs).
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

namespace osc {

/// When a parameter may be written.
#define OSC_PARAM_ACCESS_LIST(X)                                                \
  X(Always, "always", "at any time; a motion already planned keeps its values") \
  X(TorqueOff, "torque_off", "only while the torque is off: disabled, or in fault (else refused torque_on)")

/// Why a parameter operation was refused, or ok.
#define OSC_PARAM_STATUS_LIST(X)                                                                                  \
  X(Ok, "ok", "done")                                                                                             \
  X(UnknownParam, "unknown_param", "no parameter of that index")                                                  \
  X(BadElement, "bad_element", "the parameter has no element of that number")                                     \
  X(BadOp, "bad_op", "an operation outside its list")                                                             \
  X(NotFinite, "not_finite", "the value is not a finite number")                                                  \
  X(OutOfRange, "out_of_range", "the value is outside the parameter's range")                                     \
  X(TorqueOn, "torque_on", "the parameter (or a save, load or reset) needs the torque off: disable first")        \
  X(UnstableObserver, "unstable_observer",                                                                        \
    "the gains would make the discrete observer unstable at the last computed pose (param check: margin)")        \
  X(UnstableLoop, "unstable_loop",                                                                                \
    "the gains would make the sampled closed loop unstable at the last computed pose (param check: loop margin)") \
  X(StoreFailed, "store_failed", "the parameter store could not write the record")                                \
  X(NoRecord, "no_record", "load: the store holds no valid record (the values are unchanged)")                    \
  X(LayoutMismatch, "layout_mismatch", "load: the stored record is of another table layout (values unchanged)")   \
  X(BadRecord, "bad_record", "load: a stored value is outside its range now (values unchanged)")

#define OSC_X_PREFIX k
enum class ParamAccess : std::uint8_t { OSC_PARAM_ACCESS_LIST(OSC_X_ENUMERATOR) };
enum class ParamStatus : std::uint8_t { OSC_PARAM_STATUS_LIST(OSC_X_ENUMERATOR) };
#undef OSC_X_PREFIX
constexpr const char* kParamAccessNames[] = {OSC_PARAM_ACCESS_LIST(OSC_X_NAME)};
constexpr const char* kParamAccessDocs[] = {OSC_PARAM_ACCESS_LIST(OSC_X_DOC)};
constexpr const char* kParamStatusNames[] = {OSC_PARAM_STATUS_LIST(OSC_X_NAME)};
constexpr const char* kParamStatusDocs[] = {OSC_PARAM_STATUS_LIST(OSC_X_DOC)};
constexpr int kParamStatusCount = sizeof(kParamStatusNames) / sizeof(*kParamStatusNames);
constexpr const char* param_status_name(ParamStatus s) { return kParamStatusNames[static_cast<int>(s)]; }

namespace params {
/// The motion limits' largest settable values: the configured maxima (kMoveLinear, kMoveAngular)
/// times this. docs/motion.md validates tracking within 1 mm at the defaults only; beyond them the
/// tracking and saturation monitors still bound what a too fast move can do.
constexpr double kMoveLimitCap = 4;
/// The stream timeout's range [s]: from two ticks to the longest extrapolation of a late stream
/// (osc/control/stream.hpp); the default is kStreamTimeoutMin.
constexpr double kStreamTimeoutLo = 0.002;
}  // namespace params

namespace detail {
constexpr double kMoveLinearCap[3] = {params::kMoveLinear[0] * params::kMoveLimitCap,
                                      params::kMoveLinear[1] * params::kMoveLimitCap,
                                      params::kMoveLinear[2] * params::kMoveLimitCap};
constexpr double kMoveAngularCap[3] = {params::kMoveAngular[0] * params::kMoveLimitCap,
                                       params::kMoveAngular[1] * params::kMoveLimitCap,
                                       params::kMoveAngular[2] * params::kMoveLimitCap};
constexpr double kZeros[kDof] = {};
/// Homing's speeds: from 1 mm/s and 1 mrad/s (a homing that still ends within a minute) to the
/// configured move maxima.
constexpr double kHomeSpeedLo[2] = {1e-3, 1e-3};
constexpr double kHomeSpeedHi[2] = {params::kMoveLinear[0], params::kMoveAngular[0]};
}  // namespace detail

// X(Name, "name", elements, unit, lo, hi (of each element: a number or a list), default (a number or
// a list), access, persists, meaning): the runtime parameters besides the gains. A name is a key of
// the host's run.* configuration where the host sets it too.
#define OSC_RUNTIME_PARAM_LIST(X)                                                                                     \
  X(Adaptation, "adaptation", 1, "", 0, kAdaptationLawCount - 1, static_cast<double>(kDefaultAdaptationLaw),          \
    TorqueOff, true, "the friction adaptation law: 0 paper (67), 1 robust, 2 momentum")                               \
  X(MoveLinear, "move_linear", 3, "m/s, m/s^2, m/s^3", 1e-6, detail::kMoveLinearCap, params::kMoveLinear, Always,     \
    true, "a move's and a stream's maxima of the wrist centre's speed, acceleration, jerk")                           \
  X(MoveAngular, "move_angular", 3, "rad/s, rad/s^2, rad/s^3", 1e-6, detail::kMoveAngularCap, params::kMoveAngular,   \
    Always, true, "the same of the rotation")                                                                         \
  X(CollisionReaction, "collision_reaction", 1, "", 0, MotionNames<CollisionReaction>::kCount - 1, 0, Always, true,   \
    "what a collision does: 0 category_0, 1 category_2, 2 yield")                                                     \
  X(CollisionThreshold, "collision_threshold", kDof, "N m", 0, robot::kDrives.torque_limit, detail::kZeros, Always,   \
    true, "each joint's collision threshold; 0: the derived threshold alone")                                         \
  X(StreamTimeout, "stream_timeout", 1, "s", params::kStreamTimeoutLo, kStreamExtrapolation, kStreamTimeoutMin,       \
    Always, true, "a stream is stale after max(2 periods, this) without a setpoint; from the next stream on")         \
  X(Pots, "pots", 1, "", 0, 1, 1, TorqueOff, true,                                                                    \
    "1: the arm's potentiometers are wired (the position cross-check runs); 0: an arm without them")                  \
  X(HomeSpeed, "home_speed", 2, "m/s, rad/s", detail::kHomeSpeedLo, detail::kHomeSpeedHi, params::kHomeSpeed, Always, \
    true, "the homing move's speeds: the wrist centre's, the rotation's (accelerations, jerks: the move's)")          \
  X(ResidualMonitor, "residual_monitor", 1, "", 0, 1, params::kResidualMonitorArmed ? 1 : 0, TorqueOff, true,         \
    "1: the residual monitor armed: it raises encoder_stuck, drive_fault, collision (the stuck-encoder "              \
    "monitor off but homing); 0: a trial (recorded; the stuck-encoder monitor raises encoder_stuck)")

#define OSC_X_PREFIX kParam
#define OSC_RUNTIME_PARAM_ID(Name, name, n, unit, lo, hi, def, access, persists, doc) OSC_X_CAT(OSC_X_PREFIX, Name),
enum class RuntimeParam : std::uint8_t { OSC_RUNTIME_PARAM_LIST(OSC_RUNTIME_PARAM_ID) kCount };
#undef OSC_RUNTIME_PARAM_ID
#undef OSC_X_PREFIX

/// A parameter's facts. Element e's range is [lo_of(e), hi_of(e)], its default def_of(e).
struct ParamInfo {
  const char* name;
  const char* unit;
  const char* doc;
  std::uint8_t count;  ///< elements: 1 to 6
  double lo, hi;       ///< the range of every element, unless lo_each / hi_each give one per element
  const double* lo_each;
  const double* hi_each;
  double def;  ///< a runtime parameter's default of every element, unless def_each gives one per element (a
               ///< gain's is its paper value: param_default)
  const double* def_each;
  ParamAccess access;
  bool persists;
  int gain;  ///< its index in kGainInfo, or -1: the runtime parameter `runtime`
  RuntimeParam runtime;

  constexpr double lo_of(int e) const { return lo_each ? lo_each[e] : lo; }
  constexpr double hi_of(int e) const { return hi_each ? hi_each[e] : hi; }
};

namespace detail {
struct Bound {
  double one;
  const double* each;
  constexpr Bound(double v) : one(v), each(nullptr) {}   // NOLINT(google-explicit-constructor)
  constexpr Bound(int v) : one(v), each(nullptr) {}      // NOLINT(google-explicit-constructor)
  constexpr Bound(const double* v) : one(0), each(v) {}  // NOLINT(google-explicit-constructor)
};
constexpr int gain_elements(GainForm f) { return f == GainForm::kPerAxis ? kDof : f == GainForm::kNone ? 0 : 1; }
constexpr int gain_param_count() {
  int n = 0;
  for (const GainInfo& g : kGainInfo) n += g.param.form != GainForm::kNone;
  return n;
}
}  // namespace detail

/// The table: the gains with a key, then the runtime list.
constexpr int kParamCount = detail::gain_param_count() + static_cast<int>(RuntimeParam::kCount);

inline constexpr auto kParams = [] {
  std::array<ParamInfo, kParamCount> t{};
  int n = 0;
  for (int i = 0; i < static_cast<int>(sizeof(kGainInfo) / sizeof(*kGainInfo)); ++i) {
    const GainInfo& g = kGainInfo[i];
    if (g.param.form == GainForm::kNone) continue;
    t[n++] = {g.param.key,
              g.param.unit,
              g.doc,
              static_cast<std::uint8_t>(detail::gain_elements(g.param.form)),
              g.param.lo,
              g.param.hi,
              g.param.lo_each,
              g.param.hi_each,
              0,
              nullptr,
              ParamAccess::kTorqueOff,
              true,
              i,
              RuntimeParam::kCount};
  }
#define OSC_RUNTIME_PARAM_INFO(Name, name, count, unit, lo, hi, def, access, persists, doc)                          \
  {                                                                                                                  \
    const detail::Bound l(lo), h(hi), d(def);                                                                        \
    t[n++] = {name,   unit,  doc,    static_cast<std::uint8_t>(count), l.one,    h.one, l.each,                      \
              h.each, d.one, d.each, ParamAccess::k##access,           persists, -1,    RuntimeParam::kParam##Name}; \
  }
  OSC_RUNTIME_PARAM_LIST(OSC_RUNTIME_PARAM_INFO)
#undef OSC_RUNTIME_PARAM_INFO
  return t;
}();

/// The index of a parameter's name in kParams; -1 for none.
constexpr int param_index(const char* name) {
  for (int i = 0; i < kParamCount; ++i) {
    const char *a = kParams[i].name, *b = name;
    while (*a && *a == *b) ++a, ++b;
    if (*a == *b) return i;
  }
  return -1;
}

/// Every element of the table, in order: the slots of a stored record.
constexpr int kParamSlots = [] {
  int n = 0;
  for (const ParamInfo& p : kParams) n += p.count;
  return n;
}();
/// The first slot of parameter i.
constexpr int param_slot(int i) {
  int n = 0;
  for (int k = 0; k < i; ++k) n += kParams[k].count;
  return n;
}
/// The record layout's version: a hash of every name and element count, so that a record written by
/// a firmware with another table is not read as this one's (FNV-1a, folded to 16 bits).
constexpr std::uint16_t kParamLayout = [] {
  std::uint32_t h = 2166136261u;
  auto mix = [&h](std::uint8_t b) { h = (h ^ b) * 16777619u; };
  for (const ParamInfo& p : kParams) {
    for (const char* c = p.name; *c; ++c) mix(static_cast<std::uint8_t>(*c));
    mix(0), mix(p.count);
  }
  return static_cast<std::uint16_t>((h >> 16) ^ (h & 0xFFFFu));
}();

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
    case RuntimeParam::kParamCollisionThreshold:
      task.residual.collision_floor(e) = static_cast<S>(v);
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
    case RuntimeParam::kParamResidualMonitor:
      task.residual.armed = v != 0;
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
          p.runtime == RuntimeParam::kParamPots || p.runtime == RuntimeParam::kParamResidualMonitor);
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
template <class S>
Mat6<double> task_lambda_inverse(ControlTask<S>& task) {
  OpSpace<S> os;
  opspace_update(task.model, task.check_data, os, task.state.adapt.q_prev, task.state.R_ref);
  return lambda_inverse(task.check_data.A.template cast<double>(), os.Ja.template cast<double>());
}

/// Whether gains of these margins may run (GainMargins' rules), and which check fails first.
inline ParamStatus gain_status(const GainMargins& m) {
  if (!m.observer_stable()) return ParamStatus::kUnstableObserver;
  if (!m.loop_stable()) return ParamStatus::kUnstableLoop;
  return ParamStatus::kOk;
}

/// The margins of the task's gains with element e of parameter i set to v (i < 0: as they are).
template <class S>
GainMargins param_margins(ControlTask<S>& task, int i = -1, int e = 0, double v = 0) {
  Gains<double> g = task.gains.template cast<double>();
  if (i >= 0 && kParams[i].gain >= 0) detail::gain_put(g, kParams[i].gain, e, v);
  return gain_margins(g, task_lambda_inverse(task));
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
  if (p.gain >= 0) {
    const GainMargins m = param_margins(task, i, e, v);
    if (margins) *margins = m;
    if (const ParamStatus g = gain_status(m); g != ParamStatus::kOk) return g;
  }
  param_put(task, i, e, v);
  return ParamStatus::kOk;
}

/// Every parameter's value in one record (the slots in table order), as a store keeps it.
struct ParamRecord {
  float value[kParamSlots];
};

template <class S>
ParamRecord param_capture(const ControlTask<S>& task) {
  ParamRecord r{};
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e) r.value[param_slot(i) + e] = static_cast<float>(param_get(task, i, e));
  return r;
}

/// The table's defaults.
inline ParamRecord param_defaults() {
  ParamRecord r{};
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e) r.value[param_slot(i) + e] = static_cast<float>(param_default(i, e));
  return r;
}

/// Applies a record when every value is valid and the gains keep the observer stable (else nothing
/// changes: bad_record, unstable_observer). Needs the torque off.
template <class S>
ParamStatus param_apply(ControlTask<S>& task, const ParamRecord& r) {
  if (!param_torque_off(task)) return ParamStatus::kTorqueOn;
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e)
      if (param_value_status<S>(i, e, r.value[param_slot(i) + e]) != ParamStatus::kOk) return ParamStatus::kBadRecord;
  Gains<double> g = task.gains.template cast<double>();
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count && kParams[i].gain >= 0; ++e)
      detail::gain_put(g, kParams[i].gain, e, r.value[param_slot(i) + e]);
  if (const ParamStatus st = gain_status(gain_margins(g, task_lambda_inverse(task))); st != ParamStatus::kOk) return st;
  for (int i = 0; i < kParamCount; ++i)
    for (int e = 0; e < kParams[i].count; ++e) param_put(task, i, e, r.value[param_slot(i) + e]);
  return ParamStatus::kOk;
}

}  // namespace osc
