// The friction model (osc/kernels/friction.hpp) on random velocities (props_fixture.hpp): (18)-(19)
// W_j(qd) theta = the friction torque (2), including joints at rest (sgn 0 = 0).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "osc/kernels/friction.hpp"
#include "props_fixture.hpp"

using namespace osc;
using namespace osc::test;

namespace {

TEST_F(Props, FrictionRegressorReproducesModel2IncludingZeroVelocity) {
  FrictionParams<double> p;
  for (int i = 0; i < kDof; ++i) {
    p.vis(i) = robot::kFrictionPaper.vis[i];
    p.cou(i) = robot::kFrictionPaper.cou[i];
    p.sti(i) = robot::kFrictionPaper.sti[i];
    p.dec(i) = 0.5 + i;
  }
  const Vec18<double> theta = p.theta();
  for (int k = 0; k < kStates; ++k) {
    Vec6<double> qd = rs.vec(2.0);
    const int rest = k % kDof;
    qd(rest) = 0.0;                                // sgn(0) = 0: no friction on a joint at rest
    if (k % 3 == 0) qd((rest + 3) % kDof) = -0.0;  // negative zero too
    Vec6<double> tau, tw;
    Regressor<double> W;
    {
      NoMalloc guard;
      tau = friction_torque(p, qd);
      W = friction_regressor(qd, p.dec);
      tw = W * theta;
    }
    EXPECT_LT((tau - tw).norm(), 1e-12 * std::max(tau.norm(), 1.0));
    // Model (2) written out independently.
    for (int i = 0; i < kDof; ++i) {
      const double s = qd(i) > 0 ? 1 : (qd(i) < 0 ? -1 : 0);
      EXPECT_NEAR(tau(i), p.vis(i) * qd(i) + (p.cou(i) + p.sti(i) * std::exp(-p.dec(i) * qd(i) * qd(i))) * s, 1e-12);
      if (qd(i) == 0.0) {
        EXPECT_EQ(tau(i), 0.0);
        EXPECT_EQ(tw(i), 0.0);
        EXPECT_EQ(W.row(i).cwiseAbs().maxCoeff(), 0.0);
      }
    }
  }
}

}  // namespace
