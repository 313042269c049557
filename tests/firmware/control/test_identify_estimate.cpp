// The identification run's estimate (osc/control/identify_estimate.hpp) on data whose truth is known: the excitation
// motion (osc/control/excitation.hpp) prepared at the build's start pose, its friction columns and payload regressor
// every 5 ms over a period, the torques those of the arm's first friction preset and a known payload. Exact recovery
// without noise; the solution, its standard deviations and its condition against an independent solver (the stacked
// weighted regression by Householder QR, the eigenvalues by Eigen's symmetric solver); the coverage of the reported
// sigma over 200 seeds of Gaussian noise; unequal noise and the weighting; every status reached; the payload
// subsets; noise filtered by F and the correlation factor; and the run end to end with KDL's torques, through the
// exact states (parts 1 and 3) and through the run's filter at 1 kHz (parts 1, 2 and 3).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "kdl_puma.hpp"
#include "osc/control/excitation.hpp"
#include "osc/control/identify_estimate.hpp"
#include "osc/control/identify_filter.hpp"
#include "test_util.hpp"

using namespace osc;
using test::from_kdl;
using test::to_kdl;

namespace {

constexpr int kEvery = 5;  // ticks between samples: 200 Hz
constexpr std::uint32_t kPeriod = excitation::kPeriodTicks;
constexpr int kSeeds = 200;

const Model<double>& model() {
  static const Model<double> m = Model<double>::of(robot::kArm);
  return m;
}

/// The truth: the arm's first friction preset, and a payload of 1.5 kg, 87 mm from the flange, a box of
/// 0.12 x 0.08 x 0.05 m.
const FrictionParams<double> kFriction = FrictionParams<double>::from(*robot::kFrictionPresets[0], params::kTauDec);
constexpr double kBoxI[3] = {1.5 / 12 * (0.08 * 0.08 + 0.05 * 0.05), 1.5 / 12 * (0.12 * 0.12 + 0.05 * 0.05),
                             1.5 / 12 * (0.12 * 0.12 + 0.08 * 0.08)};
const Payload kPayload = {1.5, {0.03, -0.02, 0.08}, {kBoxI[0], kBoxI[1], kBoxI[2], 0, 0, 0}};
const PayloadVector<double> kTruePi = PayloadParams<double>::from(kPayload).vector();

/// pi with only the entries of `mask` (what data whose payload has only those make of it).
PayloadVector<double> masked(const PayloadVector<double>& pi, std::uint16_t mask) {
  PayloadVector<double> p = PayloadVector<double>::Zero();
  for (int k = 0; k < 10; ++k)
    if (mask >> k & 1u) p(k) = pi(k);
  return p;
}

/// The excitation motion, prepared (planned and checked) at the build's start pose.
const ExcitationMotion<double>& motion() {
  static const std::unique_ptr<ExcitationMotion<double>> m = [] {
    auto p = std::make_unique<ExcitationMotion<double>>();
    auto data = std::make_unique<Data<double>>();
    const Vec6<double> q0 = test::from_array(robot::kQStart);
    forward_kinematics(model(), *data, q0);
    const Mat3<double> R_ref = data->R[kDof];
    const ExcitationCheck<double> c =
        prepare_excitation(model(), *data, q0, R_ref, ExcitationLimits<double>::defaults(), *p);
    EXPECT_EQ(c.status, ExcitationStatus::kOk);
    return p;
  }();
  return *m;
}

/// A sample of the design: the state, the friction columns and the payload regressor there.
struct Sample {
  Vec6<double> q, qd, qdd;
  RegressorDiagonals<double> w;
  PayloadRegressor<double> Y;
  /// The torque of the truth, friction and the entries of pi that `mask` selects.
  Vec6<double> y(std::uint16_t mask) const { return w.times(kFriction.theta()) + Y * masked(kTruePi, mask); }
};

/// The excitation's samples every kEvery ticks over a period, at `scale` of the prepared motion's gains.
std::vector<Sample> samples_of(double scale) {
  ExcitationMotion<double> m = motion();
  m.set_scale(m.scale() * scale);
  std::vector<Sample> v;
  Data<double> data;
  for (std::uint32_t n = kEvery; n < kPeriod; n += kEvery) {
    const JointSample<double> d = m.at_tick(n);
    Sample s{d.q, d.qd, d.qdd, friction_regressor_diagonals(d.qd, kFriction.dec), {}};
    forward_kinematics(model(), data, d.q);
    geometric_jacobian(data);
    s.Y = payload_regressor(model(), data, d.qd, d.qdd);
    v.push_back(s);
  }
  return v;
}
const std::vector<Sample>& design() {
  static const std::vector<Sample> samples = samples_of(1.0);
  return samples;
}

/// Per-joint noise standard deviations [N m] (unequal: the arm's big joints noisier).
const Vec6<double> kNoise(0.3, 0.5, 0.2, 0.02, 0.01, 0.02);

/// The design's torques with Gaussian noise of sd `noise` per joint, seed `seed`.
std::vector<Vec6<double>> noisy(std::uint16_t mask, std::uint64_t seed, const Vec6<double>& noise) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::vector<Vec6<double>> y;
  for (const Sample& s : design()) {
    Vec6<double> v = s.y(mask);
    for (int i = 0; i < kDof; ++i) v(i) += noise(i) * g(rng);
    y.push_back(v);
  }
  return y;
}

