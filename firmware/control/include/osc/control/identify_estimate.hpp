// The identification run's estimate (issue 57): the 18 friction coefficients of model (2) and optionally a payload's
// inertial parameters (osc/kernels/payload.hpp) by weighted least squares over the run's samples, each with an honest
// standard deviation, and the run's verdict by name.
//
// The regression. At a sample, for each joint i (the signals through the run's filter, identify_filter.hpp),
//   y_i = F tau_i - tau_rb,i(q_f, qd_f, qdd_f) = w_i^T theta_i + Y_i pi + e_i,
// y_i the torque the model leaves (the caller forms it), w_i the joint's filtered friction columns (vis, cou, sti),
// theta_i = (vis_i, cou_i, sti_i), Y_i the payload regressor's row and pi the payload's parameters, all ten or the
// subset a mask selects. Optionally a joint's row also carries dI_i qdd_i, dI_i the correction to the model's
// armature (the rotor's inertia referred to the joint, G^2 J_m: the PUMA's two published sets differ by 2.4 kg m^2
// on J2, which left out goes into the friction and fails the run on its prediction error), and -b_i, b_i the torque
// the drive adds to the one commanded (an amplifier's offset: 0.1 % of J5's range moved its Coulomb / Stribeck split by
// 0.43 N m, 8.5 times issue 57's bar, with the sum unchanged: test_identify_sim, "*Offset*"). A run that moves
// estimates all ten: about the flange a payload's inertia is mostly m |c|^2 (1.5 kg at 87 mm: 0.012 of its 0.014 kg
// m^2), and left out it goes into the friction and the centre of mass (on the excitation 2.3 mm, 0.16 %, a friction
// coefficient 9
// %: test_identify_estimate.cpp); the mass and first moments alone (payload_mask::kMassAndMoment) are for poses held
// still. Friction is per joint (Property 4), the payload common to all: the information matrix is block-arrowed, the
// friction blocks coupled only through pi.
//
// The sums. Per joint, of phi = (w_i, qdd_i, 1, Y_i) (15 columns): the symmetric block sum phi phi^T, its right-hand
// side sum phi y, sum y^2 and the count. In double on every target: a run's 10^4 samples of products of regressors
// spanning 10^3 in size need more than float's 24 bits or Q12.19's resolution, and an accumulator that rounds a
// sample's share away biases the estimate; the samples arrive at 100 Hz at most, outside the control tick. Any
// parameter vector's residual sum of squares per joint follows from them: RSS_i = sum y^2 - 2 x^T b_i + x^T M_i x.
//
// The solve (solve()). The unknowns x = [theta; pi's selected entries] (theta in FrictionParams::theta's order: vis,
// cou, sti, each per joint), the normal equations sum_i M_i / s_i^2 x = sum_i b_i / s_i^2 assembled from the blocks,
// weighted per joint by its residual variance s_i^2 = RSS_i / (n_i - p_i) (n_i its rows summed), p_i = 3 + n_pi / 6
// (its own coefficients and an equal share of the payload's, so that the p_i sum to the unknowns): unweighted first
// (s_i = 1), then weighted with the variances of its residuals, then once more with the weighted solution's (Gautier's
// weighted least squares). Each solve factors the column-normalised matrix H = D A D (D = diag(A)^-1/2, unit
// diagonal) as L D' L^T (identify::PackedLdlt, no pivoting: H is positive definite when the motion excites every
// column; it is not when a column is zero or a combination of others). Payload entries the mask leaves out are rows of
// the identity: their eigenvalue 1 lies between H's extremes, so they change neither the solution nor the condition.
//
// What it reports (IdentifyReport). Each coefficient with its standard deviation sqrt(kappa (A^-1)_jj), A the
// weighted information matrix and its inverse's diagonal by solves (A^-1 = D H^-1 D, column j of H^-1 solved
// for e_j). kappa >= 1 is the caller's factor for correlated samples: noise alike in neighbouring samples carries
// less information than as many independent ones, and A counts them as independent. For noise white before the
// run's filter and samples every d ticks it is identify::noise_correlation_factor(d) (12.7 at 5 ms: the coverage
// of 2 sigma is 95 % with it and 45 % without, test_identify_estimate.cpp); 1 for independent samples; for noise
// coloured at the motion's own frequencies (a model error) more, which no factor from the filter knows. The
// condition number of H, estimated by power iterations on H and on H^-1 (through the factor), each until its
// Rayleigh quotient moves by less than 1e-6: a lower bound (within 1e-5 of the eigenvalues' ratio in the test),
// reported with the upper bound ||H||_inf trace(H^-1). Per joint the residual rms sqrt(RSS_i / n) and the
// torque-prediction error, the rms residual over the rms of y_i. Each coefficient's verdict by the excitation monitor's
// rule (friction_identified, osc/control/identification.hpp: identified when its standard deviation is at most
// params::kIdentifiedFraction of its value), the payload's entries too (an entry near 0, a first moment along an
// axis the centre of mass is on, is never identified by a relative rule, however well it is known). The status, the
// first of: kNotFinite (a sample or the solution not finite; such a sample is not summed), kTooFewSamples (a joint with
// fewer rows than params::kIdentifyMinSamples), kIllConditioned (H not positive definite or its condition above
// params::kIdentifyMaxCondition), kPredictionError (a joint's prediction error above
// params::kIdentifyMaxPredictionError), else kOk.
//
// Size and cost: the sums 11.6 kB, the solve's workspace (H and its factor packed in one matrix, a member so that the
// board's stack does not hold it) 13.8 kB; a sample 6 x 120 multiply-adds with the armatures, the offsets and the
// payload's ten (6 x 15 without the payload); a solve three factorisations of 40 x 40, 40 solves and at most 2 x 200
// power iterations, once per run. No heap.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "osc/control/faults.hpp"  // OSC_X_NAME, OSC_X_DOC, OSC_X_ENUMERATOR
#include "osc/control/identification.hpp"
#include "osc/control/params.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/kernels/payload.hpp"

