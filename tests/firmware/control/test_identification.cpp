// The friction identifier of the `momentum` law (osc/control/identification.hpp), alone: its Kalman
// correction against the batch least-squares solution it must equal, its projection against the
// closed form, its gates, its noise measure and its random walk.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "osc/control/gains.hpp"
#include "osc/control/identification.hpp"
#include "osc/math/fixed.hpp"
#include "test_util.hpp"

using namespace osc;

namespace {

using Vec4 = FrictionIdentifier<double>::Vec4;
using Mat4 = FrictionIdentifier<double>::Mat4;

struct Regression {
  std::vector<Vec4> phi;  // vis, cou, sti, the model's gravity torque
  std::vector<double> y;
};

/// A joint's samples: the regressor columns of a sinusoidal velocity (amplitude `speed` rad/s, and a
/// small faster one) through a first-order filter
/// (as the residual monitor's), a gravity torque that changes with the pose, y = phi^T theta + noise
/// (theta's fourth coefficient: the model's relative gravity error).
Regression samples(const Vec4& theta, double noise, int n, unsigned seed, double speed = 0.4) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise);
  Regression r;
  Vec4 f = Vec4::Zero();
  for (int k = 0; k < n; ++k) {
    const double t = 0.006 * k, v = speed * std::sin(1.3 * t) + 0.05 * std::sin(5.1 * t);
    const double sign = v > 0 ? 1 : -1, q = speed * (1 - std::cos(1.3 * t)) / 1.3;
    const Vec4 w(v, sign, sign * std::exp(-v * v), 40.0 * std::cos(q));
    f += 0.3 * (w - f);  // 50 /s over 6 ms
    r.phi.push_back(f);
    r.y.push_back(f.dot(theta) + gauss(rng));
  }
  return r;
}
FrictionSample<double> sample_of(const Regression& d, std::size_t k) {
  return {d.y[k], d.phi[k].head<3>(), d.phi[k](3), true};
}

}  // namespace

// The sequential correction from the prior (theta^ = 0, covariance P0) equals the batch solution of
// the regularised least squares (P0^-1 + Phi^T Phi / R) theta = Phi^T y / R, and its covariance the
// inverse of that information matrix: solved here with Eigen's LDLT, independently.
TEST(FrictionIdentifier, CorrectionEqualsBatchLeastSquares) {
  const Vec4 truth(5.8, 4.9, 4.1, 0.05);
  const double R = 0.04;
  const Regression d = samples(truth, std::sqrt(R), 3000, 1);
  FrictionIdentifier<double> id;
  id.reset();
  const int joint = 0;
  const Mat4 P0 = id.P[joint];
  Vec4 th = Vec4::Zero();
  Mat4 info = P0.inverse();  // the prior information (a test may invert a 4x4)
  Vec4 rhs = Vec4::Zero();
  for (std::size_t k = 0; k < d.y.size(); ++k) {
    const Vec4 Pphi = id.P[joint] * d.phi[k];
    const double var = d.phi[k].dot(Pphi) + R;
    const double innovation = d.y[k] - d.phi[k].dot(th);
    th += id.correct(joint, Pphi, var) * innovation;
    info += d.phi[k] * d.phi[k].transpose() / R;
    rhs += d.phi[k] * d.y[k] / R;
  }
  const Vec4 batch = info.ldlt().solve(rhs);
  const Mat4 cov = info.ldlt().solve(Mat4::Identity());
  for (int c = 0; c < 4; ++c) {
    EXPECT_NEAR(th(c), batch(c), 1e-9 * (1 + std::abs(batch(c)))) << c;
    for (int e = 0; e < 4; ++e)
      EXPECT_NEAR(id.P[joint](c, e), cov(c, e), 1e-8 * std::sqrt(cov(c, c) * cov(e, e))) << c << e;
  }
  // And the regression is unbiased: within four of its standard deviations of the truth.
  for (int c = 0; c < 4; ++c) EXPECT_LT(std::abs(th(c) - truth(c)), 4 * std::sqrt(cov(c, c))) << c;
}

