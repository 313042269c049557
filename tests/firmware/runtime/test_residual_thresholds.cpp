// The residual monitor's thresholds (osc/runtime/residual_thresholds.hpp; docs/safety.md): the change
// channel against a slow drift and a step, a creeping joint's static band, a still joint's threshold
// against every friction preset, and the identified band narrowing a still and a sliding joint's
// thresholds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "monitor_fixtures.hpp"
#include "osc/runtime/residual_thresholds.hpp"

using namespace osc;
using namespace osc::test;

namespace {

/// A rig whose joints all move steadily at 0.5 rad/s (their encoders count every tick), held (the
/// torque that drives the arm is what was commanded less `ext`), for 2 s: long enough for the
/// static band to leave the change channel.
template <class S>
ResidualRig<S> moving_rig(const FrictionBounds<S>* proven = nullptr) {
  ResidualRig<S> rig;
  rig.proven = proven;
  rig.m.armed = true;
  rig.qd.setConstant(0.5);
  const bool all[kDof] = {true, true, true, true, true, true};
  for (int n = 0; n < 2000; ++n) {
    const std::uint32_t f = rig.step(Vec6<double>::Zero(), all, false);
    EXPECT_EQ(f, 0u) << n << " " << rig.m.r.template cast<double>().transpose() << " | "
                     << rig.m.threshold.template cast<double>().transpose() << " | "
                     << rig.m.d.template cast<double>().transpose() << " | "
                     << rig.m.change_threshold.template cast<double>().transpose();
    if (f) break;
  }
  return rig;
}

// A model error that grows slowly is little change: a ramp of slope a reaches the change residual
// as a / K_slow (the high-pass of a ramp); a step well below the absolute threshold but beyond the
// change threshold is a fault in a few ticks.
TYPED_TEST(Monitors, TheChangeChannelIgnoresASlowDriftAndCatchesAStep) {
  using S = TypeParam;
  const bool all[kDof] = {true, true, true, true, true, true};
  {
    ResidualRig<S> rig = moving_rig<S>();
    Vec6<double> slope;  // [N m/s]: d settles at a tenth of the change threshold
    for (int i = 0; i < kDof; ++i)
      slope(i) = 0.1 * static_cast<double>(rig.m.change_threshold(i)) * params::kResidualSlowGain;
    for (int n = 0; n < 2000; ++n) ASSERT_EQ(rig.step(slope * (n * params::kDt), all, false), 0u) << n;
    for (int i = 0; i < kDof; ++i) {
      // Less the filter's lag: the residual trails the ramp by 1 / K.
      const double expect = slope(i) / params::kResidualSlowGain;
      EXPECT_NEAR(static_cast<double>(rig.m.d(i)), expect, 0.05 * expect + 1e-3) << i;
      EXPECT_LT(rig.m.peak_ratio(i), lit<S>(0.2)) << i;
    }
  }
  {
    ResidualRig<S> rig = moving_rig<S>();
    const double cth = static_cast<double>(rig.m.change_threshold(1)), th = static_cast<double>(rig.m.threshold(1));
    EXPECT_LT(cth, 0.5 * th) << "a moving joint's change threshold leaves the static band out";
    Vec6<double> ext = Vec6<double>::Zero();
    ext(1) = 3 * cth;
    int n = 0;
    std::uint32_t kind = 0;
    for (; n < 100 && kind == 0; ++n) kind = rig.step(ext, all, false);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultDriveFault));
    // The step's share in d crosses 1/3 within 9 ticks (0.55 at 17 ms), then 3 ticks qualify it.
    EXPECT_LE(n, 14);
  }
}