namespace osc {

/// Which of pi's entries a run estimates: bit k for pi(k) (payload.hpp's order: m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy,
/// Iyz, Izz).
namespace payload_mask {
constexpr std::uint16_t kNone = 0;
constexpr std::uint16_t kMass = 0x001;
constexpr std::uint16_t kMassAndMoment = 0x00F;  ///< m and h = m c: the mass and the centre of mass
constexpr std::uint16_t kAll = 0x3FF;
}  // namespace payload_mask

/// A run's verdict (IdentifyReport::status), the first that applies; aborted is the board's, for a run whose motion
/// was aborted (a stop, a fault: no estimate).
#define OSC_IDENTIFY_STATUS_LIST(X)                                                                               \
  X(Ok, "ok", "the estimate is reported; each coefficient says whether it is identified")                         \
  X(TooFewSamples, "too_few_samples", "a joint moved too little: fewer rows than params::kIdentifyMinSamples")    \
  X(IllConditioned, "ill_conditioned",                                                                            \
    "the columns (nearly) dependent: the condition above params::kIdentifyMaxCondition")                          \
  X(PredictionError, "prediction_error",                                                                          \
    "a joint's torque-prediction error above params::kIdentifyMaxPredictionError (20 %): the model does not fit") \
  X(NotFinite, "not_finite", "a sample or the solution not finite")                                               \
  X(Aborted, "aborted", "the run's motion was aborted (a stop, a fault, a collision): no estimate")

#define OSC_X_PREFIX k
enum class IdentifyStatus : std::uint8_t { OSC_IDENTIFY_STATUS_LIST(OSC_X_ENUMERATOR) };
#undef OSC_X_PREFIX
constexpr const char* kIdentifyStatusNames[] = {OSC_IDENTIFY_STATUS_LIST(OSC_X_NAME)};
constexpr const char* kIdentifyStatusDocs[] = {OSC_IDENTIFY_STATUS_LIST(OSC_X_DOC)};
constexpr int kIdentifyStatusCount = sizeof(kIdentifyStatusNames) / sizeof(*kIdentifyStatusNames);
constexpr const char* identify_status_name(IdentifyStatus s) { return kIdentifyStatusNames[static_cast<int>(s)]; }

/// A coefficient's verdict.
enum class CoefficientVerdict : std::uint8_t {
  kIdentified,   ///< its standard deviation within params::kIdentifiedFraction of its value
  kNotExcited,   ///< estimated, but the motion did not pin it down that far
  kNotEstimated  ///< a payload entry the mask left out (reported as 0)
};

/// What solve() found. Coefficients in SI units, their standard deviations likewise (+inf where none could be had).
struct IdentifyReport {
  IdentifyStatus status = IdentifyStatus::kNotFinite;
  Vec18<double> friction = Vec18<double>::Zero();  ///< theta = [vis; cou; sti], FrictionParams::theta's order
  Vec18<double> friction_sd = Vec18<double>::Zero();
  /// The joints' armature corrections (what the model's armature lacks, N m s^2/rad: 0 where not estimated).
  Vec6<double> armature = Vec6<double>::Zero();
  Vec6<double> armature_sd = Vec6<double>::Zero();
  /// The torque each drive adds to the one commanded, a constant (an amplifier's offset, N m: 0 where not estimated).
  Vec6<double> offset = Vec6<double>::Zero();
  Vec6<double> offset_sd = Vec6<double>::Zero();
  PayloadVector<double> payload = PayloadVector<double>::Zero();  ///< pi (0 where not estimated)
  PayloadVector<double> payload_sd = PayloadVector<double>::Zero();
  std::array<CoefficientVerdict, 3 * kDof> friction_verdict{};
  std::array<CoefficientVerdict, 10> payload_verdict{};
  /// The column-normalised information matrix's condition by power iterations (from below), and ||H||_inf
  /// trace(H^-1) (from above); +inf where H is singular, 0 where no solve ran (too few samples, not finite).
  double condition = 0;
  double condition_bound = 0;
  Vec6<double> noise_sd = Vec6<double>::Zero();          ///< the s_i the solution was weighted with [N m]
  Vec6<double> residual_rms = Vec6<double>::Zero();      ///< sqrt(RSS_i / n) [N m]
  Vec6<double> prediction_error = Vec6<double>::Zero();  ///< rms residual / rms y_i
  double worst_prediction_error = 0;
  int worst_joint = -1;
  std::uint32_t samples = 0;
};

namespace identify {
constexpr std::uint8_t kAllRows = (1u << kDof) - 1;  // every joint's row of a sample
constexpr int kJointColumns = 15;   // a joint's phi: its 3 friction columns, its armature's, its offset's, pi's 10
constexpr int kArmatureColumn = 3;  // the armature's local column, then the offset's; the payload's follow them
constexpr int kOffsetColumn = 4;
constexpr int kPayloadColumn = 5;
constexpr int kUnknowns = 5 * kDof + 10;          // theta, the armatures' corrections, the offsets and pi
constexpr int kPowerIterations = 200;             // the condition's estimate: at most, each way
constexpr double kPowerTolerance = 1e-6;          // ... or until the Rayleigh quotient moves less than this (relative)
constexpr double kVarianceFloor = 1e-24;          // [N^2 m^2]: a joint whose model fits exactly still gets a weight
constexpr double kRelativeVarianceFloor = 1e-12;  // ... and at least this of its mean square

/// Where a joint's local column l (0-2 friction, 3 armature, 4 offset, 5-14 pi) sits among the unknowns.
constexpr int unknown_index(int joint, int l) {
  return l < kPayloadColumn ? l * kDof + joint : 5 * kDof + l - kPayloadColumn;
}

using Matrix = Eigen::Matrix<double, kUnknowns, kUnknowns>;
using Vector = Eigen::Matrix<double, kUnknowns, 1>;

/// H = L D L^T of a symmetric matrix H, packed in one matrix: H in its upper triangle and diagonal, L's strict
/// lower part below (its unit diagonal implied), D apart. No pivoting (H positive definite); a pivot at most
/// kUnknowns epsilon, H's diagonal being 1 (column-normalised), is singular to working precision. Loops, not
/// LdltFactor (osc/kernels/opspace.hpp), which unrolls each row for the tick's 6 x 6: at 28 x 28 the estimate's code
/// took 72 kB of an M4F build with it and takes 12 kB with this, for a factorisation that runs three times a run;
/// and H and its factor share one matrix (12.8 kB at 40 x 40).
struct PackedLdlt {
  Matrix m;
  Vector d;