// The projection in the metric of P^-1, in the filter's coordinates (vis, cou + sti, sti, delta):
// coefficient c = a^T x beyond a bound moves x by P a excess / a^T P a. With the sum well known and
// the Stribeck level not, a Coulomb level of -1 becomes 0 and the Stribeck level gives up what keeps
// the sum: the closed form, and the sum kept to within 1 %.
TEST(FrictionIdentifier, ProjectionKeepsTheWellKnownSum) {
  FrictionIdentifier<double> id;
  id.reset();
  Mat4& P = id.P[2];
  P << 0.5, 0.0, 0.0, 0.0,  //
      0.0, 0.04, 0.0, 0.0,  //
      0.0, 0.0, 4.0, 0.0,   //
      0.0, 0.0, 0.0, 0.01;
  const Vec18<double> theta_max = Gains<double>::paper().theta_max;
  const Vec4 x(2.0, 3.0, 4.0, -0.3);  // vis 2, cou -1, sti 4
  const Vec4 p = id.project(2, x, theta_max);
  EXPECT_DOUBLE_EQ(p(3), -0.3);  // the gravity error is not bounded
  EXPECT_DOUBLE_EQ(p(0), 2.0);
  EXPECT_NEAR(p(1), 0.0, 1e-12);
  // a = (0, 1, -1, 0): P a = (0, 0.04, -4, 0), a^T P a = 4.04, excess -1.
  EXPECT_NEAR(p(2), 4.0 - 4.0 / 4.04, 1e-12);
  EXPECT_NEAR(p(1) + p(2), 3.0 + 0.04 / 4.04, 1e-12);
  EXPECT_NEAR(p(1) + p(2), 3.0, 0.03);  // the sum kept within 1 %
  // A per-coefficient clip would have raised the sum by the whole excess.
  EXPECT_GT(std::abs((0.0 + 4.0) - 3.0), 0.9);
  // Above a bound (in the joint's units, FrictionIdentifier::scale_of): the same rule, from the
  // other side.
  const double sc = FrictionIdentifier<double>::scale_of(2);
  const double hi = theta_max(kDof + 2) * sc;
  const Vec4 high(2.0, hi + 1.5, 0.5, 0.0);  // cou hi + 1
  const Vec4 q = id.project(2, high, theta_max);
  EXPECT_NEAR(q(1), hi, 1e-12);
  EXPECT_NEAR(q(2), 0.5 + 4.0 / 4.04, 1e-12);
}

// Gates: a sample that has not settled, or whose residual is high, changes nothing but P's random
// walk; an innovation beyond kIdentifyGate standard deviations is counted and refused.
TEST(FrictionIdentifier, GatesLeaveTheEstimateAlone) {
  FrictionIdentifier<double> id;
  id.reset();
  const Vec18<double> theta_max = Gains<double>::paper().theta_max;
  Vec18<double> theta = Vec18<double>::Constant(1.0);
  const Vec18<double> before = theta;
  FrictionSample<double> s{10.0, Vec3<double>(0.2, 1.0, 0.98), 0.0, false};
  EXPECT_EQ(id.update(1, s, true, 0.01, 1.0, theta, theta_max), IdentifyOutcome::kNotSettled);
  s.settled = true;
  EXPECT_EQ(id.update(1, s, false, 0.01, 1.0, theta, theta_max), IdentifyOutcome::kResidualHigh);
  EXPECT_EQ(theta, before);
  EXPECT_EQ(id.updates[1], 0u);
  // Shrink joint 1's covariance to a known, small one: an innovation of 10 N m is then an outlier.
  id.P[1] = Mat4::Identity() * 1e-4;
  EXPECT_EQ(id.update(1, s, true, 0.01, 1.0, theta, theta_max), IdentifyOutcome::kOutlier);
  EXPECT_EQ(id.outliers[1], 1u);
  EXPECT_EQ(theta, before);
  // Within the gate it learns (its estimate z in the joint's units: theta^ = 1 N m s/rad, 1 N m, 1 N m).
  const double sc = FrictionIdentifier<double>::scale_of(1);
  id.z[1] << sc, 2 * sc, sc, 0;  // the filter's coordinates: (vis, cou + sti, sti, delta)
  s.y = theta(1) * 0.2 + theta(kDof + 1) * 1.0 + theta(2 * kDof + 1) * 0.98 + 0.05;
  EXPECT_EQ(id.update(1, s, true, 0.01, 1.0, theta, theta_max), IdentifyOutcome::kUpdated);
  EXPECT_NE(theta, before);
  for (int i = 0; i < 18; ++i) {
    if (i % kDof != 1) {
      EXPECT_EQ(theta(i), before(i)) << "only joint 1's coefficients move";
    }
  }
}