// A joint that counts slowly one way may be creeping in stick-slip, its friction anywhere within
// the static band however steady its velocity estimate: it keeps that band in both channels
// (params::kResidualSlideInterval). The same friction flipping on a joint that counts every tick,
// sliding, is a fault: its change threshold has left the static band out.
TYPED_TEST(Monitors, ACreepingJointKeepsItsStaticBand) {
  using S = TypeParam;
  constexpr int kJ = 3;  // J4
  const ModelErrorBounds& b = robot::kModelErrorBounds;
  const double band = b.friction_hi.cou[kJ] + b.friction_hi.sti[kJ];
  // After 1 s of steady motion, an unexplained torque of +-half the band, flipping every 80 ms.
  const auto run = [&](int interval) {
    ResidualRig<S> rig;
    rig.m.armed = true;
    rig.qd(kJ) = 1 / (counts_per_rad(kJ) * interval * params::kDt);  // a count every `interval` ticks
    std::uint32_t kind = 0;
    for (int n = 0; n < 3000 && kind == 0; ++n) {
      bool counting[kDof] = {};
      counting[kJ] = n % interval == 0;
      Vec6<double> ext = Vec6<double>::Zero();
      if (n >= 1000) ext(kJ) = ((n / 80) % 2 ? 0.5 : -0.5) * band;
      kind = rig.step(ext, counting, false);
    }
    return std::make_pair(kind, static_cast<double>(rig.m.peak_ratio(kJ)));
  };
  // J4's creep in the sweep: a count every 10 ticks (0.008 rad/s at its quantum on the real arm).
  const auto [creep_kind, creep_ratio] = run(10);
  EXPECT_EQ(creep_kind, 0u);
  EXPECT_LT(creep_ratio, 0.5);
  const auto [slide_kind, slide_ratio] = run(params::kResidualSlideInterval);
  EXPECT_EQ(slide_kind, static_cast<std::uint32_t>(kFaultDriveFault)) << slide_ratio;
}

// A still joint is judged against its whole static-friction band (Coulomb plus Stribeck at the
// band's top, robot::kModelErrorBounds), which every friction preset of the arm lies within.
TEST(Residual, AStillJointsThresholdCoversTheStaticFrictionOfEveryPreset) {
  ResidualRig<double> rig;
  const bool still[kDof] = {};
  rig.step(Vec6<double>::Zero(), still);
  for (int i = 0; i < kDof; ++i) {
    for (const FrictionCoefficients* p : {&robot::kFrictionPaper, &robot::kFrictionCorke})
      EXPECT_GT(rig.m.threshold(i), params::kResidualPeakFactor[i] * (p->cou[i] + p->sti[i]) * 1.3) << i;
    EXPECT_GE(rig.m.threshold(i), params::kResidualPeakFactor[i] * (robot::kModelErrorBounds.friction_hi.cou[i] +
                                                                    robot::kModelErrorBounds.friction_hi.sti[i]))
        << i;
  }
  // The band is the presets' range widened by the drift: Corke's J1 Coulomb is the largest.
  EXPECT_NEAR(robot::kModelErrorBounds.friction_hi.cou[0], robot::kFrictionCorke.cou[0] * 1.3, 1e-12);
  EXPECT_NEAR(robot::kModelErrorBounds.friction_lo.cou[0], robot::kFrictionPaper.cou[0] * 0.7, 1e-12);
}

// The identified band narrows a still joint's thresholds too (docs/safety.md, "The identified band"):
// static friction anywhere within the proven breakaway instead of the band's top, so each threshold
// shrinks by exactly kResidualMargin times the peak factor times what the band's top exceeds the
// proven breakaway by. A joint held still for 0.3 s, then under an unexplained torque midway between
// the two thresholds, is a drive fault, where the band's top holds it without a fault (the residual
// alone: the travel check, which would name a joint held under a torque beyond its breakaway first,
// waits as it does against a contact the task reacted to).
TYPED_TEST(Monitors, AStillJointsThresholdsTakeTheIdentifiedBand) {
  using S = TypeParam;
  const FrictionCoefficients &paper = robot::kFrictionPaper, &hi = robot::kModelErrorBounds.friction_hi;
  FrictionBounds<S> proven;
  for (int i = 0; i < kDof; ++i) {
    proven.vis(i) = lit<S>(hi.vis[i]);  // the viscous band's top: only the breakaway narrows
    proven.breakaway(i) = lit<S>(1.1 * (paper.cou[i] + paper.sti[i]));
  }
  const bool still[kDof] = {};
  ResidualRig<S> top, identified;
  identified.proven = &proven;
  top.step(Vec6<double>::Zero(), still);
  identified.step(Vec6<double>::Zero(), still);
  for (int i = 0; i < kDof; ++i) {
    const double narrower = params::kResidualMargin * params::kResidualPeakFactor[i] *
                            (hi.cou[i] + hi.sti[i] - static_cast<double>(proven.breakaway(i)));
    const double t_top = static_cast<double>(top.m.threshold(i));
    EXPECT_NEAR(t_top - static_cast<double>(identified.m.threshold(i)), narrower, 1e-3 * t_top + kClosedFormTol<S>)
        << "J" << i + 1;
  }
  // Held still for 0.3 s, then pushed by `ext`: the ticks to the fault (-1: none), its kind and joint.
  const auto held_ticks = [&](const FrictionBounds<S>* band, const Vec6<double>& ext, std::uint32_t& kind, int& joint) {
    ResidualRig<S> held;
    held.proven = band;
    held.m.armed = held.m.contact = true;
    for (int n = 0; n < 300; ++n) held.step(Vec6<double>::Zero(), still);
    const int ticks = ticks_to_fault(held, ext, still, kind);
    joint = held.m.joint;
    return ticks;
  };
  for (int j : {0, 2}) {
    Vec6<double> ext = Vec6<double>::Zero();
    ext(j) = 0.5 * static_cast<double>(top.m.threshold(j) + identified.m.threshold(j));
    std::uint32_t kind = 0;
    int joint = -1;
    EXPECT_EQ(held_ticks(nullptr, ext, kind, joint), -1) << "J" << j + 1 << ": " << fault_name(kind);
    EXPECT_GT(held_ticks(&proven, ext, kind, joint), params::kResidualQualifyTicks) << "J" << j + 1;
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultDriveFault)) << "J" << j + 1 << ": " << fault_name(kind);
    EXPECT_EQ(joint, j);
  }
}