  bool factor() {
    for (int j = 0; j < kUnknowns; ++j) {
      double dj = m(j, j);
      for (int k = 0; k < j; ++k) dj -= m(j, k) * m(j, k) * d(k);
      if (!(dj > kUnknowns * std::numeric_limits<double>::epsilon())) return false;
      d(j) = dj;
      for (int i = j + 1; i < kUnknowns; ++i) {
        double v = m(j, i);  // H(i, j), from the upper triangle
        for (int k = 0; k < j; ++k) v -= m(i, k) * m(j, k) * d(k);
        m(i, j) = v / dj;
      }
    }
    return true;
  }
  /// H^-1 b: L y = b, then L^T x = D^-1 y.
  Vector solve(const Vector& b) const {
    Vector x = b;
    for (int i = 1; i < kUnknowns; ++i)
      for (int k = 0; k < i; ++k) x(i) -= m(i, k) * x(k);
    x = x.cwiseQuotient(d);
    for (int i = kUnknowns - 2; i >= 0; --i)
      for (int k = i + 1; k < kUnknowns; ++k) x(i) -= m(k, i) * x(k);
    return x;
  }
  /// H v, from the upper triangle.
  Vector times(const Vector& v) const { return m.selfadjointView<Eigen::Upper>() * v; }
  /// ||H||_inf, its largest row sum of magnitudes.
  double norm_inf() const {
    double largest = 0;
    for (int r = 0; r < kUnknowns; ++r) {
      double sum = 0;
      for (int c = 0; c < kUnknowns; ++c) sum += std::abs(r <= c ? m(r, c) : m(c, r));
      largest = std::max(largest, sum);
    }
    return largest;
  }
};
}  // namespace identify

/// The batch weighted least-squares estimate of a run (the file comment).
class IdentifyEstimate {
 public:
  using JointMatrix = Eigen::Matrix<double, identify::kJointColumns, identify::kJointColumns>;
  using JointVector = Eigen::Matrix<double, identify::kJointColumns, 1>;
  using Vector = identify::Vector;