// The random walk: P's diagonal grows by kIdentifyDrift^2 times the prior's diagonal per hour of
// updates, and never beyond the prior.
TEST(FrictionIdentifier, RandomWalkGrowsToThePriorAndNoFurther) {
  FrictionIdentifier<double> id;
  id.reset();
  const Mat4 prior = FrictionIdentifier<double>::prior(0);
  id.P[0] = Mat4::Zero();
  const Vec18<double> theta_max = Gains<double>::paper().theta_max;
  Vec18<double> theta = Vec18<double>::Zero();
  const FrictionSample<double> still{0, Vec3<double>::Zero(), 0, false};
  const int per_hour = static_cast<int>(FrictionIdentifier<double>::kPerHour);
  for (int k = 0; k < per_hour; ++k) id.update(0, still, true, 0.01, 1.0, theta, theta_max);
  const double drift = params::kIdentifyDrift * params::kIdentifyDrift;
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(id.P[0](c, c), drift * prior(c, c), 1e-6 * prior(c, c)) << c;
  for (int k = 0; k < 20 * per_hour; ++k) id.update(0, still, true, 0.01, 1.0, theta, theta_max);
  for (int c = 0; c < 4; ++c) EXPECT_DOUBLE_EQ(id.P[0](c, c), prior(c, c)) << c;
  EXPECT_EQ(theta, Vec18<double>::Zero());
}

