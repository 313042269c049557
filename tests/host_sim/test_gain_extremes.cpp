// Issue 53, defect 4: a value that is accepted must run. Every parameter of the runtime table set to
// each end of its range (the others at their defaults), then an enable of the simulated arm: the
// set is accepted (or, in a scalar that cannot hold the value, refused out_of_range) and the arm
// holds for 3 s without a fault, the oscillation monitor within half its limit. Before the fix, k_s = 1e5 (then inside
// its range) was accepted and latched non_finite 21 ms after the enable. The gains' ranges were set on the PUMA
// (params.hpp): on another arm a bound that would lose its loop is refused by name (unstable_loop,
// unstable_observer), counted and printed; on the PUMA none is.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "motion_sim.hpp"
#include "osc/runtime/parameters.hpp"
#include "test_util.hpp"

using namespace osc;
using sim::MotionSim;

namespace {

sim::Vec6 start_pose() { return joint_vector<double>(robot::kQStart); }

struct Held {
  std::uint32_t faults = 0;
  MotionState state = MotionState::kDisabled;
  double tip_moved = 0;  // largest |tip - tip at the enable| [m]
  double shaking = 0;    // the oscillation monitor's largest ratio to its limit, any joint
};

/// Element e of parameter i (every element when e < 0) set to its bound, an enable, 3 s of holding.
template <class S>
ParamStatus set_and_hold(int i, int e, bool top, Held& h) {
  MotionSim<S> sim(start_pose());
  const ParamInfo& p = kParams[i];
  // A payload's products are bounded by its moments (positive semi-definite): the moments at their top
  // first, where a product is set (not_physical otherwise).
  const bool inertia = p.runtime == RuntimeParam::kParamPayloadInertia;
  if (inertia && (e < 0 || e >= 3))
    for (int k = 0; k < 3; ++k)
      if (const ParamStatus s = param_set(sim.task(), i, k, p.hi_of(k)); s != ParamStatus::kOk) return s;
  for (int k = 0; k < p.count; ++k) {
    if ((e >= 0 && k != e) || (inertia && e < 0 && k < 3)) continue;
    // Every product at its bound together is no body's (three of them at their bottom, or one after
    // another at their top): a quarter of it, with the moments at their top.
    const double v = (top ? p.hi_of(k) : p.lo_of(k)) * (inertia && e < 0 ? 0.25 : 1.0);
    const ParamStatus s = param_set(sim.task(), i, k, v);
    if (s != ParamStatus::kOk) return s;
  }
  sim.command(MotionVerb::kEnable, 1);
  const sim::Vec3 tip0 = sim.tip();
  for (int n = 0; n < 3000; ++n) {
    h.faults |= sim.tick();
    h.tip_moved = std::max(h.tip_moved, (sim.tip() - tip0).norm());
    for (int j = 0; j < kDof; ++j) h.shaking = std::max(h.shaking, sim.task().oscillation.ratio(j));
  }
  h.state = sim.task().machine.state;
  return ParamStatus::kOk;
}

/// Every bound of every parameter, element by element (each_element) or all elements at once.
template <class S>
void every_bound_holds(bool each_element) {
  int runs = 0, refused = 0;
  double shaking = 0;
  for (int i = 0; i < kParamCount; ++i) {
    const ParamInfo& p = kParams[i];
    for (int e = each_element ? 0 : -1; e < (each_element ? p.count : 0); ++e)
      for (const bool top : {false, true}) {
        Held h;
        const ParamStatus s = set_and_hold<S>(i, e, top, h);
        char what[64];
        if (e >= 0)
          std::snprintf(what, sizeof what, "%s[%d] at its %s", p.name, e, top ? "top" : "bottom");
        else
          std::snprintf(what, sizeof what, "%s at its %s", p.name, top ? "top" : "bottom");
        if (s == ParamStatus::kOutOfRange) {  // only where the scalar cannot hold the bound
          EXPECT_GE(top ? p.hi_of(std::max(e, 0)) : -p.lo_of(std::max(e, 0)), param_scalar_max<S>() - 1) << what;
          continue;
        }
        if (!test::kPumaBuild && (s == ParamStatus::kUnstableLoop || s == ParamStatus::kUnstableObserver)) {
          std::printf("%s: refused %s on this arm\n", what, param_status_name(s));
          ++refused;
          continue;
        }
        ASSERT_EQ(s, ParamStatus::kOk) << what;
        ++runs;
        EXPECT_EQ(h.faults, 0u) << what << ": " << fault_name(h.faults);
        EXPECT_EQ(h.state, MotionState::kHolding) << what;
        // The friction law's estimate at its top (theta_max, three times the largest published friction) is
        // over-compensation, not a gain: the arm creeps at the enable (measured 6.2 mm on J1 alone, 8.0 mm with
        // every joint's) and holds, with no fault. A saved estimate that no longer fits is issue 57's staleness check.
        const bool estimate = p.runtime == RuntimeParam::kParamFrictionVis ||
                              p.runtime == RuntimeParam::kParamFrictionCou ||
                              p.runtime == RuntimeParam::kParamFrictionSti;
        EXPECT_LT(h.tip_moved, estimate && top ? 0.01 : 0.005) << what;
        // The quantisation's noise through the highest gains shakes the torques at half the tick rate, bounded:
        // the oscillation monitor's healthy margin (docs/safety.md, "The oscillation monitor").
        EXPECT_LE(h.shaking, 0.5) << what;
        shaking = std::max(shaking, h.shaking);
      }
  }
  EXPECT_GT(runs + refused, 2 * kParamCount - 8);
  EXPECT_LE(refused, runs / 4) << "most bounds are taken on any arm";
  std::printf("%s: %d runs, %d refused by name; the oscillation monitor at most %.3f of its limit\n",
              each_element ? "each element" : "each parameter", runs, refused, shaking);
}

TEST(GainExtremes, EveryElementsBoundsHoldTheArmDouble) { every_bound_holds<double>(true); }
TEST(GainExtremes, EveryParametersBoundsHoldTheArmFloat) { every_bound_holds<float>(false); }
TEST(GainExtremes, EveryParametersBoundsHoldTheArmFixed) { every_bound_holds<Fixed>(false); }

/// The defect's own value, now outside the range, and the old range's top through the controller:
/// a loop the check would refuse latches a fault within a fraction of a second (the check is not
/// idle caution).
TEST(GainExtremes, TheOldRangesTopFaultsTheArm) {
  const int ks = param_index("ks");
  MotionSim<double> sim(start_pose());
  EXPECT_EQ(param_set(sim.task(), ks, 0, 1e5), ParamStatus::kOutOfRange);
  sim.task().gains.ks.setConstant(1e5);  // what the old range let through
  sim.command(MotionVerb::kEnable, 1);
  std::uint32_t faults = 0;
  int n = 0;
  for (; n < 1000 && faults == 0; ++n) faults |= sim.tick();
  EXPECT_NE(faults, 0u);
  EXPECT_LT(n, 200);
  EXPECT_EQ(sim.task().machine.state, MotionState::kFault);
}

}  // namespace