  explicit IdentifyEstimate(std::uint16_t payload = payload_mask::kNone) { reset(payload); }

  /// Clears the sums; `payload` selects pi's entries (payload_mask), `armature` and `offset` the joints whose armature
  /// correction and torque offset are estimated (bit i for joint i; none by default).
  void reset(std::uint16_t payload, std::uint8_t armature = 0, std::uint8_t offset = 0) {
    mask_ = static_cast<std::uint16_t>(payload & payload_mask::kAll);
    armature_ = static_cast<std::uint8_t>(armature & identify::kAllRows);
    offset_ = static_cast<std::uint8_t>(offset & identify::kAllRows);
    for (int i = 0; i < kDof; ++i) {
      columns_[i] = 0;
      for (int l = 0; l < identify::kJointColumns; ++l)
        if (estimated(identify::unknown_index(i, l))) column_[i][columns_[i]++] = l;
    }
    for (int i = 0; i < kDof; ++i) M_[i].setZero(), b_[i].setZero();
    yy_.setZero();
    n_ = 0;
    rows_.fill(0);
    not_finite_ = false;
  }

  /// One sample: y_i (the torque the model leaves, per joint), the filtered friction columns, and the payload
  /// regressor (its rows Y_i; ignored where the mask selects nothing); `rows`: bit i for joint i's row, the rows
  /// summed (the caller leaves out a joint about its reversals: identify::moving_rows). A sample with a value
  /// that is not finite is not summed, and the run's status is kNotFinite.
  /// qdd: the joints' accelerations (the armature's columns; read only for the joints reset() selected).
  template <class S>
  void add(const Vec6<S>& y, const RegressorDiagonals<S>& w, const PayloadRegressor<S>& Y,
           std::uint8_t rows = identify::kAllRows, const Vec6<S>& qdd = Vec6<S>::Zero()) {
    double phi[kDof][identify::kJointColumns], yd[kDof];
    bool finite = true;
    for (int i = 0; i < kDof; ++i) {
      yd[i] = static_cast<double>(y(i));
      phi[i][0] = static_cast<double>(w.vis(i)), phi[i][1] = static_cast<double>(w.cou(i));
      phi[i][2] = static_cast<double>(w.sti(i));
      phi[i][identify::kArmatureColumn] = static_cast<double>(qdd(i));
      phi[i][identify::kOffsetColumn] = -1;  // b_i, added by the drive: y_i is short of it
      for (int k = 0; k < 10; ++k) phi[i][identify::kPayloadColumn + k] = static_cast<double>(Y(i, k));
      for (int c = 0; c < columns_[i]; ++c) finite = finite && std::isfinite(phi[i][column_[i][c]]);
      finite = finite && std::isfinite(yd[i]);
    }
    if (!finite) {
      not_finite_ = true;
      return;
    }
    for (int i = 0; i < kDof; ++i)
      if (rows >> i & 1u) accumulate(i, phi[i], yd[i]), ++rows_[i];
    ++n_;
  }
  /// A sample without a payload regressor (friction only: the mask selects nothing).
  template <class S>
  void add(const Vec6<S>& y, const RegressorDiagonals<S>& w, std::uint8_t rows = identify::kAllRows,
           const Vec6<S>& qdd = Vec6<S>::Zero()) {
    add(y, w, PayloadRegressor<S>(PayloadRegressor<S>::Zero()), rows, qdd);
  }