// The noise measure: from samples of known noise, the identifier's variance settles near it (the
// mean squared innovation less what P explains), and the estimate converges within its own
// standard deviations; in float too. The motion reaches 1.5 rad/s, where the Stribeck decay shows:
// the excitation monitor opens the split, and the Coulomb and Stribeck levels are learned apart.
template <class S>
void converges_on_noisy_samples() {
  OSC_PUMA_ONLY();  // the PUMA's J2 friction (paper preset) as the truth, within its band
  const Vec4 truth(3.7, 4.8, 4.3, -0.08);
  const double sd = 0.3;
  const Regression d = samples(truth, sd, 20000, 7, 1.5);
  FrictionIdentifier<S> id;
  id.reset();
  const Vec18<S> theta_max = Gains<double>::paper().theta_max.template cast<S>();
  Vec18<S> theta = Vec18<S>::Zero();
  int updated = 0, folded = 0;
  for (std::size_t k = 0; k < d.y.size(); ++k) {
    const FrictionSample<double> e = sample_of(d, k);
    const FrictionSample<S> s{S(e.y), e.phi.template cast<S>(), S(e.gravity), true};
    const IdentifyOutcome o = id.update(1, s, true, S(1.0), S(1.0), theta, theta_max);
    updated += o == IdentifyOutcome::kUpdated;
    folded += o == IdentifyOutcome::kFolded;
  }
  // One turn in 65 folds the excitation monitor's block; a 4-sigma gate refuses almost none of
  // gaussian noise.
  EXPECT_NEAR(folded, 20000 / (params::kIdentifyExciteBlock + 1), 3);
  EXPECT_GT(updated + folded, 19900);                    // a 4-sigma gate refuses almost none of gaussian noise
  const double sc = FrictionIdentifier<S>::scale_of(1);  // the joint's unit: 1 / sc N m
  EXPECT_NEAR(static_cast<double>(id.innovation2(1)) / (sc * sc), sd * sd, 0.3 * sd * sd);
  const double sum = static_cast<double>(theta(kDof + 1) + theta(2 * kDof + 1));
  const double sum_sd = std::sqrt(id.breakaway_variance(1));
  EXPECT_LT(std::abs(sum - (truth(1) + truth(2))), 4 * sum_sd);
  EXPECT_LT(std::abs(static_cast<double>(theta(1)) - truth(0)), 4 * std::sqrt(id.variance(1, 0)));
  EXPECT_TRUE(friction_identified(sum, sum_sd)) << sum_sd;
  const double g_sd = std::sqrt(static_cast<double>(id.P[1](3, 3))) /
                      (FrictionIdentifier<S>::scale_of(1) * robot::kDrives.torque_limit[1]);
  EXPECT_NEAR(id.gravity_error(1), truth(3), 4 * g_sd);
  // The split was excited, and learned: each level within four of its standard deviations.
  EXPECT_GE(id.decay_excitation(1), params::kIdentifySplitExcitation);
  EXPECT_LT(std::abs(static_cast<double>(theta(kDof + 1)) - truth(1)), 4 * std::sqrt(id.variance(1, 1)));
  EXPECT_LT(std::abs(static_cast<double>(theta(2 * kDof + 1)) - truth(2)), 4 * std::sqrt(id.variance(1, 2)));
  EXPECT_LT(std::sqrt(id.variance(1, 2)),
            0.5 * std::sqrt(FrictionIdentifier<double>::prior(1)(2, 2)) / FrictionIdentifier<double>::scale_of(1));
  // The travel check's proven friction: the truth within it, and at most 1.1 times the estimate
  // (identified within 2.5 %); the joints that had no sample keep the band's tops.
  const ModelErrorBounds& band = robot::kModelErrorBounds;
  const double proven = static_cast<double>(id.proven.breakaway(1)), vis = static_cast<double>(id.proven.vis(1));
  EXPECT_GE(proven, truth(1) + truth(2));
  EXPECT_LE(proven, 1.1 * sum * (1 + 1e-5));
  EXPECT_GE(vis, truth(0));
  EXPECT_LT(vis, 1.4 * static_cast<double>(theta(1)));
  for (int i : {0, 2, 3, 4, 5}) {
    EXPECT_NEAR(static_cast<double>(id.proven.breakaway(i)), band.friction_hi.cou[i] + band.friction_hi.sti[i], 1e-4)
        << i;
    EXPECT_NEAR(static_cast<double>(id.proven.vis(i)), band.friction_hi.vis[i], 1e-4) << i;
  }
}
TEST(FrictionIdentifier, ConvergesOnNoisySamplesDouble) { converges_on_noisy_samples<double>(); }
TEST(FrictionIdentifier, ConvergesOnNoisySamplesFloat) { converges_on_noisy_samples<float>(); }

