// The controller's tunable parameters: gains (69), K_ad, tau_dec, the sample time, the task's
// trajectory (68), and the choices a caller makes (friction mode, adaptation law). Defaults from params.hpp; the
// adaptation law defaults to the momentum law (kDefaultAdaptationLaw, docs/adaptation.md); AdaptationLaw::kPaper
// gives (67) exactly, kRobust the robust law.
#pragma once

#include <cstdint>
#include <string_view>
#include <type_traits>

#include "osc/control/params.hpp"
#include "osc/control/trajectory.hpp"
#include "osc/kernels/model.hpp"

namespace osc {

/// With adaptive friction compensation (Table I), or without (f^ = 0, no adaptation: Table III).
enum class FrictionMode : std::uint8_t { kAdaptive, kNone };

/// The law that updates the friction estimates (osc/control/adaptation.hpp).
enum class AdaptationLaw : std::uint8_t {
  kPaper,     ///< the paper's sampled law (67), exactly
  kRobust,    ///< (67)'s error with the regressor one sample older, projection, leakage
  kMomentum,  ///< identified from the residual monitor's momentum residual, a Kalman filter per joint
              ///< (osc/control/identification.hpp): the control step holds theta^, the task updates it
};
/// The default law (Gains::paper(), the runtime parameter adaptation): the momentum law, as fast as
/// (67) in the first minutes and bounded for hours (docs/adaptation.md, section 5).
constexpr AdaptationLaw kDefaultAdaptationLaw = AdaptationLaw::kMomentum;
/// Names of the laws, in enum order (command lines, logs).
constexpr const char* kAdaptationLawNames[] = {"paper", "robust", "momentum"};
constexpr int kAdaptationLawCount = sizeof(kAdaptationLawNames) / sizeof(kAdaptationLawNames[0]);

constexpr const char* adaptation_law_name(AdaptationLaw law) { return kAdaptationLawNames[static_cast<int>(law)]; }
/// The law of a name; false when there is none.
constexpr bool adaptation_law_from_name(std::string_view name, AdaptationLaw& law) {
  for (int i = 0; i < kAdaptationLawCount; ++i)
    if (name == kAdaptationLawNames[i]) {
      law = static_cast<AdaptationLaw>(i);
      return true;
    }
  return false;
}

/// How often the control step refreshes the arm's dynamics model (controller.hpp, dynamics_turn). The kinematics
/// (x, J and its factors), the observer, the controller and the adaptation run every step either way.
enum class ModelRate : std::uint8_t {
  kEveryStep,  ///< A(q), its factors, g(q) and Psi's velocity products every step (the paper's sampled law)
  kAlternate,  ///< A(q), its factors and g(q) on one step, Psi's velocity products on the next, each held for the
               ///< step between: the dynamics at half the rate, each term at most one period old
};
/// The default rate (Gains::paper()): alternate, the firmware's tick budget (docs/benchmarks.md).
constexpr ModelRate kDefaultModelRate = ModelRate::kAlternate;
/// Names of the rates, in enum order (command lines, logs).
constexpr const char* kModelRateNames[] = {"every_step", "alternate"};
constexpr int kModelRateCount = sizeof(kModelRateNames) / sizeof(kModelRateNames[0]);

namespace detail {
/// A gain's paper value in the scalar of its field: a list of params.hpp, a number (every element of
/// a vector gets it), or a value of the field's own type (an enum, the trajectory).
template <class Field, class V>
Field gain_value(const V& v) {
  if constexpr (requires { Field::RowsAtCompileTime; }) {
    using S = typename Field::Scalar;
    Field f;
    for (int i = 0; i < Field::RowsAtCompileTime; ++i) {
      if constexpr (std::is_arithmetic_v<V>)
        f(i) = lit<S>(v);
      else
        f(i) = lit<S>(v[i]);
    }
    return f;
  } else if constexpr (std::is_arithmetic_v<V>) {
    return lit<Field>(v);
  } else {
    return v;
  }
}
/// A gain in another scalar T: Eigen vectors and the trajectory cast, numbers converted, enums kept.
template <class T, class Field>
auto gain_cast(const Field& v) {
  if constexpr (requires { v.template cast<T>(); })
    return v.template cast<T>();
  else if constexpr (std::is_enum_v<Field>)
    return v;
  else
    return static_cast<T>(v);
}
}  // namespace detail

/// Whether and how a parameter is set from outside the firmware (GainParam).
enum class GainForm : std::uint8_t {
  kNone,     ///< not from outside: a build constant, or set through keys of its own (the law, the task)
  kPerAxis,  ///< a list of six numbers, one per axis or joint
  kOne,      ///< one number
  kEvery,    ///< one number, given to every element of the vector
};

/// A parameter's facts for the tables that set it (the host experiment's controller.<key> entries,
/// later the runtime parameter tables): its key, form, accepted range (of each element) and unit.
struct GainParam {
  const char* key;
  GainForm form;
  double lo, hi;                    ///< the range of every element (with lo_each / hi_each: the bounds of theirs)
  const char* unit;                 ///< "" where it has none (the gains of (69))
  const double* lo_each = nullptr;  ///< each element's range, where the axes' differ (kPerAxis)
  const double* hi_each = nullptr;