  std::uint32_t samples() const { return n_; }
  std::uint16_t mask() const { return mask_; }

  /// The estimate, its uncertainty and the run's verdict (the file comment). correlation_factor: kappa >= 1, the
  /// variance factor of correlated samples (identify::noise_correlation_factor of the decimation).
  IdentifyReport solve(double correlation_factor = 1) {
    IdentifyReport r;
    r.samples = n_;
    if (not_finite_) return failed(r, IdentifyStatus::kNotFinite);
    if (*std::min_element(rows_.begin(), rows_.end()) < params::kIdentifyMinSamples)
      return failed(r, IdentifyStatus::kTooFewSamples);
    Vec6<double> variance = Vec6<double>::Ones(), weights = variance;
    Vector x = Vector::Zero();
    for (int pass = 0; pass < 3; ++pass) {  // unweighted, then weighted twice
      if (!factor(variance)) {              // singular: a column never excited, or a combination of others
        r.condition = r.condition_bound = std::numeric_limits<double>::infinity();
        return failed(r, IdentifyStatus::kIllConditioned);
      }
      x = D_.cwiseProduct(f_.solve(D_.cwiseProduct(rhs_)));
      weights = variance;
      for (int i = 0; i < kDof; ++i) variance(i) = residual_variance(i, x);
    }
    r.noise_sd = weights.cwiseSqrt();
    report(r, x, correlation_factor);
    return r;
  }

 private:
  void accumulate(int i, const double* phi, double y) {
    for (int a = 0; a < columns_[i]; ++a) {
      const int la = column_[i][a];
      for (int c = a; c < columns_[i]; ++c) M_[i](la, column_[i][c]) += phi[la] * phi[column_[i][c]];
      b_[i](la) += phi[la] * y;
    }
    yy_(i) += y * y;
  }