// In fixed point the update's variance is floored (FrictionIdentifier::kFixedVarFloor): a joint whose
// quantisation noise squared is below Q12.19's resolution (the UR5e's wrist: 0.5 mN m, its square
// 2e-7 N^2 m^2, 0 in Q12.19) and a sample that explains nothing (phi = 0, as the worst-case timing image
// counts at rest) divided 0 by 0 and latched `overflow`; with the floor the update is a gain of 0.
TEST(FrictionIdentifier, FixedPointNoiseBelowItsResolutionDividesNothingByZero) {
  FrictionIdentifier<Fixed> id;
  id.reset();
  const Vec18<Fixed> theta_max = Gains<Fixed>::paper().theta_max;
  Vec18<Fixed> theta = Vec18<Fixed>::Zero();
  const FrictionSample<Fixed> nothing{Fixed(0), Vec3<Fixed>::Zero(), Fixed(0), true};
  (void)math::take_arithmetic_fault<Fixed>();
  for (int k = 0; k < 8; ++k) {
    const IdentifyOutcome o = id.update(4, nothing, true, Fixed(0), Fixed(1), theta, theta_max);
    EXPECT_EQ(o, IdentifyOutcome::kUpdated) << k;
  }
  EXPECT_FALSE(math::take_arithmetic_fault<Fixed>());
  EXPECT_EQ(theta, Vec18<Fixed>::Zero());
}

// The proven breakaway while the joint stands (no samples, P drifting back toward the prior): it
// steps up through its tiers, 1.1, 1.2, 1.4 and 1.8 times the estimate, each as the standard
// deviation passes 2.5, 5, 10 and 20 % of it, and then is the band's top. Checked against the
// standard deviation itself (sqrt of P, which prove() does not take) at every turn, for 20 minutes.
TEST(FrictionIdentifier, ProvenBreakawayFollowsItsStandardDeviation) {
  OSC_PUMA_ONLY();  // the PUMA's J2 friction as the truth, its band's top
  const Vec4 truth(3.7, 4.8, 4.3, -0.08);
  const Regression d = samples(truth, 0.3, 20000, 7, 1.5);
  FrictionIdentifier<double> id;
  id.reset();
  const Vec18<double> theta_max = Gains<double>::paper().theta_max;
  Vec18<double> theta = Vec18<double>::Zero();
  for (std::size_t k = 0; k < d.y.size(); ++k) id.update(1, sample_of(d, k), true, 1.0, 1.0, theta, theta_max);
  const double z = id.z[1](1) / FrictionIdentifier<double>::scale_of(1);
  const double top = robot::kModelErrorBounds.friction_hi.cou[1] + robot::kModelErrorBounds.friction_hi.sti[1];
  const FrictionSample<double> still{0, Vec3<double>::Zero(), 0, false};
  double last = 0;
  int steps = 0;
  const int turns = static_cast<int>(FrictionIdentifier<double>::kPerHour / 3);
  for (int k = 0; k < turns; ++k) {
    id.update(1, still, true, 1.0, 1.0, theta, theta_max);
    const double proven = id.proven.breakaway(1), sd = std::sqrt(id.breakaway_variance(1));
    double expected = top;
    for (double f : {0.025, 0.05, 0.1, 0.2})
      if (sd <= f * z) {
        expected = std::min(top, (1 + params::kTravelIdentifiedSd * f) * z);
        break;
      }
    ASSERT_NEAR(proven, expected, 1e-9) << k;
    ASSERT_GE(proven, z + params::kTravelIdentifiedSd * std::min(sd, 0.2 * z) - 1e-9) << k;
    steps += proven != last;
    last = proven;
  }
  EXPECT_EQ(last, top);
  EXPECT_EQ(steps, 5);  // 1.1, 1.2, 1.4, 1.8 z and the top
}