// The identified band narrows a sliding joint's Coulomb interval (docs/safety.md, "The identified
// band"): its Coulomb level is within the band and at most the proven breakaway less the Stribeck
// band's least, so with theta^ = 0 each absolute threshold shrinks by kResidualMargin times the peak
// factor times what the Coulomb band's top exceeds that by. An unexplained torque that ramps over
// 10 s (too slowly for the change channel) to midway between the two thresholds is a drive fault
// with the proven band, and nothing with the band's top.
TYPED_TEST(Monitors, ASlidingJointsThresholdsTakeTheIdentifiedBand) {
  using S = TypeParam;
  const FrictionCoefficients &paper = robot::kFrictionPaper, &lo = robot::kModelErrorBounds.friction_lo,
                             &hi = robot::kModelErrorBounds.friction_hi;
  static FrictionBounds<S> proven;
  for (int i = 0; i < kDof; ++i) {
    proven.vis(i) = lit<S>(hi.vis[i]);
    proven.breakaway(i) = lit<S>(1.1 * (paper.cou[i] + paper.sti[i]));
  }
  const ResidualRig<S> top = moving_rig<S>(), identified = moving_rig<S>(&proven);
  for (int j : {0, 2}) {
    const double cou_top = std::min(hi.cou[j], static_cast<double>(proven.breakaway(j)) - lo.sti[j]);
    const double narrower = params::kResidualMargin * params::kResidualPeakFactor[j] * (hi.cou[j] - cou_top);
    ASSERT_GT(narrower, 1.0) << "J" << j + 1;
    const double t_top = static_cast<double>(top.m.threshold(j));
    EXPECT_NEAR(t_top - static_cast<double>(identified.m.threshold(j)), narrower, 1e-3 * t_top + kClosedFormTol<S>)
        << "J" << j + 1;
    // The ramp to midway, then 0.5 s held there.
    const double mid = 0.5 * (t_top + static_cast<double>(identified.m.threshold(j)));
    const auto ramp_fault = [&](ResidualRig<S> rig) {
      const bool all[kDof] = {true, true, true, true, true, true};
      std::uint32_t kind = 0;
      for (int n = 0; n < 10500 && kind == 0; ++n) {
        Vec6<double> ext = Vec6<double>::Zero();
        ext(j) = mid * std::min(1.0, n / 10000.0);
        kind = rig.step(ext, all, false);
      }
      return std::make_pair(kind, static_cast<int>(rig.m.joint));
    };
    EXPECT_EQ(ramp_fault(top).first, 0u) << "J" << j + 1;
    const auto [kind, joint] = ramp_fault(identified);
    EXPECT_EQ(kind, static_cast<std::uint32_t>(kFaultDriveFault)) << "J" << j + 1 << ": " << fault_name(kind);
    EXPECT_EQ(joint, j);
  }
}

}  // namespace