  /// Joint i's local parameters (its theta_i and pi) out of the unknowns.
  JointVector local(int i, const Vector& x) const {
    JointVector v = JointVector::Zero();
    for (int c = 0; c < columns_[i]; ++c) v(column_[i][c]) = x(identify::unknown_index(i, column_[i][c]));
    return v;
  }
  /// Joint i's residual sum of squares at x, from the sums (never below 0: the sums' rounding).
  double rss(int i, const Vector& x) const {
    const JointVector v = local(i, x);
    const double s = yy_(i) - 2 * v.dot(b_[i]) + v.dot(M_[i].selfadjointView<Eigen::Upper>() * v);
    return s > 0 ? s : 0;
  }
  double degrees_of_freedom(int i) const {
    const int own = 3 + (armature_ >> i & 1u) + (offset_ >> i & 1u);  // and a sixth of pi's
    return static_cast<double>(rows_[i]) - own - (columns_[i] - own) / static_cast<double>(kDof);
  }
  /// s_i^2 = RSS_i / (n_i - p_i), at least kRelativeVarianceFloor of y_i's mean square and kVarianceFloor.
  double residual_variance(int i, const Vector& x) const {
    const double v = rss(i, x) / degrees_of_freedom(i), floor = identify::kRelativeVarianceFloor * yy_(i) / rows_[i];
    return std::max(v, std::max(floor, identify::kVarianceFloor));
  }

  /// The weighted normal equations A x = rhs_, assembled in f_'s upper triangle and column-normalised there (H = D
  /// A D, D_ the scaling), and H's factor.
  bool factor(const Vec6<double>& variance) {
    identify::Matrix& H = f_.m;
    H.setZero();
    rhs_.setZero();
    for (int i = 0; i < kDof; ++i)
      for (int a = 0; a < columns_[i]; ++a) {
        const int la = column_[i][a], ga = identify::unknown_index(i, la);
        for (int c = a; c < columns_[i]; ++c) {  // la <= lc, and ga <= gc: the upper triangle
          const int lc = column_[i][c];
          H(ga, identify::unknown_index(i, lc)) += M_[i](la, lc) / variance(i);
        }
        rhs_(ga) += b_[i](la) / variance(i);
      }
    for (int k = 0; k < identify::kUnknowns; ++k) {
      if (!(H(k, k) > 0)) H(k, k) = estimated(k) ? 0 : 1;  // a column never excited stays 0: H is singular
      D_(k) = H(k, k) > 0 ? 1 / std::sqrt(H(k, k)) : 1;
    }
    for (int c = 0; c < identify::kUnknowns; ++c)
      for (int r = 0; r <= c; ++r) H(r, c) *= D_(r) * D_(c);
    return f_.factor();
  }

  bool estimated(int k) const {
    if (k < 3 * kDof) return true;
    if (k < 5 * kDof) return (k < 4 * kDof ? armature_ >> (k - 3 * kDof) : offset_ >> (k - 4 * kDof)) & 1u;
    return mask_ >> (k - 5 * kDof) & 1u;
  }

