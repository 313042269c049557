// The fit check of a friction set (osc/control/friction_fit.hpp) alone, on given estimates: no verdict before
// params::kIdentifyNoiseSamples updates since the set, nor while the estimate's standard deviation is above
// params::kIdentifiedFraction of the set value; then one verdict per coefficient, stale beyond
// params::kSavedFitFraction either way, never changed by later estimates; a new set starts its joint's check again
// and no other's; a joint with nothing set is never judged. In double, float and Q12.19. The closed loop's check is
// test_identification's and test_identify_sim's.
#include <gtest/gtest.h>

#include <cstdint>

#include "osc/control/friction_fit.hpp"
#include "osc/math/q.hpp"

using namespace osc;

namespace {

template <class S>
void fit_verdicts() {
  const auto n = static_cast<std::uint32_t>(params::kIdentifyNoiseSamples);
  const double vis = 3.7, sum = 9.1, known = 0.02 * sum;  // a standard deviation within 2.5 % of the set value
  FrictionFit<S> f;
  f.reset();
  f.set(1, S(vis), S(sum), 100);
  f.judge(1, 1, S(20.0), S(0.0), 100 + n - 1);  // one update short of the window, however far off
  EXPECT_EQ(f.checked(), 0u);
  f.judge(1, 1, S(20.0), S(0.026 * sum * 0.026 * sum), 100 + n);  // not known well enough yet
  EXPECT_EQ(f.checked(), 0u);
  f.judge(1, 1, S(1.19 * sum), S(known * known), 100 + n);  // 19 % above: fits
  EXPECT_EQ(f.checked(), 1u << 1);
  EXPECT_EQ(f.judged[1], 1u << 1);
  EXPECT_EQ(f.stale, 0u);
  f.judge(1, 1, S(20.0), S(0.0), 100 + 5 * n);  // judged once: a later estimate changes nothing
  EXPECT_EQ(f.stale, 0u);
  f.judge(1, 0, S(0.79 * vis), S(0.0), 100 + n);  // the viscous coefficient 21 % below: stale
  EXPECT_EQ(f.judged[0], 1u << 1);
  EXPECT_EQ(f.stale, 1u << 1);
  f.set(3, S(1.0), S(2.5), 0);
  f.judge(3, 1, S(3.1), S(0.0), n);  // 24 % above: stale
  EXPECT_EQ(f.stale, (1u << 1) | (1u << 3));
  f.set(1, S(vis), S(sum), 300);  // joint 1 set again: its verdicts start again, joint 3's stay
  EXPECT_EQ(f.checked(), 1u << 3);
  EXPECT_EQ(f.stale, 1u << 3);
  f.judge(5, 1, S(2.0), S(0.0), 10 * n);  // nothing set on joint 5: never judged
  EXPECT_EQ(f.checked() & (1u << 5), 0u);
}

}  // namespace

TEST(FrictionFit, JudgesEachSetCoefficientOnceWhenKnownDouble) { fit_verdicts<double>(); }
TEST(FrictionFit, JudgesEachSetCoefficientOnceWhenKnownFloat) { fit_verdicts<float>(); }
TEST(FrictionFit, JudgesEachSetCoefficientOnceWhenKnownFixed) { fit_verdicts<Fixed>(); }