  constexpr double lo_of(int e) const { return lo_each ? lo_each[e] : lo; }
  constexpr double hi_of(int e) const { return hi_each ? hi_each[e] : hi; }
};
namespace gain_param {
constexpr GainParam per_axis(const char* key, double lo, double hi, const char* unit = "") {
  return {key, GainForm::kPerAxis, lo, hi, unit};
}
/// Six numbers, each element within its own range (the translational axes' and the rotations').
constexpr GainParam per_axis(const char* key, const double (&lo)[6], const double (&hi)[6]) {
  double l = lo[0], h = hi[0];
  for (int i = 1; i < 6; ++i) l = lo[i] < l ? lo[i] : l, h = hi[i] > h ? hi[i] : h;
  return {key, GainForm::kPerAxis, l, h, "", lo, hi};
}
constexpr GainParam one(const char* key, double lo, double hi, const char* unit = "") {
  return {key, GainForm::kOne, lo, hi, unit};
}
constexpr GainParam every(const char* key, double lo, double hi, const char* unit = "") {
  return {key, GainForm::kEvery, lo, hi, unit};
}
constexpr GainParam none() { return {"", GainForm::kNone, 0, 0, ""}; }
}  // namespace gain_param

// X(type, name, paper value, meaning, parameter): the controller's parameters, each declared once;
// the struct, Gains::paper(), Gains::cast() and kGainInfo are made from this list, and the host
// experiment's controller.<key> entries (host_sim/config.cpp) from its parameter column.
#define OSC_GAINS_FIELDS(X)                                                                                          \
  X(Vec6<S>, knd, params::kKnd, "observer gain k_nd of (69), per axis x y z rx ry rz",                               \
    gain_param::per_axis("knd", osc::params::kKndRange[0], osc::params::kKndRange[1]))                               \
  X(Vec6<S>, k, params::kK, "observer gain k of (69)",                                                               \
    gain_param::per_axis("k", osc::params::kKRange[0], osc::params::kKRange[1]))                                     \
  X(Vec6<S>, ks, params::kKs, "controller gain k_s of (69)",                                                         \
    gain_param::per_axis("ks", osc::params::kKsRange[0], osc::params::kKsRange[1]))                                  \
  X(Vec6<S>, ki, params::kKi, "controller gain k_i of (69)",                                                         \
    gain_param::per_axis("ki", osc::params::kKiRange[0], osc::params::kKiRange[1]))                                  \
  X(S, kad, params::kKad, "adaptation gain: every diagonal entry of K_ad", gain_param::one("k_ad", 0, 1e5))          \
  X(Vec6<S>, tau_dec, params::kTauDec, "the controller's Stribeck decay tau_dec of model (2), every joint",          \
    gain_param::every("tau_dec", 0.01, 100, "s^2/rad^2"))                                                            \
  X(S, dt, params::kDt, "the sample time [s]", gain_param::none())                                                   \
  X(S, min_rcond, params::kMinJacobianRcond, "the Jacobian test's least reciprocal condition", gain_param::none())   \
  X(AdaptationLaw, adaptation, kDefaultAdaptationLaw, "the friction adaptation law", gain_param::none())             \
  X(ModelRate, model_rate, kDefaultModelRate, "how often the step refreshes the dynamics model", gain_param::none()) \
  X(Vec18<S>, theta_max, params::kThetaMax, "projection bounds of the robust law (lower bounds 0)",                  \
    gain_param::none())                                                                                              \
  X(S, leakage, params::kAdaptationLeakage, "leakage sigma of the robust law",                                       \
    gain_param::one("leakage", 0, 1, "1/s"))                                                                         \
  X(TrajectorySpec<S>, trajectory, TrajectorySpec<S>::paper(), "the task (68)", gain_param::none())

/// Each parameter's name, meaning and parameter facts, in the list's order.
struct GainInfo {
  const char* name;
  const char* doc;
  GainParam param;
};
inline constexpr GainInfo kGainInfo[] = {
#define OSC_GAINS_INFO(type, name, paper, doc, param) {#name, doc, param},
    OSC_GAINS_FIELDS(OSC_GAINS_INFO)
#undef OSC_GAINS_INFO
};

template <class S>
struct Gains {
#define OSC_GAINS_MEMBER(type, name, paper, doc, param) type name;
  OSC_GAINS_FIELDS(OSC_GAINS_MEMBER)
#undef OSC_GAINS_MEMBER

  /// The paper's set-up (params.hpp) and the firmware's default law.
  static Gains paper() {
    Gains g;
#define OSC_GAINS_PAPER(type, name, paper, doc, param) g.name = detail::gain_value<type>(paper);
    OSC_GAINS_FIELDS(OSC_GAINS_PAPER)
#undef OSC_GAINS_PAPER
    return g;
  }

  /// The same parameters in another scalar (the host's experiment configures them in double).
  template <class T>
  Gains<T> cast() const {
    Gains<T> g;
#define OSC_GAINS_CAST(type, name, paper, doc, param) g.name = detail::gain_cast<T>(name);
    OSC_GAINS_FIELDS(OSC_GAINS_CAST)
#undef OSC_GAINS_CAST
    return g;
  }
};

}  // namespace osc