// The excitation monitor's gate: at the speeds of the paper's motion (0.15 rad/s) the Stribeck
// decay hardly shows and the Coulomb and Stribeck columns are collinear. The split is held: the
// Stribeck estimate and its variance do not move at all, while the sum is learned to its truth.
TEST(FrictionIdentifier, CollinearMotionLearnsTheSumAndHoldsTheSplit) {
  const Vec4 truth(3.7, 4.8, 4.3, -0.08);
  const Regression d = samples(truth, 0.3, 20000, 11, 0.15);
  FrictionIdentifier<double> id;
  id.reset();
  const double sc = FrictionIdentifier<double>::scale_of(1);
  id.z[1](2) = 1.5 * sc;  // a split learned before (1.5 N m of Stribeck level)
  const double sti_var = id.P[1](2, 2);
  const Vec18<double> theta_max = Gains<double>::paper().theta_max;
  Vec18<double> theta = Vec18<double>::Zero();
  for (std::size_t k = 0; k < d.y.size(); ++k) id.update(1, sample_of(d, k), true, 1.0, 1.0, theta, theta_max);
  EXPECT_GT(id.updates[1], 19900u * params::kIdentifyExciteBlock / (params::kIdentifyExciteBlock + 1));
  EXPECT_LT(id.decay_excitation(1), 0.2 * params::kIdentifySplitExcitation);
  EXPECT_EQ(id.z[1](2), 1.5 * sc);    // held, bit for bit
  EXPECT_EQ(id.P[1](2, 2), sti_var);  // and its variance with it (the prior: the random walk's cap)
  const double sum = theta(kDof + 1) + theta(2 * kDof + 1);
  EXPECT_NEAR(sum, truth(1) + truth(2), 4 * std::sqrt(id.breakaway_variance(1)));
  EXPECT_TRUE(friction_identified(sum, std::sqrt(id.breakaway_variance(1))));
}

// The consider (Schmidt) update against its definition: in the filter's coordinates (vis,
// cou + sti, sti, delta) the Stribeck level's gain is 0, the others' the Kalman gain, and the
// covariance is Joseph's form for that gain, (I - K h^T) P (I - K h^T)^T + K R K^T, computed here
// independently; the sum is learned as a Kalman filter would, the Stribeck level not at all.
TEST(FrictionIdentifier, ConsiderUpdateIsSchmidtsFilter) {
  FrictionIdentifier<double> id;
  id.reset();
  Mat4 P;
  P << 2.0, 0.3, -0.2, 0.05,  //
      0.3, 0.9, 0.5, 0.1,     //
      -0.2, 0.5, 4.6, -0.05,  //
      0.05, 0.1, -0.05, 0.8;
  id.P[0] = P;
  const Vec4 h(0.12, 0.97, -0.02, 0.4);
  const double R = 0.07;
  const Vec4 Ph = P * h;
  const double var = h.dot(Ph) + R;
  const Vec4 gain = id.correct(0, Ph, var, false);
  Vec4 K = Ph / var;
  K(2) = 0.0;
  const Mat4 A = Mat4::Identity() - K * h.transpose();
  const Mat4 P_next = A * P * A.transpose() + K * R * K.transpose();
  for (int a = 0; a < 4; ++a) {
    EXPECT_NEAR(gain(a), K(a), 1e-12) << a;
    for (int b = 0; b < 4; ++b) EXPECT_NEAR(id.P[0](a, b), P_next(a, b), 1e-12) << a << b;
  }
  EXPECT_EQ(id.P[0](2, 2), 4.6);
  // The sum's variance falls as the Kalman filter's own would.
  EXPECT_NEAR(id.P[0](1, 1), P(1, 1) - Ph(1) * Ph(1) / var, 1e-12);
}

