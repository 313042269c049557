// The fit check of a friction set (issue 57; docs/adaptation.md, "A saved friction that no longer fits the arm"):
// whether the friction the momentum law was given (a saved record applied at power-on, an identify run's applied)
// fits the arm, judged once per joint and coefficient against what the law then identifies
// (FrictionIdentifier::seed gives it, FrictionIdentifier::update asks it after each update).
#pragma once

#include <cstdint>

#include "osc/control/params.hpp"
#include "osc/kernels/model.hpp"

namespace osc {

template <class S>
struct FrictionFit {
  /// The friction set last, each joint's viscous coefficient (row 0) and breakaway torque (row 1, Coulomb +
  /// Stribeck) in the identifier's units of the joint; 0 where none is set.
  Eigen::Matrix<S, 2, kDof> given;
  /// Bit i joint i: judged[c], coefficient c (0 viscous, 1 breakaway) compared once with the law's estimate since the
  /// set; stale, a comparison found it more than params::kSavedFitFraction off.
  std::uint8_t judged[2];
  std::uint8_t stale;
  std::uint32_t seeded[kDof];  // the joint's update count at its last set: judge waits kIdentifyNoiseSamples more

  void reset() {
    given.setZero();
    judged[0] = judged[1] = stale = 0;
    for (int i = 0; i < kDof; ++i) seeded[i] = 0;
  }
  /// Joint i set to viscous coefficient `vis` and breakaway torque `sum` (its units) at its update count `updates`:
  /// its check starts again.
  void set(int i, S vis, S sum, std::uint32_t updates) {
    given(0, i) = vis;
    given(1, i) = sum;
    seeded[i] = updates;
    const auto keep = static_cast<std::uint8_t>(~(1u << i));
    judged[0] &= keep, judged[1] &= keep, stale &= keep;
  }
  /// Joints whose set friction has been checked, a bit each.
  std::uint8_t checked() const { return static_cast<std::uint8_t>(judged[0] | judged[1]); }

  /// Joint i's check after an update, its estimate `value` of coefficient c and that estimate's variance `var` (its
  /// units), `updates` its update count: the first time since the set that the law knows coefficient c within
  /// params::kIdentifiedFraction of the set value (its standard deviation: the bar, params::kSavedFitFraction of it,
  /// is then eight of them, whether the arm's is lower or higher) with at least params::kIdentifyNoiseSamples updates
  /// since the set (the noise measure's window: before it the estimate is still on its way from the set value, and
  /// its deviation not yet the data's), the set one is judged, once: stale when it lies more than
  /// params::kSavedFitFraction of itself from the estimate. Later drift (temperature: the band's +-30 %) is the
  /// law's to follow, not a verdict on what was set.
  void judge(int i, int c, S value, S var, std::uint32_t updates) {
    static constexpr S kFraction = lit<S>(params::kIdentifiedFraction);
    static constexpr S kFit = lit<S>(params::kSavedFitFraction);
    const auto bit = static_cast<std::uint8_t>(1u << i);
    const bool settled = updates - seeded[i] >= static_cast<std::uint32_t>(params::kIdentifyNoiseSamples);
    const S ref = given(c, i), f = kFraction * ref, d = value - ref, lim = kFit * ref;
    const bool open = settled && !(judged[c] & bit) && ref > S(0) && var <= f * f;
    if (!open && !params::kTickWorstCase) return;
    judged[c] |= bit;
    if (d > lim || -d > lim) stale |= bit;
  }
};

}  // namespace osc