/// The estimator (26 kB: static, as on the board, not on the stack) fed the design with torques y.
IdentifyReport estimate(std::uint16_t mask, const std::vector<Vec6<double>>& y, double kappa = 1) {
  static_assert(sizeof(IdentifyEstimate) < 26 * 1024, "identify_estimate.hpp's stated size: 11.6 + 13.8 kB");
  static IdentifyEstimate e;
  const std::vector<Sample>& d = design();
  test::NoMalloc guard;  // the sums and the solve: no heap
  e.reset(mask);
  for (std::size_t k = 0; k < y.size(); ++k) e.add(y[k], d[k].w, d[k].Y);
  return e.solve(kappa);
}

/// (estimate - truth) / sd of every estimated coefficient.
std::vector<double> z_scores(const IdentifyReport& r, std::uint16_t mask) {
  std::vector<double> z;
  const Vec18<double> theta = kFriction.theta();
  for (int k = 0; k < 3 * kDof; ++k) z.push_back((r.friction(k) - theta(k)) / r.friction_sd(k));
  for (int k = 0; k < 10; ++k)
    if (mask >> k & 1u) z.push_back((r.payload(k) - kTruePi(k)) / r.payload_sd(k));
  return z;
}

/// The fraction of |z| within 2 and 3, and the largest |z|.
struct Coverage {
  std::size_t n = 0, within2 = 0, within3 = 0;
  double largest = 0;
  void add(const std::vector<double>& z) {
    for (const double v : z) {
      ++n;
      within2 += std::abs(v) <= 2;
      within3 += std::abs(v) <= 3;
      largest = std::max(largest, std::abs(v));
    }
  }
  double two() const { return static_cast<double>(within2) / n; }
  double three() const { return static_cast<double>(within3) / n; }
};

/// The stacked regression of the design (rows: sample, joint; columns: the estimated unknowns in the estimator's
/// order), each row divided by its joint's sd: an independent weighted least squares.
struct Stacked {
  Eigen::MatrixXd X;
  Eigen::VectorXd y;
};
Stacked stacked(std::uint16_t mask, const std::vector<Vec6<double>>& y, const Vec6<double>& sd) {
  std::vector<int> payload;
  for (int k = 0; k < 10; ++k)
    if (mask >> k & 1u) payload.push_back(k);
  const int rows = static_cast<int>(design().size()) * kDof, cols = 3 * kDof + static_cast<int>(payload.size());
  Stacked s{Eigen::MatrixXd::Zero(rows, cols), Eigen::VectorXd(rows)};
  for (std::size_t k = 0; k < design().size(); ++k)
    for (int i = 0; i < kDof; ++i) {
      const int row = static_cast<int>(k) * kDof + i;
      const Sample& d = design()[k];
      s.X(row, i) = d.w.vis(i), s.X(row, kDof + i) = d.w.cou(i), s.X(row, 2 * kDof + i) = d.w.sti(i);
      for (std::size_t c = 0; c < payload.size(); ++c) s.X(row, 3 * kDof + static_cast<int>(c)) = d.Y(i, payload[c]);
      s.X.row(row) /= sd(i);
      s.y(row) = y[k](i) / sd(i);
    }
  return s;
}