// Issue 57's stale saved friction (FrictionIdentifier::seed, FrictionFit::judge). A friction set (a saved record at
// power-on, an identify run's applied) is where the estimate goes on from: a sample that tells nothing leaves theta^ as
// set (before the seed, the law's first update wrote its prior's 0 over it). The set friction is judged once per
// coefficient, when the law first identifies it params::kIdentifyNoiseSamples updates or more after the set: the
// truth's and 10 % below it fit; 40 % above is stale, and stays stale as the estimate moves on to the truth; a fit
// one stays fit when the friction later drifts by 30 % (temperature: the law's to follow); a new set starts the check
// again; joints with nothing set (0) are never checked. In double, float and Q12.19.
template <class S>
void judges_a_set_friction() {
  OSC_PUMA_ONLY();  // the PUMA's J2 friction (paper preset) as the truth, within its band
  const Vec4 truth(3.7, 4.8, 4.3, -0.08);
  const Regression d = samples(truth, 0.3, 6000, 7, 1.5);
  const Vec4 warm(3.7 * 1.3, 4.8 * 1.3, 4.3 * 1.3, -0.08);  // the same joint 30 % warmer
  const Regression later = samples(warm, 0.3, 6000, 8, 1.5);
  const Vec18<S> theta_max = Gains<double>::paper().theta_max.template cast<S>();
  const auto feed = [&](FrictionIdentifier<S>& id, Vec18<S>& theta, const Regression& r) {
    for (std::size_t k = 0; k < r.y.size(); ++k) {
      const FrictionSample<double> e = sample_of(r, k);
      const FrictionSample<S> s{S(e.y), e.phi.template cast<S>(), S(e.gravity), true};
      id.update(1, s, true, S(1.0), S(1.0), theta, theta_max);
    }
  };
  const auto sum_of = [](const Vec18<S>& th) { return static_cast<double>(th(kDof + 1) + th(2 * kDof + 1)); };
  const double breakaway = truth(1) + truth(2);
  const FrictionSample<S> nothing{S(0), Vec3<S>::Zero(), S(0), true};
  for (const double factor : {0.0, 1.0, 0.9, 1.4}) {
    SCOPED_TRACE(factor);
    FrictionIdentifier<S> id;
    id.reset();
    Vec18<S> theta = Vec18<S>::Zero();
    theta(1) = S(truth(0) * factor), theta(kDof + 1) = S(truth(1) * factor), theta(2 * kDof + 1) = S(truth(2) * factor);
    const Vec18<S> set = theta;
    for (int i = 0; i < kDof; ++i) id.seed(i, theta);
    EXPECT_EQ(id.update(1, nothing, true, S(1.0), S(1.0), theta, theta_max), IdentifyOutcome::kUpdated);
    for (int k : {1, kDof + 1, 2 * kDof + 1})
      EXPECT_NEAR(static_cast<double>(theta(k)), static_cast<double>(set(k)), 1e-5) << k;
    feed(id, theta, d);
    EXPECT_EQ(id.fit.checked(), factor > 0 ? 1u << 1 : 0u);  // J2 only: the others have no samples
    EXPECT_EQ(id.fit.stale, factor > 1.2 ? 1u << 1 : 0u);
    EXPECT_EQ(id.fit.judged[1], factor > 0 ? 1u << 1 : 0u);  // the breakaway's verdict is among them
    EXPECT_NEAR(sum_of(theta), breakaway, 0.05 * breakaway);
    // The verdict is made once: the friction drifting 30 % up later changes none.
    const std::uint8_t stale = id.fit.stale;
    feed(id, theta, later);
    EXPECT_NEAR(sum_of(theta), 1.3 * breakaway, 0.05 * breakaway);
    EXPECT_EQ(id.fit.stale, stale);
    // A new set, the truth's again, is judged anew against the warmer data: more than 20 % off, stale.
    if (factor != 1.0) continue;
    theta(kDof + 1) = S(truth(1)), theta(2 * kDof + 1) = S(truth(2));
    id.seed(1, theta);
    EXPECT_EQ(id.fit.checked(), 0u);
    feed(id, theta, later);
    EXPECT_EQ(id.fit.stale, 1u << 1);
  }
}
TEST(FrictionIdentifier, ASetFrictionIsWhereItGoesOnFromAndIsJudgedOnceDouble) { judges_a_set_friction<double>(); }
TEST(FrictionIdentifier, ASetFrictionIsWhereItGoesOnFromAndIsJudgedOnceFloat) { judges_a_set_friction<float>(); }
TEST(FrictionIdentifier, ASetFrictionIsWhereItGoesOnFromAndIsJudgedOnceFixed) { judges_a_set_friction<Fixed>(); }
