// The controller's tunable parameters: gains (69), K_ad, tau_dec, the sample time, the task's
// trajectory (68), and the choices a caller makes (friction mode, adaptation law). Defaults from params.hpp; the
// adaptation law defaults to the robust one (docs/adaptation.md); AdaptationLaw::kPaper gives (67) exactly.
#pragma once

#include <cstdint>
#include <string_view>

#include "osc/control/params.hpp"
#include "osc/control/trajectory.hpp"
#include "osc/kernels/model.hpp"

namespace osc {

/// With adaptive friction compensation (Table I), or without (f^ = 0, no adaptation: Table III).
enum class FrictionMode : std::uint8_t { kAdaptive, kNone };

/// The law that updates the friction estimates (osc/control/adaptation.hpp).
enum class AdaptationLaw : std::uint8_t {
  kPaper,   ///< the paper's sampled law (67), exactly
  kRobust,  ///< (67)'s error with the regressor one sample older, projection, leakage (the default)
};
/// Names of the laws, in enum order (command lines, logs).
constexpr const char* kAdaptationLawNames[] = {"paper", "robust"};
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

template <class S>
struct Gains {
  Vec6<S> knd, k, ks, ki;
  S kad;
  Vec6<S> tau_dec;
  S dt;
  S min_rcond;
  AdaptationLaw adaptation;
  Vec18<S> theta_max;            // projection bounds of the robust law (lower bounds 0)
  S leakage;                     // sigma of the robust law [1/s]
  TrajectorySpec<S> trajectory;  // the task (68)

  static Gains paper() {
    Gains g;
    for (int i = 0; i < kDof; ++i) {
      g.knd(i) = lit<S>(params::kKnd[i]);
      g.k(i) = lit<S>(params::kK[i]);
      g.ks(i) = lit<S>(params::kKs[i]);
      g.ki(i) = lit<S>(params::kKi[i]);
      g.tau_dec(i) = lit<S>(params::kTauDec);
    }
    g.kad = lit<S>(params::kKad);
    g.dt = lit<S>(params::kDt);
    g.min_rcond = lit<S>(params::kMinJacobianRcond);
    g.adaptation = AdaptationLaw::kRobust;
    for (int i = 0; i < 3 * kDof; ++i) g.theta_max(i) = lit<S>(params::kThetaMax[i]);
    g.leakage = lit<S>(params::kAdaptationLeakage);
    g.trajectory = TrajectorySpec<S>::paper();
    return g;
  }

  /// The same parameters in another scalar (the host's experiment configures them in double).
  template <class T>
  Gains<T> cast() const {
    Gains<T> g;
    g.knd = knd.template cast<T>();
    g.k = k.template cast<T>();
    g.ks = ks.template cast<T>();
    g.ki = ki.template cast<T>();
    g.kad = static_cast<T>(kad);
    g.tau_dec = tau_dec.template cast<T>();
    g.dt = static_cast<T>(dt);
    g.min_rcond = static_cast<T>(min_rcond);
    g.adaptation = adaptation;
    g.theta_max = theta_max.template cast<T>();
    g.leakage = static_cast<T>(leakage);
    g.trajectory = trajectory.template cast<T>();
    return g;
  }
};

}  // namespace osc