  /// The report of the solution x, f_ the factor of its weights (the file comment's "What it reports").
  void report(IdentifyReport& r, const Vector& x, double kappa) const {
    Vector sd = Vector::Zero();
    double trace = 0;  // of H^-1
    for (int k = 0; k < identify::kUnknowns; ++k)
      if (estimated(k)) {
        const double h = f_.solve(Vector::Unit(k))(k);  // (H^-1)_kk
        trace += h;
        sd(k) = D_(k) * std::sqrt(kappa * h);
      }
    r.friction = x.head<3 * kDof>(), r.friction_sd = sd.head<3 * kDof>();
    r.armature = x.segment<kDof>(3 * kDof), r.armature_sd = sd.segment<kDof>(3 * kDof);
    r.offset = x.segment<kDof>(4 * kDof), r.offset_sd = sd.segment<kDof>(4 * kDof);
    r.payload = x.tail<10>(), r.payload_sd = sd.tail<10>();
    for (int k = 0; k < identify::kUnknowns; ++k) {
      if (k >= 3 * kDof && k < 5 * kDof) continue;  // an armature's correction, an offset: judged by the caller
      const CoefficientVerdict v = !estimated(k)                      ? CoefficientVerdict::kNotEstimated
                                   : friction_identified(x(k), sd(k)) ? CoefficientVerdict::kIdentified
                                                                      : CoefficientVerdict::kNotExcited;
      (k < 3 * kDof ? r.friction_verdict[k] : r.payload_verdict[k - 5 * kDof]) = v;
    }
    for (int i = 0; i < kDof; ++i) {
      const double e = rss(i, x);
      r.residual_rms(i) = std::sqrt(e / rows_[i]);
      const double inf = std::numeric_limits<double>::infinity();
      r.prediction_error(i) = yy_(i) > 0 ? std::sqrt(e / yy_(i)) : (e > 0 ? inf : 0);
      if (r.worst_joint < 0 || !(r.prediction_error(i) <= r.worst_prediction_error))
        r.worst_joint = i, r.worst_prediction_error = r.prediction_error(i);
    }
    r.condition = extreme_eigenvalue(false) * extreme_eigenvalue(true);  // lambda_max / lambda_min
    r.condition_bound = f_.norm_inf() * trace;
    const bool finite = math::all_finite(x) && math::all_finite(sd) && std::isfinite(r.condition);
    r.status = !finite                                                              ? IdentifyStatus::kNotFinite
               : !(r.condition <= params::kIdentifyMaxCondition)                    ? IdentifyStatus::kIllConditioned
               : !(r.worst_prediction_error <= params::kIdentifyMaxPredictionError) ? IdentifyStatus::kPredictionError
                                                                                    : IdentifyStatus::kOk;
  }

  /// H's largest eigenvalue by power iterations, or (inverse) H^-1's, through the factor: the Rayleigh quotient,
  /// which rises towards it, until it moves by less than kPowerTolerance of itself.
  double extreme_eigenvalue(bool inverse) const {
    Vector v;
    for (int k = 0; k < identify::kUnknowns; ++k) v(k) = 1 + static_cast<double>(k) / identify::kUnknowns;
    v.normalize();
    double lambda = 0;
    for (int it = 0; it < identify::kPowerIterations; ++it) {
      const Vector w = inverse ? f_.solve(v) : f_.times(v);
      const double next = v.dot(w);
      v = w / w.norm();
      const bool settled = std::abs(next - lambda) <= identify::kPowerTolerance * next;
      lambda = next;
      if (settled) break;
    }
    return lambda;
  }

  /// A report without a solution: no standard deviations, nothing identified.
  IdentifyReport& failed(IdentifyReport& r, IdentifyStatus s) const {
    r.status = s;
    r.friction_sd.setConstant(std::numeric_limits<double>::infinity());
    for (int i = 0; i < kDof; ++i) {
      r.armature_sd(i) = estimated(3 * kDof + i) ? std::numeric_limits<double>::infinity() : 0;
      r.offset_sd(i) = estimated(4 * kDof + i) ? std::numeric_limits<double>::infinity() : 0;
    }
    r.friction_verdict.fill(CoefficientVerdict::kNotExcited);
    for (int k = 0; k < 10; ++k) {
      const bool on = estimated(5 * kDof + k);
      r.payload_sd(k) = on ? std::numeric_limits<double>::infinity() : 0;
      r.payload_verdict[k] = on ? CoefficientVerdict::kNotExcited : CoefficientVerdict::kNotEstimated;
    }
    return r;
  }

  JointMatrix M_[kDof];  // upper triangles of the selected columns
  JointVector b_[kDof];
  Vec6<double> yy_;
  std::uint32_t n_ = 0;                     // samples
  std::array<std::uint32_t, kDof> rows_{};  // rows summed per joint
  bool not_finite_ = false;
  std::uint16_t mask_ = 0;
  std::uint8_t armature_ = 0, offset_ = 0;
  int column_[kDof][identify::kJointColumns] = {};  // each joint's selected local columns, in order
  int columns_[kDof] = {};
  identify::PackedLdlt f_;  // the solve's workspace: H and its factor
  Vector D_, rhs_;
};

}  // namespace osc
