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
// This header holds the table (kParams) and its addressing; osc/runtime/parameters.hpp reads and
// writes the task through it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "osc/control/gains.hpp"
#include "osc/control/stream.hpp"
#include "osc/robot.hpp"
#include "osc/runtime/motion_states.hpp"

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
  X(NotPhysical, "not_physical",                                                                                  \
    "the payload's inertia would not be positive semi-definite (set the moments before the products)")            \
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
/// The pots parameter's default and largest value: 1 where the arm is described with potentiometers.
constexpr double kPotsWired = has_pots(robot::kDriveTrain) ? 1 : 0;
/// The drive_check parameter's default and largest value: 1 where the arm is described with current monitors.
constexpr double kCurrentWired = has_current_monitors(robot::kDriveTrain) ? 1 : 0;
/// The payload's envelope (robot::kPayloadRating): its centre of mass within +-com_reach in each
/// coordinate of frame 6; its moments within [0, inertia], its products within +-inertia.
constexpr double kPayloadComLo = -robot::kPayloadRating.com_reach;
constexpr double kPayloadInertiaLo[6] = {
    0, 0, 0, -robot::kPayloadRating.inertia, -robot::kPayloadRating.inertia, -robot::kPayloadRating.inertia};
constexpr double kPayloadInertiaHi[6] = {robot::kPayloadRating.inertia, robot::kPayloadRating.inertia,
                                         robot::kPayloadRating.inertia, robot::kPayloadRating.inertia,
                                         robot::kPayloadRating.inertia, robot::kPayloadRating.inertia};
/// The drives' armature correction's range (parameter armature_correction): each joint's within
/// [-0.2, 3] times its described armature G^2 Jm, plus 0.01 kg m^2 above (a drive described without
/// one). Above, the range holds the published motor inertias' spread three times over (the PUMA's
/// AKB86 set, robot::kDriveTrain.motor_inertia_alt: +45 / +105 / +50 % on J1-J3). Below, a lighter
/// armature is a larger inverse mass: on the PUMA at the paper's gains every drive 25 % lighter at once
/// still keeps the sampled loop stable, 30 % does not (J4's alone at 50 % does not either), so a drive
/// is taken as at most 20 % lighter than described (the gain tests run every bound).
constexpr double described_armature(int i) {
  return robot::kArm.links[i].gear_ratio * robot::kArm.links[i].gear_ratio * robot::kArm.links[i].motor_inertia;
}
constexpr double kArmatureCorrectionLo[kDof] = {-0.2 * described_armature(0), -0.2 * described_armature(1),
                                                -0.2 * described_armature(2), -0.2 * described_armature(3),
                                                -0.2 * described_armature(4), -0.2 * described_armature(5)};
constexpr double kArmatureCorrectionHi[kDof] = {3 * described_armature(0) + 0.01, 3 * described_armature(1) + 0.01,
                                                3 * described_armature(2) + 0.01, 3 * described_armature(3) + 0.01,
                                                3 * described_armature(4) + 0.01, 3 * described_armature(5) + 0.01};
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
  X(Pots, "pots", 1, "", 0, detail::kPotsWired, detail::kPotsWired, TorqueOff, true,                                  \
    "1: the arm's potentiometers are wired (the position cross-check runs); 0: an arm without them (its only value "  \
    "on an arm described without potentiometers)")                                                                    \
  X(HomeSpeed, "home_speed", 2, "m/s, rad/s", detail::kHomeSpeedLo, detail::kHomeSpeedHi, params::kHomeSpeed, Always, \
    true, "the homing move's speeds: the wrist centre's, the rotation's (accelerations, jerks: the move's)")          \
  X(ResidualMonitor, "residual_monitor", 1, "", 0, 1, params::kResidualMonitorArmed ? 1 : 0, TorqueOff, true,         \
    "1: the residual monitor armed: it raises encoder_stuck, drive_fault, collision (the stuck-encoder "              \
    "monitor off but homing); 0: a trial (recorded; the stuck-encoder monitor raises encoder_stuck)")                 \
  X(DriveCheck, "drive_check", 1, "", 0, detail::kCurrentWired, detail::kCurrentWired, TorqueOff, true,               \
    "1: the amplifiers' current monitors are wired (the drive check runs: drive_fault, current_sense; a residual "    \
    "on a healthy drive is a collision); 0: none (its only value on an arm described without them)")                  \
  X(DitherAmplitude, "dither_amplitude", 1, "of full scale", 0, 0.05, params::kDitherAmplitude, TorqueOff, true,      \
    "the drive check's test dither on each DAC code, a fraction of its full scale (0: off: a DAC frozen at rest "     \
    "is not found)")                                                                                                  \
  X(DitherHalfPeriod, "dither_half_period", 1, "ticks", 2, 8, params::kDitherHalfPeriod, TorqueOff, true,             \
    "the test dither's half period: a square wave of 1000 / (2 n) Hz (n = 4: 125 Hz)")                                \
  X(PayloadMass, "payload_mass", 1, "kg", 0, robot::kPayloadRating.mass, 0, TorqueOff, true,                          \
    "the payload's mass at the flange (a tool, a part in the gripper): the model's link 6 carries it, up to the "     \
    "arm's rating")                                                                                                   \
  X(PayloadCom, "payload_com", 3, "m", detail::kPayloadComLo, robot::kPayloadRating.com_reach, 0, TorqueOff, true,    \
    "the payload's centre of mass in frame 6 (the flange), each coordinate within the arm's stated reach")            \
  X(PayloadInertia, "payload_inertia", 6, "kg m^2", detail::kPayloadInertiaLo, detail::kPayloadInertiaHi, 0,          \
    TorqueOff, true,                                                                                                  \
    "the payload's inertia about its centre of mass, frame-6 axes: Ixx, Iyy, Izz, Ixy, Ixz, Iyz; positive "           \
    "semi-definite (else not_physical): set the moments before the products")                                         \
  X(PayloadAllowance, "payload_allowance", 1, "kg", 0, robot::kPayloadRating.mass, 0, TorqueOff, false,               \
    "a payload not yet identified: the residual monitor allows a weight of up to this mass either way at the "        \
    "flange (its thresholds raised by it: less sensitive to a collision); set before the enable of an identify "      \
    "run with --payload, whose --apply sets it back to 0; not saved (0 at power-on)")                                 \
  X(ArmatureCorrection, "armature_correction", kDof, "kg m^2", detail::kArmatureCorrectionLo,                         \
    detail::kArmatureCorrectionHi, 0, TorqueOff, true,                                                                \
    "each drive's armature correction, added to its described G^2 Jm on the diagonal of the model's A(q) (an "        \
    "identify run's estimate); the sampled loop stays stable at the last computed pose (else unstable_loop)")         \
  X(FrictionVis, "friction_vis", kDof, "N m s/rad", 0, params::kThetaMax, 0, TorqueOff, true,                         \
    "the friction law's estimate theta^ (20), viscous, each drive's (a joint's if uncoupled): read, what it has "     \
    "learnt; set (an identify run's, a saved record's at power-on), where it goes on from; within [0, the robust "    \
    "law's bound theta_max]")                                                                                         \
  X(FrictionCou, "friction_cou", kDof, "N m", 0, params::kThetaMax + kDof, 0, TorqueOff, true,                        \
    "the same of the Coulomb levels")                                                                                 \
  X(FrictionSti, "friction_sti", kDof, "N m", 0, params::kThetaMax + 2 * kDof, 0, TorqueOff, true,                    \
    "the same of the Stribeck excesses")

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

}  // namespace osc