/// The estimated unknowns of a report in the estimator's order.
Eigen::VectorXd unknowns(const IdentifyReport& r, std::uint16_t mask, bool sd) {
  std::vector<double> v;
  for (int k = 0; k < 3 * kDof; ++k) v.push_back(sd ? r.friction_sd(k) : r.friction(k));
  for (int k = 0; k < 10; ++k)
    if (mask >> k & 1u) v.push_back(sd ? r.payload_sd(k) : r.payload(k));
  return Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace

// ---------------------------------------------------------------- exact data and an independent solver

TEST(IdentifyEstimate, RecoversTheTruthWithoutNoise) {
  for (const std::uint16_t mask : {payload_mask::kNone, payload_mask::kMassAndMoment, payload_mask::kAll}) {
    const IdentifyReport r = estimate(mask, noisy(mask, 1, Vec6<double>::Zero()));
    const PayloadVector<double> pi = masked(kTruePi, mask);
    std::printf("mask 0x%03x: %u samples, condition %.4g (bound %.4g), friction error %.1e, payload error %.1e\n", mask,
                r.samples, r.condition, r.condition_bound, (r.friction - kFriction.theta()).cwiseAbs().maxCoeff(),
                (r.payload - pi).cwiseAbs().maxCoeff());
    EXPECT_EQ(r.status, IdentifyStatus::kOk) << mask;
    EXPECT_LT((r.friction - kFriction.theta()).norm(), 1e-9 * kFriction.theta().norm()) << mask;
    EXPECT_LT((r.payload - pi).norm(), 1e-9 * kTruePi.norm()) << mask;
    EXPECT_LT(r.worst_prediction_error, 1e-6) << mask;
    for (int k = 0; k < 10; ++k)
      EXPECT_EQ(r.payload_verdict[k] == CoefficientVerdict::kNotEstimated, !(mask >> k & 1u)) << mask << " " << k;
  }
}

TEST(IdentifyEstimate, AnArmatureTheModelLacksIsEstimatedWithTheFrictionAndThePayload) {
  // The plant's armature larger than the model's by the PUMA's two published sets' difference (G^2 (J_m' - J_m):
  // 0.36, 2.43, 0.29 kg m^2 on J1-J3, about 0.01 on the wrist), on top of the friction and the payload: with the
  // armatures' columns every unknown comes back (noise-free, within 1e-9); without them the friction takes the
  // difference and the prediction fails (measured: J2 28.5 %, a coefficient off by 2.55 times itself).
  const Vec6<double> extra(0.3566, 2.4288, 0.2858, 0.0116, 0.0103, 0.0118);
  const std::uint16_t mask = payload_mask::kAll;
  std::vector<Vec6<double>> y;
  for (const Sample& s : design()) y.push_back(Vec6<double>(s.y(mask) + extra.cwiseProduct(s.qdd)));
  static IdentifyEstimate with, without;
  with.reset(mask, identify::kAllRows), without.reset(mask);
  for (std::size_t k = 0; k < y.size(); ++k) {
    with.add(y[k], design()[k].w, design()[k].Y, identify::kAllRows, design()[k].qdd);
    without.add(y[k], design()[k].w, design()[k].Y);
  }
  const IdentifyReport r = with.solve(), n = without.solve();
  std::printf(
      "with the armatures: condition %.4g, armature error %.1e, friction error %.1e; without: prediction error "
      "%.3f (J%d), friction worst %.2f relative\n",
      r.condition, (r.armature - extra).cwiseAbs().maxCoeff(), (r.friction - kFriction.theta()).cwiseAbs().maxCoeff(),
      n.worst_prediction_error, n.worst_joint + 1,
      (n.friction - kFriction.theta()).cwiseQuotient(kFriction.theta()).cwiseAbs().maxCoeff());
  EXPECT_EQ(r.status, IdentifyStatus::kOk);
  EXPECT_LT((r.armature - extra).norm(), 1e-9 * extra.norm());
  EXPECT_LT((r.friction - kFriction.theta()).norm(), 1e-9 * kFriction.theta().norm());
  EXPECT_LT((r.payload - kTruePi).norm(), 1e-9 * kTruePi.norm());
  EXPECT_GT(n.worst_prediction_error, 0.05);
  EXPECT_GT((n.friction - kFriction.theta()).cwiseQuotient(kFriction.theta()).cwiseAbs().maxCoeff(), 0.1);
  EXPECT_EQ(n.armature, Vec6<double>::Zero());  // not estimated: 0, with no sigma
  EXPECT_EQ(n.armature_sd, Vec6<double>::Zero());
}

TEST(IdentifyEstimate, EachDrivesTorqueOffsetIsEstimatedWithTheArmatureTheFrictionAndThePayload) {
  // Each drive adds a constant b_i to the torque commanded (an amplifier's offset: the realistic plant's, 0.1 % of
  // each channel's range, signs mixed), so y_i is short of it; on top of the armatures, the friction and the payload.
  // With the offsets' columns every unknown comes back (noise-free, within 1e-9); without them the friction and the
  // payload take the offsets (no column of model (2) is a constant).
  const Vec6<double> extra(0.3566, 2.4288, 0.2858, 0.0116, 0.0103, 0.0118),
      b(0.098, -0.186, 0.089, -0.024, 0.020, -0.021);
  const std::uint16_t mask = payload_mask::kAll;
  std::vector<Vec6<double>> y;
  for (const Sample& s : design()) y.push_back(Vec6<double>(s.y(mask) + extra.cwiseProduct(s.qdd) - b));
  static IdentifyEstimate with, without;
  with.reset(mask, identify::kAllRows, identify::kAllRows), without.reset(mask, identify::kAllRows);
  for (std::size_t k = 0; k < y.size(); ++k) {
    with.add(y[k], design()[k].w, design()[k].Y, identify::kAllRows, design()[k].qdd);
    without.add(y[k], design()[k].w, design()[k].Y, identify::kAllRows, design()[k].qdd);
  }
  const IdentifyReport r = with.solve(), n = without.solve();
  std::printf("with the offsets: condition %.4g, offset error %.1e; without: friction worst %.3f relative\n",
              r.condition, (r.offset - b).cwiseAbs().maxCoeff(),
              (n.friction - kFriction.theta()).cwiseQuotient(kFriction.theta()).cwiseAbs().maxCoeff());
  EXPECT_EQ(r.status, IdentifyStatus::kOk);
  EXPECT_LT((r.offset - b).norm(), 1e-9 * b.norm());
  EXPECT_GT(r.offset_sd.minCoeff(), 0.0);
  EXPECT_LT((r.armature - extra).norm(), 1e-9 * extra.norm());
  EXPECT_LT((r.friction - kFriction.theta()).norm(), 1e-9 * kFriction.theta().norm());
  EXPECT_LT((r.payload - kTruePi).norm(), 1e-9 * kTruePi.norm());
  EXPECT_GT((n.friction - kFriction.theta()).cwiseQuotient(kFriction.theta()).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_EQ(n.offset, Vec6<double>::Zero());  // not estimated: 0, with no sigma
  EXPECT_EQ(n.offset_sd, Vec6<double>::Zero());
}

TEST(IdentifyEstimate, IsTheWeightedLeastSquaresOfTheStackedRegressionSolvedByQr) {
  // The report's weights (noise_sd) on the stacked rows, Householder QR: the same solution, the same standard
  // deviations (diag (X^T X)^-1 from R^-1), and the condition of the column-normalised X^T X by Eigen's symmetric
  // eigensolver: the report's estimate from below within 1e-5, its bound above.
  const std::uint16_t mask = payload_mask::kMassAndMoment;
  const std::vector<Vec6<double>> y = noisy(mask, 11, kNoise);
  const IdentifyReport r = estimate(mask, y);
  const Stacked s = stacked(mask, y, r.noise_sd);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(s.X);
  const Eigen::VectorXd x = qr.solve(s.y);
  const Eigen::Index p = s.X.cols();
  const Eigen::MatrixXd R = qr.matrixQR().topRows(p).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd Rinv = R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(p, p));
  const Eigen::VectorXd sd = Rinv.rowwise().norm();  // sqrt of diag(R^-1 R^-T)
  const Eigen::MatrixXd A = s.X.transpose() * s.X;
  const Eigen::VectorXd D = A.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(D.asDiagonal() * A * D.asDiagonal());
  const double condition = eig.eigenvalues().maxCoeff() / eig.eigenvalues().minCoeff();
  const double dx = (unknowns(r, mask, false) - x).cwiseQuotient(sd).cwiseAbs().maxCoeff();
  const double dsd = (unknowns(r, mask, true) - sd).cwiseQuotient(sd).cwiseAbs().maxCoeff();
  std::printf("against QR: solution within %.1e sd, sd within %.1e of itself; condition %.6g (QR's %.6g), bound %.4g\n",
              dx, dsd, r.condition, condition, r.condition_bound);
  EXPECT_LT(dx, 1e-8);
  EXPECT_LT(dsd, 1e-8);
  EXPECT_LE(r.condition, condition * (1 + 1e-9));
  EXPECT_GE(r.condition, condition * (1 - 1e-5));
  EXPECT_GE(r.condition_bound, condition);
  // The weights are the residuals' own: each noise_sd within 10 % of the noise that was added (2000 samples: the
  // sample sd's own spread is 1.6 %).
  for (int i = 0; i < kDof; ++i) EXPECT_NEAR(r.noise_sd(i) / kNoise(i), 1, 0.1) << i;
}

// ---------------------------------------------------------------- honest sigma

TEST(IdentifyEstimate, TheReportedSigmaCoversTheTruthAtTheNormalRatesOver200Seeds) {
  // 200 seeds x 22 coefficients (friction and the payload's mass and first moments, coupled through it) = 4400.
  // Gaussian rates: 95.45 % within 2 sigma, 99.73 % within 3, and P(|z| > 4.5) = 7e-6 (0.03 expected beyond). The
  // binomial sd of the 2 sigma rate is 0.31 %. Bars: 2 sigma in [93.5, 97.5] %, 3 sigma at least 99.3 %, none
  // beyond 4.5. A sigma reported 15 % small covers 91.1 % at 2 sigma and fails; 15 % large covers 97.9 % and fails.
  const std::uint16_t mask = payload_mask::kMassAndMoment;
  Coverage c;
  for (int seed = 1; seed <= kSeeds; ++seed) c.add(z_scores(estimate(mask, noisy(mask, seed, kNoise)), mask));
  std::printf("coverage over %d seeds, %zu coefficients: %.2f %% within 2 sigma, %.2f %% within 3, largest |z| %.2f\n",
              kSeeds, c.n, 100 * c.two(), 100 * c.three(), c.largest);
  EXPECT_GE(c.two(), 0.935);
  EXPECT_LE(c.two(), 0.975);
  EXPECT_GE(c.three(), 0.993);
  EXPECT_LE(c.largest, 4.5);
}

TEST(IdentifyEstimate, UnequalNoiseIsWeightedSoThatQuietJointsTellTheMost) {
  // J2 ten times noisier than the rest (5 N m against 0.01-0.3). Its own coefficients' sd grow with it, the other
  // joints' stay; and the payload, which every joint sees, is estimated from the quiet joints: its sd against the
  // unweighted solution's true sd ((X^T X)^-1 X^T Sigma X (X^T X)^-1 with the noise's Sigma) is smaller.
  const std::uint16_t mask = payload_mask::kMassAndMoment;
  Vec6<double> loud = kNoise;
  loud(1) *= 10;
  const IdentifyReport quiet = estimate(mask, noisy(mask, 3, kNoise)), r = estimate(mask, noisy(mask, 3, loud));
  for (int i = 0; i < kDof; ++i)
    for (int l = 0; l < 3; ++l) {
      const double ratio = r.friction_sd(l * kDof + i) / quiet.friction_sd(l * kDof + i);
      EXPECT_NEAR(ratio, i == 1 ? 10 : 1, i == 1 ? 1.0 : 0.1) << i << " " << l;
    }
  const Stacked s = stacked(mask, noisy(mask, 3, loud), Vec6<double>::Ones());  // unweighted
  const Eigen::MatrixXd Ainv = (s.X.transpose() * s.X).inverse();               // test-side oracle (22 x 22)
  Eigen::VectorXd sigma2(s.X.rows());
  for (Eigen::Index row = 0; row < s.X.rows(); ++row) sigma2(row) = loud(row % kDof) * loud(row % kDof);
  const Eigen::MatrixXd ols = Ainv * s.X.transpose() * sigma2.asDiagonal() * s.X * Ainv;
  for (int k = 0; k < 4; ++k) {
    const double ols_sd = std::sqrt(ols(3 * kDof + k, 3 * kDof + k));
    std::printf("pi(%d): weighted sd %.3e, unweighted %.3e\n", k, r.payload_sd(k), ols_sd);
    EXPECT_LT(r.payload_sd(k), 0.8 * ols_sd) << k;
  }
}

TEST(IdentifyEstimate, NoiseFilteredByFIsCoveredWithTheCorrelationFactor) {
  // Noise white at 1 kHz through the run's filter F (identify_filter.hpp), sampled every 5 ticks: neighbouring
  // samples alike over 4 / w = 64 ms. Without the factor the reported sigma is about sqrt(12.7) = 3.6 times too
  // small; with identify::noise_correlation_factor(5) the coverage is the normal one (bars as above, 100 seeds).
  const std::uint16_t mask = payload_mask::kMassAndMoment;
  const double kappa = identify::noise_correlation_factor(kEvery);
  Coverage with, without;
  for (int seed = 1; seed <= kSeeds / 2; ++seed) {
    std::mt19937_64 rng(1000 + seed);
    std::normal_distribution<double> g;
    identify::StateVariableFilter<double, kDof, identify::kTorqueBits> f;
    f.prime(Vec6<double>::Zero());
    std::vector<Vec6<double>> y;
    for (std::uint32_t n = 1; n < kPeriod; ++n) {
      Vec6<double> e;
      for (int i = 0; i < kDof; ++i) e(i) = 4 * kNoise(i) * g(rng);  // about kNoise after F
      f.step(e);
      if (n % kEvery == 0) y.push_back(design()[y.size()].y(mask) + f.value());
    }
    with.add(z_scores(estimate(mask, y, kappa), mask));
    without.add(z_scores(estimate(mask, y, 1.0), mask));
  }
  std::printf(
      "filtered noise, kappa %.2f: %.2f %% within 2 sigma, %.2f %% within 3, largest %.2f; without it %.2f %%\n", kappa,
      100 * with.two(), 100 * with.three(), with.largest, 100 * without.two());
  EXPECT_GE(with.two(), 0.93);
  EXPECT_LE(with.two(), 0.98);
  EXPECT_GE(with.three(), 0.99);
  EXPECT_LT(without.two(), 0.6);
}

// ---------------------------------------------------------------- the statuses

TEST(IdentifyEstimate, TooFewSamples) {
  // One short of params::kIdentifyMinSamples: no solution, nothing identified, the masked entries not estimated.
  const std::uint16_t mask = payload_mask::kMassAndMoment;
  static IdentifyEstimate e;
  e.reset(mask);
  const std::vector<Vec6<double>> y = noisy(mask, 5, kNoise);
  for (unsigned k = 0; k + 1 < params::kIdentifyMinSamples; ++k) e.add(y[k], design()[k].w, design()[k].Y);
  const IdentifyReport r = e.solve();
  EXPECT_EQ(r.status, IdentifyStatus::kTooFewSamples);
  EXPECT_TRUE(std::isinf(r.friction_sd(0)));
  EXPECT_EQ(r.friction_verdict[0], CoefficientVerdict::kNotExcited);
  EXPECT_EQ(r.payload_verdict[0], CoefficientVerdict::kNotExcited);
  EXPECT_EQ(r.payload_verdict[5], CoefficientVerdict::kNotEstimated);
  const unsigned last = params::kIdentifyMinSamples - 1;
  e.add(y[last], design()[last].w, design()[last].Y);
  EXPECT_NE(e.solve().status, IdentifyStatus::kTooFewSamples);
}

TEST(IdentifyEstimate, ARowLeftOutIsNotReadAndEachJointCountsItsOwnRows) {
  // Joint 1's row left out of every odd sample (identify::moving_rows leaves a joint out about its reversals), its y
  // there corrupted: not read. Without a payload the joints' friction blocks are uncoupled, so joint 1's coefficients
  // and sigma are those of the even samples alone (its residual variance from its own rows), and the other joints'
  // those of every sample.
  const std::uint16_t mask = payload_mask::kNone;
  const std::vector<Vec6<double>> y = noisy(mask, 13, kNoise);
  static IdentifyEstimate left_out, even, all;
  left_out.reset(mask), even.reset(mask), all.reset(mask);
  const std::uint8_t without_j1 = identify::kAllRows & ~1u;
  for (std::size_t k = 0; k < y.size(); ++k) {
    Vec6<double> yk = y[k];
    if (k % 2) yk(0) += 1e3;
    left_out.add(yk, design()[k].w, k % 2 ? without_j1 : identify::kAllRows);
    if (k % 2 == 0) even.add(y[k], design()[k].w);
    all.add(y[k], design()[k].w);
  }
  const IdentifyReport r = left_out.solve(), e = even.solve(), a = all.solve();
  ASSERT_EQ(r.status, IdentifyStatus::kOk);
  for (int c = 0; c < 3; ++c) {
    const int j1 = c * kDof, j2 = c * kDof + 1;
    EXPECT_NEAR(r.friction(j1), e.friction(j1), 1e-9 * std::abs(e.friction(j1)) + 1e-12) << c;
    EXPECT_NEAR(r.friction_sd(j1), e.friction_sd(j1), 1e-9 * e.friction_sd(j1)) << c;
    EXPECT_NEAR(r.friction(j2), a.friction(j2), 1e-9 * std::abs(a.friction(j2)) + 1e-12) << c;
  }
  EXPECT_NEAR(r.residual_rms(0), e.residual_rms(0), 1e-9 * e.residual_rms(0));
  // A joint with no row at all: too few samples, though every sample was added.
  static IdentifyEstimate none;
  none.reset(mask);
  for (std::size_t k = 0; k < y.size(); ++k) none.add(y[k], design()[k].w, without_j1);
  EXPECT_EQ(none.solve().status, IdentifyStatus::kTooFewSamples);
}

TEST(IdentifyEstimate, DependentColumnsAreIllConditioned) {
  // (a) J3's Stribeck column the Coulomb column (a decay of 0): exactly dependent. (b) J5 never moves: its three
  // columns zero. (c) Every joint at 5 % of the excitation's speed: the Stribeck decay 0.4 % of its level, the
  // columns nearly dependent, a finite condition above the bound.
  for (int c = 0; c < 3; ++c) {
    static IdentifyEstimate e;
    e.reset(payload_mask::kNone);
    const std::vector<Sample> slow = c == 2 ? samples_of(0.05) : std::vector<Sample>{};
    for (std::size_t k = 0; k < design().size(); ++k) {
      const Sample& d = c == 2 ? slow[k] : design()[k];
      RegressorDiagonals<double> w = d.w;
      if (c == 0) w.sti(2) = w.cou(2);
      if (c == 1) w.vis(4) = w.cou(4) = w.sti(4) = 0;
      e.add(Vec6<double>(w.times(kFriction.theta())), w);
    }
    const IdentifyReport r = e.solve();
    std::printf("case %c: status %d, condition %.3g\n", 'a' + c, static_cast<int>(r.status), r.condition);
    EXPECT_EQ(r.status, IdentifyStatus::kIllConditioned) << c;
    if (c == 2) {
      EXPECT_TRUE(std::isfinite(r.condition) && r.condition > params::kIdentifyMaxCondition);
    } else {
      EXPECT_TRUE(std::isinf(r.condition));  // H not positive definite: singular
    }
  }
}

TEST(IdentifyEstimate, ABiasTheModelCannotExplainIsAPredictionError) {
  // 4 N m more on J1 at every sample, which no friction column holds (sgn qd is not a constant): its residual
  // keeps most of it, over 20 % of its torque.
  std::vector<Vec6<double>> y = noisy(payload_mask::kNone, 6, kNoise);
  for (Vec6<double>& v : y) v(0) += 4;
  const IdentifyReport r = estimate(payload_mask::kNone, y);
  std::printf("bias: J1's prediction error %.3f, J2's %.3f\n", r.prediction_error(0), r.prediction_error(1));
  EXPECT_EQ(r.status, IdentifyStatus::kPredictionError);
  EXPECT_EQ(r.worst_joint, 0);
  EXPECT_GT(r.worst_prediction_error, params::kIdentifyMaxPredictionError);
  EXPECT_EQ(estimate(payload_mask::kNone, noisy(payload_mask::kNone, 6, kNoise)).status, IdentifyStatus::kOk);
}

TEST(IdentifyEstimate, ANonFiniteSampleIsNotFiniteAndAnUnselectedColumnIsNotRead) {
  std::vector<Vec6<double>> y = noisy(payload_mask::kNone, 7, kNoise);
  y[100](3) = std::numeric_limits<double>::quiet_NaN();
  const IdentifyReport r = estimate(payload_mask::kNone, y);
  EXPECT_EQ(r.status, IdentifyStatus::kNotFinite);
  EXPECT_EQ(r.samples, design().size() - 1);  // that sample left out of the sums
  // A NaN in a payload column the mask does not select is never read.
  static IdentifyEstimate e;
  e.reset(payload_mask::kMassAndMoment);
  const std::vector<Vec6<double>> good = noisy(payload_mask::kMassAndMoment, 7, kNoise);
  for (std::size_t k = 0; k < design().size(); ++k) {
    PayloadRegressor<double> Y = design()[k].Y;
    Y.col(5).setConstant(std::numeric_limits<double>::quiet_NaN());  // Ixy's
    e.add(good[k], design()[k].w, Y);
  }
  EXPECT_EQ(e.solve().status, IdentifyStatus::kOk);
}

// ---------------------------------------------------------------- the payload's subsets

TEST(IdentifyEstimate, APayloadSubsetEstimatesItsEntriesAndReportsTheOthersNotEstimated) {
  for (const std::uint16_t mask : {payload_mask::kMass, payload_mask::kMassAndMoment, std::uint16_t{0x0F1}}) {
    const IdentifyReport r = estimate(mask, noisy(mask, 8, Vec6<double>::Zero()));
    EXPECT_EQ(r.status, IdentifyStatus::kOk) << mask;
    for (int k = 0; k < 10; ++k) {
      if (mask >> k & 1u) {
        EXPECT_NEAR(r.payload(k), kTruePi(k), 1e-9) << mask << " " << k;
        EXPECT_NE(r.payload_verdict[k], CoefficientVerdict::kNotEstimated);
      } else {
        EXPECT_EQ(r.payload(k), 0) << mask << " " << k;
        EXPECT_EQ(r.payload_sd(k), 0) << mask << " " << k;
        EXPECT_EQ(r.payload_verdict[k], CoefficientVerdict::kNotEstimated);
      }
    }
  }
}

TEST(IdentifyEstimate, TheVerdictIsTheExcitationMonitorsRule) {
  // identified exactly where sd <= params::kIdentifiedFraction |value| (friction_identified), and both verdicts met
  // on the PUMA's excitation with its noise (the Stribeck levels of the wrist are the hardest).
  const IdentifyReport r = estimate(payload_mask::kNone, noisy(payload_mask::kNone, 9, 3 * kNoise));
  int identified = 0;
  for (int k = 0; k < 3 * kDof; ++k) {
    const bool rule = r.friction_sd(k) <= params::kIdentifiedFraction * std::abs(r.friction(k));
    EXPECT_EQ(r.friction_verdict[k] == CoefficientVerdict::kIdentified, rule) << k;
    identified += rule;
  }
  std::printf("identified %d of 18 at three times the noise\n", identified);
  EXPECT_GT(identified, 0);
  EXPECT_LT(identified, 3 * kDof);
}

TEST(IdentifyEstimate, TheExcitationsConditionStaysWithinTheBoundDownToItsSmallestScale) {
  // params::kIdentifyMaxCondition's figures: the prepared motion, and every gain at the smallest scale the plan
  // accepts (kExcitationMinScale's tries: 0.512), with all ten payload entries; and each joint's friction block
  // alone, column-normalised.
  for (const double scale : {1.0, 0.512}) {
    static IdentifyEstimate e;
    e.reset(payload_mask::kAll);
    for (const Sample& s : samples_of(scale)) e.add(s.y(payload_mask::kAll), s.w, s.Y);
    const IdentifyReport r = e.solve();
    std::printf("scale %.3f, all ten: condition %.4g\n", scale, r.condition);
    EXPECT_LT(r.condition, 2e4) << scale;  // the figures' 14 000 at most, with room
  }
  for (int i = 0; i < kDof; ++i) {
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    for (const Sample& s : design()) {
      const Eigen::Vector3d p(s.w.vis(i), s.w.cou(i), s.w.sti(i));
      M += p * p.transpose();
    }
    const Eigen::Vector3d D = M.diagonal().cwiseSqrt().cwiseInverse();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(D.asDiagonal() * M * D.asDiagonal());
    std::printf("J%d's friction block: condition %.4g\n", i + 1, eig.eigenvalues()(2) / eig.eigenvalues()(0));
  }
}

// ---------------------------------------------------------------- float and fixed-point inputs

TEST(IdentifyEstimate, FloatAndQ1219SamplesAreSummedInDouble) {
  // The same samples rounded to float and to Q12.19 on their way in: the estimates differ from double's by what the
  // inputs' rounding does (2^-20 of the regressors, 1e-6 N m of y), within a tenth of a standard deviation.
  const std::uint16_t mask = payload_mask::kMassAndMoment;
  const std::vector<Vec6<double>> y = noisy(mask, 10, kNoise);
  const IdentifyReport d = estimate(mask, y);
  static IdentifyEstimate ef, ex;
  ef.reset(mask), ex.reset(mask);
  for (std::size_t k = 0; k < design().size(); ++k) {
    const Sample& s = design()[k];
    ef.add(Vec6<float>(y[k].cast<float>()),
           RegressorDiagonals<float>{s.w.vis.cast<float>(), s.w.cou.cast<float>(), s.w.sti.cast<float>()},
           PayloadRegressor<float>(s.Y.cast<float>()));
    ex.add(Vec6<Fixed>(y[k].cast<Fixed>()),
           RegressorDiagonals<Fixed>{s.w.vis.cast<Fixed>(), s.w.cou.cast<Fixed>(), s.w.sti.cast<Fixed>()},
           PayloadRegressor<Fixed>(s.Y.cast<Fixed>()));
  }
  for (IdentifyEstimate* e : {&ef, &ex}) {
    const IdentifyReport r = e->solve();
    const double worst = (unknowns(r, mask, false) - unknowns(d, mask, false))
                             .cwiseQuotient(unknowns(d, mask, true))
                             .cwiseAbs()
                             .maxCoeff();
    std::printf("%s inputs: worst difference %.2e sd\n", e == &ef ? "float" : "Q12.19", worst);
    EXPECT_EQ(r.status, IdentifyStatus::kOk);
    EXPECT_LT(worst, 0.1);
  }
}

// ---------------------------------------------------------------- the run end to end, with KDL's torques

namespace {

/// KDL's inverse dynamics of the arm's chain (armature included, as the model's), with the payload as one more rigid
/// segment at frame 6 or without it.
class KdlArm {
 public:
  explicit KdlArm(bool with_payload) : chain_(test::puma560_chain()) {
    if (with_payload) {
      const double* I = kPayload.inertia;
      chain_.addSegment(KDL::Segment(
          KDL::Joint(KDL::Joint::None), KDL::Frame::Identity(),
          KDL::RigidBodyInertia(kPayload.mass, KDL::Vector(kPayload.com[0], kPayload.com[1], kPayload.com[2]),
                                KDL::RotationalInertia(I[0], I[1], I[2], I[3], I[4], I[5]))));
    }
    id_ = std::make_unique<KDL::ChainIdSolver_RNE>(chain_, KDL::Vector(0, 0, -robot::kArm.gravity));
  }
  Vec6<double> torque(const Vec6<double>& q, const Vec6<double>& qd, const Vec6<double>& qdd) const {
    KDL::JntArray tau(kDof);
    const KDL::Wrenches none(chain_.getNrOfSegments(), KDL::Wrench::Zero());
    EXPECT_GE(id_->CartToJnt(to_kdl(q), to_kdl(qd), to_kdl(qdd), none, tau), 0);
    return from_kdl(tau);
  }

 private:
  KDL::Chain chain_;
  std::unique_ptr<KDL::ChainIdSolver_RNE> id_;
};

/// The payload's mass error (relative) and centre of mass error [m] of a report.
struct PayloadErrors {
  double mass, com;
};
PayloadErrors payload_errors(const IdentifyReport& r) {
  const Payload b = PayloadParams<double>::of(r.payload).body();
  const Eigen::Vector3d c(b.com[0], b.com[1], b.com[2]), truth(kPayload.com[0], kPayload.com[1], kPayload.com[2]);
  return {std::abs(b.mass / kPayload.mass - 1), (c - truth).norm()};
}

void print_run(const char* what, const IdentifyReport& r) {
  const PayloadErrors e = payload_errors(r);
  const Vec18<double> rel = (r.friction - kFriction.theta()).cwiseQuotient(kFriction.theta().cwiseAbs());
  std::printf(
      "%s: status %d, mass %.5f kg (%.2e), COM error %.3f mm, friction worst %.2e relative, condition %.4g, "
      "worst prediction error %.2e (J%d)\n",
      what, static_cast<int>(r.status), r.payload(0), e.mass, 1e3 * e.com, rel.cwiseAbs().maxCoeff(), r.condition,
      r.worst_prediction_error, r.worst_joint + 1);
}

}  // namespace

TEST(IdentifyRun, KdlsTorquesAlongTheExcitationGiveThePayloadAndTheFriction) {
  // Parts 1 and 3: at every sample of the excitation (every 5 ms over a period), y = KDL's torque with the payload,
  // plus the friction (2), less KDL's without it: the torque the arm's model leaves. No noise. All ten entries: the
  // truth within the sums' rounding (mass within 0.1 %, COM within 0.1 mm asked; 1e-9 asserted). The mass and
  // first moments alone leave the payload's inertia about the flange unmodelled: within issue 57's bars (mass 3 %,
  // COM 5 mm) still, measured 0.16 % and 2.3 mm, which is why a run estimates all ten.
  const KdlArm with(true), without(false);
  for (const std::uint16_t mask : {payload_mask::kAll, payload_mask::kMassAndMoment}) {
    static IdentifyEstimate e;
    e.reset(mask);
    for (const Sample& s : design()) {
      const Vec6<double> tau = with.torque(s.q, s.qd, s.qdd) + friction_torque(kFriction, s.qd);
      e.add(Vec6<double>(tau - without.torque(s.q, s.qd, s.qdd)), s.w, s.Y);
    }
    const IdentifyReport r = e.solve();
    print_run(mask == payload_mask::kAll ? "exact states, all ten" : "exact states, m and h", r);
    const PayloadErrors p = payload_errors(r);
    EXPECT_EQ(r.status, IdentifyStatus::kOk);
    EXPECT_LT(p.mass, mask == payload_mask::kAll ? 1e-9 : 0.03);
    EXPECT_LT(p.com, mask == payload_mask::kAll ? 1e-9 : 5e-3);
    if (mask == payload_mask::kAll) {
      EXPECT_LT((r.friction - kFriction.theta()).cwiseQuotient(kFriction.theta()).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}

namespace {
/// Parts 1, 2 and 3 as the board will run them, over the whole run (8 periods): every tick the angles (exact, or
/// rounded to the encoders' counts: kEncodersUniform, 1e-4 rad on the PUMA's J1), the torque (KDL's with the
/// payload plus the friction) and the velocity through IdentifyFilter, primed at rest at the start; every 5 ticks a
/// sample, y = F tau less the model's rigid-body torque (rnea, KDL's within 1e-9) at the filtered states, Y at the
/// filtered states, each joint's row away from its reversals (identify::moving_rows); sigma with the correlation
/// factor of noise white before F.
IdentifyReport filtered_run(bool quantised) {
  const KdlArm with(true);
  IdentifyFilter<double> f;
  const Vec6<double> q0 = motion().start(), zero = Vec6<double>::Zero();
  f.prime(q0, with.torque(q0, zero, zero), zero, kFriction.dec);
  static IdentifyEstimate e;
  e.reset(payload_mask::kAll);
  Data<double> data;
  const auto counts = robot::kEncodersUniform.counts_per_rad;
  for (std::uint64_t n = 1; n <= motion().ticks(); ++n) {
    const JointSample<double> d = motion().at_tick(n);
    Vec6<double> q = d.q;
    for (int i = 0; i < kDof && quantised; ++i) q(i) = std::round(d.q(i) * counts[i]) / counts[i];
    f.update(q, Vec6<double>(with.torque(d.q, d.qd, d.qdd) + friction_torque(kFriction, d.qd)), d.qd);
    if (n % kEvery != 0) continue;
    const IdentifySignals<double> s = f.signals();
    forward_kinematics(model(), data, s.q);
    geometric_jacobian(data);
    const Vec6<double> y = s.tau - rnea(model(), data, s.qd, s.qdd, true).tau;
    e.add(y, s.w, PayloadRegressor<double>(payload_regressor(model(), data, s.qd, s.qdd)), identify::moving_rows(s.qd));
  }
  return e.solve(identify::noise_correlation_factor(kEvery));
}
}  // namespace

TEST(IdentifyRun, ThroughTheRunsFilterAt1kHz) {
  // The filter's own error: the rigid-body model at the filtered states is not the filtered torque
  // (params::kIdentifyFilterOmega). Measured at 10 Hz, the rates the velocity's through F: exact angles and the
  // encoders' counts alike (the counts reach only q_f), mass 0.09 %, COM 0.055 mm, friction within 1.4 %, the worst
  // prediction error 0.064 % (J2). Asserted: issue 57's bars for an identified coefficient (within 10 %, or 0.05
  // where that is more), every coefficient within 3 sigma with the counts, mass within 0.2 %, COM within 0.2 mm.
  for (const bool quantised : {false, true}) {
    const IdentifyReport r = filtered_run(quantised);
    print_run(quantised ? "filtered, encoders' counts" : "filtered, exact angles", r);
    const PayloadErrors p = payload_errors(r);
    EXPECT_EQ(r.status, IdentifyStatus::kOk) << quantised;
    EXPECT_LT(p.mass, 2e-3) << quantised;
    EXPECT_LT(p.com, 2e-4) << quantised;
    int identified = 0;
    for (int k = 0; k < 3 * kDof; ++k) {
      const double truth = kFriction.theta()(k), error = std::abs(r.friction(k) - truth);
      if (r.friction_verdict[k] == CoefficientVerdict::kIdentified) {
        ++identified;
        EXPECT_LE(error, std::max(0.1 * truth, 0.05)) << quantised << " " << k;
      }
      if (quantised) {
        EXPECT_LE(error, 3 * r.friction_sd(k)) << k;
      }
    }
    std::printf("  %d of 18 friction coefficients identified\n", identified);
  }
}
