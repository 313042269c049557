// The friction adaptation's stages (osc/control/adaptation.hpp): the momentum law's stage
// (adaptation_identify, with its input MomentumSample) is the identifier's update on the adaptation's
// own state, taking turns as the identifier does; the paper's and the robust law leave the momentum
// law's filter alone and the momentum law leaves theta^ to its stage; a restart keeps what the laws
// learnt and an init forgets it.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "osc/control/controller.hpp"

using namespace osc;

namespace {

/// The band's tops of the friction (the identifier's prior: what it proves before a sample).
FrictionBounds<double> band() {
  auto id = std::make_unique<FrictionIdentifier<double>>();
  id->reset();
  return id->proven;
}

/// A friction sample of joint j: the regressor at a velocity of a sinusoid and y = phi^T theta, theta
/// within the band (vis half its top, cou and sti 0.3 and 0.2 of the breakaway's), the joint moving
/// long enough.
FrictionSample<double> sample_at(int k, const Gains<double>& G, int j) {
  static const FrictionBounds<double> kBand = band();
  const double tau_dec = G.tau_dec(j);
  const Vec3<double> theta(0.5 * kBand.vis(j), 0.3 * kBand.breakaway(j), 0.2 * kBand.breakaway(j));
  const double qd = 0.4 * std::sin(0.013 * k) + 0.05 * std::sin(0.21 * k);
  const double sgn = qd > 0 ? 1.0 : (qd < 0 ? -1.0 : 0.0);
  FrictionSample<double> s;
  s.phi = Vec3<double>(qd, sgn, sgn * std::exp(-tau_dec * qd * qd));
  s.y = s.phi.dot(theta);
  s.gravity = 0;
  s.settled = true;
  return s;
}

Gains<double> momentum_gains() {
  Gains<double> g = Gains<double>::paper();
  g.adaptation = AdaptationLaw::kMomentum;
  return g;
}

}  // namespace

// The stage on the adaptation's state is the identifier's update with the sample's fields, bit for bit,
// turn by turn; it moves theta^ (the law learns), and only the sampled joint's coefficients each time.
TEST(Adaptation, MomentumStageIsTheIdentifiersUpdateOnItsInput) {
  const Gains<double> G = momentum_gains();
  auto a = std::make_unique<AdaptationState<double>>();
  adaptation_init(*a, Vec6<double>(Vec6<double>::Zero()));
  auto ref = std::make_unique<FrictionIdentifier<double>>();
  ref->reset();
  Vec18<double> theta_ref = Vec18<double>::Zero();
  for (int k = 0; k < 6000; ++k) {
    const int j = momentum_turn(*a);
    ASSERT_EQ(j, ref->take_turn());
    const FrictionSample<double> fs = sample_at(k, G, j);
    const bool low = k % 7 != 0;  // some samples with the residual high: refused by the gate
    const MomentumSample<double> in{j, fs, low, 0.01, 3.0};
    const Vec18<double> before = a->theta_hat;
    const IdentifyOutcome got = adaptation_identify(G, *a, in);
    ASSERT_EQ(got, ref->update(j, fs, low, 0.01, 3.0, theta_ref, G.theta_max)) << k;
    for (int i = 0; i < 3 * kDof; ++i) {
      ASSERT_EQ(a->theta_hat(i), theta_ref(i)) << k << " " << i;
      if (i % kDof != j) {
        ASSERT_EQ(a->theta_hat(i), before(i)) << "only joint " << j << " moves";
      }
    }
    // theta^ is the stage's alone under this law: the step's law leaves it.
    ASSERT_EQ(adaptation_step(G, *a, Vec6<double>(Vec6<double>::Ones())), a->theta_hat);
  }
  for (int j = 0; j < kDof; ++j) {
    EXPECT_EQ(a->identifier.updates[j], ref->updates[j]);
    EXPECT_GT(a->identifier.updates[j], 100u) << j;
    const double sum = 0.5 * band().breakaway(j);
    EXPECT_NEAR(a->theta_hat(kDof + j) + a->theta_hat(2 * kDof + j), sum, 0.1 * sum) << "J" << j + 1 << "'s sum learnt";
  }
}

// controller_restart (an enable, a homing's end) keeps theta^ and the momentum law's filter, and starts
// the samples anew; controller_init starts both at the prior.
TEST(Adaptation, RestartKeepsWhatTheLawsLearntAndInitForgetsIt) {
  const Gains<double> G = momentum_gains();
  const Model<double> model = Model<double>::of(robot::kArm);
  const Vec6<double> q0 = joint_vector<double>(robot::kQStart);
  auto st = std::make_unique<ControllerState<double>>();
  controller_init(model, *st, q0);
  for (int k = 0; k < 600; ++k) {
    const int j = momentum_turn(st->adapt);
    const MomentumSample<double> in{j, sample_at(k, G, j), true, 0.01, 3.0};
    adaptation_identify(G, st->adapt, in);
  }
  adaptation_record(G, st->adapt, Vec18<double>(st->adapt.theta_hat), q0, Vec6<double>(Vec6<double>::Constant(0.1)));
  const auto learnt = std::make_unique<AdaptationState<double>>(st->adapt);
  ASSERT_GT(learnt->identifier.updates[0], 0u);
  ASSERT_NE(learnt->theta_hat, Vec18<double>::Zero());
  const Vec6<double> q = q0 + Vec6<double>::Constant(0.01);
  controller_restart(model, *st, q);
  EXPECT_EQ(st->adapt.theta_hat, learnt->theta_hat);
  for (int j = 0; j < kDof; ++j) {
    EXPECT_EQ(st->adapt.identifier.z[j], learnt->identifier.z[j]);
    EXPECT_EQ(st->adapt.identifier.P[j], learnt->identifier.P[j]);
    EXPECT_EQ(st->adapt.identifier.updates[j], learnt->identifier.updates[j]);
  }
  EXPECT_EQ(st->adapt.identifier.turn, learnt->identifier.turn);
  EXPECT_EQ(st->adapt.samples, 0);
  EXPECT_EQ(st->adapt.q_prev, q);
  EXPECT_EQ(st->adapt.qd_hat_prev, Vec6<double>::Zero());
  controller_init(model, *st, q);
  EXPECT_EQ(st->adapt.theta_hat, Vec18<double>::Zero());
  auto prior = std::make_unique<FrictionIdentifier<double>>();
  prior->reset();
  for (int j = 0; j < kDof; ++j) {
    EXPECT_EQ(st->adapt.identifier.updates[j], 0u);
    EXPECT_EQ(st->adapt.identifier.P[j], prior->P[j]);
    EXPECT_EQ(st->adapt.identifier.z[j], prior->z[j]);
  }
}
