// The excitation motion (osc/control/excitation.hpp): the series against its own formula evaluated here
// from the design's table (std::sin, std::cos), at rest at q0 at the start, at every whole period and at
// the end; the analytic derivatives against finite differences; every period the same, bit for bit; the
// check at the build's start pose, its every tick against Orocos KDL's inverse dynamics (the table's
// chain, tests/support/kdl_puma.hpp) and the bounds; the refusals by name; the design's excitation (each
// joint's speed, the velocities' Gram matrix); float and Q12.19 against double.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <memory>

#include "kdl_puma.hpp"
#include "osc/control/excitation.hpp"
#include "osc/math/fixed.hpp"
#include "test_util.hpp"

using namespace osc;
using test::from_kdl;
using test::to_kdl;

namespace {

constexpr std::uint32_t P = excitation::kPeriodTicks;
constexpr double kDt = params::kDt;
constexpr double kOmega = 2 * kPi / params::kExcitationPeriod;

/// The build's model and a workspace in scalar S.
template <class S>
const Model<S>& model() {
  static const Model<S> m = Model<S>::of(robot::kArm);
  return m;
}
template <class S>
Data<S>& workspace() {
  static const std::unique_ptr<Data<S>> d = std::make_unique<Data<S>>();
  return *d;
}

/// The orientation of frame 6 at q: the controller's reference orientation when it starts there.
Mat3<double> orientation_at(const Vec6<double>& q) {
  Data<double> d;
  forward_kinematics(model<double>(), d, q);
  return d.R[kDof];
}

/// A motion prepared in scalar S about q0 (R_ref: the orientation at q0), under lim.
template <class S>
struct Prepared {
  ExcitationMotion<S> motion;
  ExcitationCheck<S> check;
};

template <class S>
Prepared<S> prepare(const Vec6<double>& q0, const ExcitationLimits<S>& lim = ExcitationLimits<S>::defaults()) {
  Prepared<S> p;
  const Vec6<S> q = q0.cast<S>();
  const Mat3<S> R_ref = orientation_at(q0).cast<S>();
  test::NoMalloc guard;
  p.check = prepare_excitation<S>(model<S>(), workspace<S>(), q, R_ref, lim, p.motion);
  return p;
}

Vec6<double> start_pose() { return joint_vector<double>(robot::kQStart); }

/// The series (the file comment of excitation.hpp) evaluated here in double from the design's table and the
/// motion's gains, one harmonic at a time with std::sin and std::cos; its third derivative too.
struct Reference {
  Vec6<double> q, qd, qdd, qddd;
};
Reference formula(const Vec6<double>& q0, const Vec6<double>& gain, double t) {
  Reference r{q0, Vec6<double>::Zero(), Vec6<double>::Zero(), Vec6<double>::Zero()};
  for (int i = 0; i < kDof; ++i)
    for (int k = 1; k <= params::kExcitationHarmonics; ++k) {
      const double a = gain(i) * params::kExcitationCos[i][k - 1], b = gain(i) * params::kExcitationSin[i][k - 1];
      const double kw = k * kOmega, s = std::sin(kw * t), c = std::cos(kw * t);
      r.q(i) += a / kw * s - b / kw * c;
      r.qd(i) += a * c + b * s;
      r.qdd(i) += kw * (b * c - a * s);
      r.qddd(i) -= kw * kw * (a * c + b * s);
    }
  return r;
}

/// The gains the motion samples with (the fitted ones times its scale).
template <class S>
Vec6<double> gains(const ExcitationMotion<S>& m) {
  return (m.fit_gain().template cast<double>() * static_cast<double>(m.scale())).eval();
}

/// The figures of a run measured tick by tick here: each joint's peak speed, swing from q0 each way, and
/// torque needed by KDL's inverse dynamics plus the strongest friction.
struct RunFigures {
  Vec6<double> speed = Vec6<double>::Zero(), up = Vec6<double>::Zero(), down = Vec6<double>::Zero();
  Vec6<double> torque = Vec6<double>::Zero();
};

/// Prints each joint's figures (the docs' and the report's numbers).
void print_figures(const char* what, const Prepared<double>& p, const RunFigures& f) {
  std::printf("%s: %s, scale %.3f, %.1f s (%d periods of %.0f s)\n", what,
              p.check.status == ExcitationStatus::kOk ? "accepted" : "refused", p.check.scale, p.motion.duration(),
              params::kExcitationPeriods, params::kExcitationPeriod);
  for (int i = 0; i < kDof; ++i)
    std::printf(
        "  J%d: peak speed %.3f rad/s (%.3f of %.1f), swing -%.3f .. +%.3f rad, torque %.1f N m (%.3f of its limit "
        "%.1f), gain after travel %.3f of the speed's\n",
        i + 1, f.speed(i), f.speed(i) / params::kExcitationMaxSpeed, params::kExcitationMaxSpeed, f.down(i), f.up(i),
        f.torque(i), f.torque(i) / robot::kDrives.torque_limit[i], robot::kDrives.torque_limit[i],
        p.motion.fit_gain()(i) / p.motion.speed_gain()(i));
  std::printf("  clearance %.3f rad beyond the margin %.3f, rcond %.4f (threshold %.4f)\n", p.check.clearance,
              params::kExcitationPositionMargin, p.check.rcond, params::kPathMinRcond);
}

// ---------------------------------------------------------------- the design and the series

TEST(Excitation, TheDesignStartsEveryPeriodAtRestWithoutAStepInTheJerk) {
  // (C), which excitation.hpp asserts of the table at compile time, by its meaning: the formula at t = 0,
  // every gain 1, at rest at q0 with no jerk.
  const Reference r = formula(Vec6<double>::Zero(), Vec6<double>::Ones(), 0.0);
  for (int i = 0; i < kDof; ++i) {
    EXPECT_NEAR(r.q(i), 0, 1e-12) << i;
    EXPECT_NEAR(r.qd(i), 0, 1e-12) << i;
    EXPECT_NEAR(r.qdd(i), 0, 1e-12) << i;
    EXPECT_NEAR(r.qddd(i), 0, 1e-12) << i;
  }
  static_assert(excitation::kTicks * params::kDt <= params::kExcitationMaxDuration + 1e-9);
}

TEST(Excitation, StartsAndEndsAtRestAtQ0WithinTheLongestRun) {
  const Prepared<double> p = prepare<double>(start_pose());
  ASSERT_EQ(p.check.status, ExcitationStatus::kOk);
  const ExcitationMotion<double>& m = p.motion;
  const Vec6<double> q0 = start_pose();
  EXPECT_LE(m.duration(), params::kExcitationMaxDuration);
  EXPECT_EQ(m.ticks(), static_cast<std::uint64_t>(std::llround(m.duration() / kDt)));
  for (const JointSample<double>& d : {m.at_tick(0), m.at_tick(m.ticks()), m.at_tick(m.ticks() + 12345), m.at(0.0),
                                       m.at(m.duration()), m.at(-1.0), m.at(m.duration() + 1)}) {
    EXPECT_EQ(d.q, q0);
    EXPECT_EQ(d.qd, Vec6<double>::Zero());
    EXPECT_EQ(d.qdd, Vec6<double>::Zero());
  }
  // Next to the ends the formula itself tends to rest: q - q0 = O(t^4) (the jerk is 0 there too).
  const Reference g = formula(q0, gains(m), 0.0);
  EXPECT_LT((g.q - q0).cwiseAbs().maxCoeff(), 1e-14);
  for (const double t : {kDt, m.duration() - kDt}) {
    const JointSample<double> d = m.at(t);
    EXPECT_LT((d.q - q0).cwiseAbs().maxCoeff(), 1e-9) << t;
    EXPECT_LT(d.qd.cwiseAbs().maxCoeff(), 1e-6) << t;
    EXPECT_LT(d.qdd.cwiseAbs().maxCoeff(), 3e-3) << t;
  }
  // ... and it moves in between.
  EXPECT_GT(m.at(0.25 * params::kExcitationPeriod).qd.cwiseAbs().maxCoeff(), 0.1);
}

TEST(Excitation, TheSeriesIsItsFormulaAndItsDerivativesAreExact) {
  const Prepared<double> p = prepare<double>(start_pose());
  ASSERT_EQ(p.check.status, ExcitationStatus::kOk);
  const ExcitationMotion<double>& m = p.motion;
  const double h = 1e-4;
  double worst[3] = {0, 0, 0}, worst_fd[2] = {0, 0};
  for (double t = 0.0137; t < m.duration(); t += 0.731) {
    const JointSample<double> d = m.at(t), before = m.at(t - h), after = m.at(t + h);
    const Reference r = formula(m.start(), gains(m), t);
    worst[0] = std::max(worst[0], (d.q - r.q).cwiseAbs().maxCoeff());
    worst[1] = std::max(worst[1], (d.qd - r.qd).cwiseAbs().maxCoeff());
    worst[2] = std::max(worst[2], (d.qdd - r.qdd).cwiseAbs().maxCoeff());
    // Central differences: error h^2 / 6 times the next derivative (qddd <= 15 rad/s^3, the fourth 50).
    worst_fd[0] = std::max(worst_fd[0], ((after.q - before.q) / (2 * h) - d.qd).cwiseAbs().maxCoeff());
    worst_fd[1] = std::max(worst_fd[1], ((after.qd - before.qd) / (2 * h) - d.qdd).cwiseAbs().maxCoeff());
  }
  std::printf("series vs formula: q %.1e, qd %.1e, qdd %.1e; vs central differences: qd %.1e, qdd %.1e\n", worst[0],
              worst[1], worst[2], worst_fd[0], worst_fd[1]);
  EXPECT_LT(worst[0], 1e-12);
  EXPECT_LT(worst[1], 1e-12);
  EXPECT_LT(worst[2], 1e-11);
  EXPECT_LT(worst_fd[0], 1e-7);
  EXPECT_LT(worst_fd[1], 1e-6);
  // The tick and the time agree.
  for (std::uint64_t n = 1; n < m.ticks(); n += 997) {
    const JointSample<double> a = m.at_tick(n), b = m.at(static_cast<double>(n) * kDt);
    EXPECT_LT((a.q - b.q).cwiseAbs().maxCoeff(), 1e-12) << n;
    EXPECT_LT((a.qd - b.qd).cwiseAbs().maxCoeff(), 1e-11) << n;
  }
}

TEST(Excitation, EveryPeriodIsTheSameMotion) {
  const Prepared<float> p = prepare<float>(start_pose());
  ASSERT_EQ(p.check.status, ExcitationStatus::kOk);
  for (std::uint32_t n = 0; n < P; n += 7)
    for (int period = 1; period < params::kExcitationPeriods; ++period) {
      const JointSample<float> a = p.motion.at_tick(n), b = p.motion.at_tick(n + std::uint64_t{P} * period);
      ASSERT_EQ(a.q, b.q) << n << " " << period;  // bit for bit: the check's one period is the run's every tick
      ASSERT_EQ(a.qd, b.qd) << n << " " << period;
      ASSERT_EQ(a.qdd, b.qdd) << n << " " << period;
    }
  // By time: the same to the rounding of t + T.
  const Prepared<double> d = prepare<double>(start_pose());
  for (double t = 0.1; t < params::kExcitationPeriod; t += 0.377) {
    const JointSample<double> a = d.motion.at(t), b = d.motion.at(t + 3 * params::kExcitationPeriod);
    EXPECT_LT((a.q - b.q).cwiseAbs().maxCoeff(), 1e-12) << t;
  }
}

// ---------------------------------------------------------------- the check at the start pose

TEST(Excitation, AcceptedAtTheStartPoseEveryTickWithinTheBoundsByKdl) {
  const Prepared<double> p = prepare<double>(start_pose());
  ASSERT_EQ(p.check.status, ExcitationStatus::kOk) << "joint " << p.check.joint << " tick " << p.check.tick;
  const KDL::Chain chain = test::arm_chain(robot::kArm);
  KDL::ChainIdSolver_RNE id(chain, KDL::Vector(0, 0, -robot::kArm.gravity));
  KDL::Wrenches f_ext(chain.getNrOfSegments(), KDL::Wrench::Zero());
  KDL::JntArray tau_kdl(kDof);
  RunFigures f;
  double worst_vs_kdl = 0, clearance = 1e9;
  for (std::uint64_t n = 0; n <= p.motion.ticks(); ++n) {  // every tick of the run, not only the period checked
    const JointSample<double> d = p.motion.at_tick(n);
    ASSERT_GE(id.CartToJnt(to_kdl(d.q), to_kdl(d.qd), to_kdl(d.qdd), f_ext, tau_kdl), 0);
    // Friction (2) at the band's top without decay, written out here.
    const FrictionCoefficients& hi = robot::kModelErrorBounds.friction_hi;
    for (int i = 0; i < kDof; ++i) {
      const double s = d.qd(i) > 0 ? 1.0 : (d.qd(i) < 0 ? -1.0 : 0.0);
      const double need = std::abs(tau_kdl(i)) + std::abs(hi.vis[i] * d.qd(i) + (hi.cou[i] + hi.sti[i]) * s);
      f.torque(i) = std::max(f.torque(i), need);
      f.speed(i) = std::max(f.speed(i), std::abs(d.qd(i)));
      f.up(i) = std::max(f.up(i), d.q(i) - p.motion.start()(i));
      f.down(i) = std::max(f.down(i), p.motion.start()(i) - d.q(i));
      clearance = std::min({clearance, d.q(i) - robot::kArm.q_min[i], robot::kArm.q_max[i] - d.q(i)});
      ASSERT_LE(need, params::kExcitationTorqueFraction * robot::kDrives.torque_limit[i]) << n << " J" << i + 1;
      ASSERT_LE(std::abs(d.qd(i)), params::kExcitationMaxSpeed - params::kExcitationSpeedMargin) << n;
      ASSERT_LE(std::abs(d.qd(i)), robot::kDrives.max_joint_speed[i]) << n;
    }
    if (n <= P) {  // the check's own torque, recomputed: rnea against KDL
      Data<double>& data = workspace<double>();
      forward_kinematics(model<double>(), data, d.q);
      const Vec6<double> tau = rnea(model<double>(), data, d.qd, d.qdd, true).tau;
      worst_vs_kdl = std::max(worst_vs_kdl, (tau - from_kdl(tau_kdl)).norm() / std::max(from_kdl(tau_kdl).norm(), 1.0));
    }
  }
  print_figures("start pose", p, f);
  if (p.check.scale < 1) {  // why the full scale was refused
    ExcitationMotion<double> full = p.motion;
    full.set_scale(1.0);
    const ExcitationCheck<double> r = check_excitation(
        model<double>(), workspace<double>(), full, orientation_at(start_pose()), ExcitationLimits<double>::defaults());
    std::printf("  at scale 1: status %d, joint %d, tick %d, rcond %.4f\n", static_cast<int>(r.status), r.joint, r.tick,
                r.rcond);
  }
  EXPECT_LT(worst_vs_kdl, 1e-9);
  EXPECT_GE(clearance, params::kExcitationPositionMargin);
  // The check's extremes are the run's.
  for (int i = 0; i < kDof; ++i) {
    EXPECT_NEAR(p.check.speed(i), f.speed(i), 1e-12) << i;
    EXPECT_NEAR(p.check.torque(i), f.torque(i), 1e-9 * f.torque(i)) << i;
  }
  EXPECT_NEAR(p.check.clearance, clearance - params::kExcitationPositionMargin, 1e-12);
  EXPECT_GE(p.check.rcond, params::kPathMinRcond);
}

// On a coupled drive train (q = C e, the PUMA's wrist: model.drives) each motor's friction is at its own rate: the
// check's strongest friction is C^-T f(C^-1 q^dot), C solved here by Eigen from the encoders' map, every tick of the
// period, and differs from the joints' own on the wrist.
TEST(Excitation, OnACoupledDriveTrainTheCheckTakesEachMotorsFrictionAtItsRate) {
  EncoderMap map = robot::kDriveTrain.encoders;
  if (map.coupling_terms == 0) map.coupling[map.coupling_terms++] = {5, 4, -0.18};  // an arm without: a coupling
  Mat6<double> C = Mat6<double>::Identity();
  for (int k = 0; k < map.coupling_terms; ++k) C(map.coupling[k].row, map.coupling[k].col) += map.coupling[k].c;
  double c[kDof][kDof], inverse[kDof][kDof];
  coupling_matrices(map, c, inverse);
  Model<double> coupled = model<double>();
  coupled.drives = DriveCoupling<double>::of(inverse);
  ASSERT_TRUE(coupled.drives.coupled());
  const Prepared<double> p = prepare<double>(start_pose());
  ASSERT_EQ(p.check.status, ExcitationStatus::kOk);
  const ExcitationLimits<double> lim = ExcitationLimits<double>::defaults();
  const ExcitationCheck<double> r =
      check_excitation(coupled, workspace<double>(), p.motion, orientation_at(start_pose()), lim);
  ASSERT_EQ(r.status, ExcitationStatus::kOk);
  Vec6<double> want = Vec6<double>::Zero();
  for (std::uint32_t n = 0; n <= P; ++n) {
    const JointSample<double> d = p.motion.at_tick(n);
    Data<double>& data = workspace<double>();
    forward_kinematics(coupled, data, d.q);
    const Vec6<double> tau = rnea(coupled, data, d.qd, d.qdd, true).tau;
    const Vec6<double> e = C.triangularView<Eigen::UnitLower>().solve(d.qd);
    Vec6<double> f;
    for (int i = 0; i < kDof; ++i)  // the limits' friction (2): viscous and breakaway, no decay
      f(i) = lim.friction.vis(i) * e(i) + lim.friction.cou(i) * (e(i) > 0 ? 1.0 : (e(i) < 0 ? -1.0 : 0.0));
    const Vec6<double> tau_f = C.transpose().triangularView<Eigen::UnitUpper>().solve(f);
    for (int i = 0; i < kDof; ++i) want(i) = std::max(want(i), std::abs(tau(i)) + std::abs(tau_f(i)));
  }
  for (int i = 0; i < kDof; ++i) EXPECT_NEAR(r.torque(i), want(i), 1e-9 * want(i)) << "J" << i + 1;
  EXPECT_GT((r.torque - p.check.torque).cwiseAbs().maxCoeff(), 1e-3);  // the wrist's
}

// ---------------------------------------------------------------- refusals

TEST(Excitation, AStartWithinTheMarginOfALimitIsOutOfWorkspace) {
  const double m = params::kExcitationPositionMargin;
  for (int i = 0; i < kDof; ++i)
    for (const double q :
         {robot::kArm.q_min[i] + 0.5 * m, robot::kArm.q_max[i] - 0.5 * m, robot::kArm.q_max[i] + m, std::nan("")}) {
      Vec6<double> q0 = start_pose();
      q0(i) = q;
      const Prepared<double> p = prepare<double>(q0);
      EXPECT_EQ(p.check.status, ExcitationStatus::kOutOfWorkspace) << "J" << i + 1 << " at " << q;
      EXPECT_EQ(p.check.joint, i);
      EXPECT_EQ(p.check.tick, -1);  // the plan's refusal: no tick checked
    }
}

TEST(Excitation, AJointWithTooLittleTravelToSwingIsOutOfWorkspace) {
  // Each joint's swing at its speed bound, from the design's peaks; a start that leaves it a fraction of
  // that below: the plan cuts the gain to that fraction, and refuses below kExcitationMinScale.
  const excitation::Peaks<double> pk = excitation::design_peaks<double>();
  const ExcitationLimits<double> lim = ExcitationLimits<double>::defaults();
  for (int i = 0; i < kDof; ++i) {
    const double gain = params::kExcitationPlanFill * lim.speed(i) / pk.speed(i);
    for (const double fraction : {0.45, 0.55, 0.9}) {
      Vec6<double> q0 = start_pose();
      q0(i) = lim.q_min(i) + fraction * gain * pk.down(i) / params::kExcitationPlanFill;
      ExcitationMotion<double> m;
      const ExcitationStatus s = m.plan(q0, lim);
      if (fraction < params::kExcitationMinScale) {
        EXPECT_EQ(s, ExcitationStatus::kOutOfWorkspace) << "J" << i + 1 << " " << fraction;
        EXPECT_EQ(m.refused_joint(), i);
      } else {
        ASSERT_EQ(s, ExcitationStatus::kOk) << "J" << i + 1 << " " << fraction;
        EXPECT_NEAR(m.fit_gain()(i) / m.speed_gain()(i), fraction, 1e-9);
        double lowest = 1e9;  // the swing then reaches the margin and no further
        for (std::uint32_t n = 0; n < P; ++n) lowest = std::min(lowest, m.at_tick(n).q(i));
        EXPECT_GE(lowest, lim.q_min(i)) << i;
        EXPECT_LT(lowest - lim.q_min(i), 0.02 * (q0(i) - lim.q_min(i))) << i;  // the fill's 1 %, sampled
      }
    }
  }
}

TEST(Excitation, AShrunkenTorqueLimitIsOverLimit) {
  // J2 holds the arm's weight: a limit far below its peak torque fits at no amplitude.
  const Prepared<double> full = prepare<double>(start_pose());
  ASSERT_EQ(full.check.status, ExcitationStatus::kOk);
  ExcitationLimits<double> lim = ExcitationLimits<double>::defaults();
  lim.torque(1) = 0.3 * full.check.torque(1);
  const Prepared<double> p = prepare<double>(start_pose(), lim);
  EXPECT_EQ(p.check.status, ExcitationStatus::kOverLimit);
  EXPECT_EQ(p.check.joint, 1);
  EXPECT_GE(p.check.tick, 0);
  // Refused after the last cut: 0.9^6 = 0.531 >= kExcitationMinScale > 0.9^7 = 0.478.
  EXPECT_EQ(excitation::kAttempts, 7);
  EXPECT_NEAR(p.check.scale, std::pow(params::kExcitationScaleStep, excitation::kAttempts - 1), 1e-15);
}

TEST(Excitation, ALimitTheDesignJustMissesIsMetAtACutAmplitude) {
  // J1's torque limit just above what the motion needs at two cuts below the scale the start pose is
  // accepted at (the PUMA's 1: 0.81): refused at the two scales above it, run at it.
  const Prepared<double> base = prepare<double>(start_pose());
  ASSERT_EQ(base.check.status, ExcitationStatus::kOk);
  const double target = base.check.scale * params::kExcitationScaleStep * params::kExcitationScaleStep;
  ASSERT_GE(target, params::kExcitationMinScale);
  ExcitationMotion<double> m = base.motion;
  m.set_scale(target);
  const ExcitationLimits<double> lim0 = ExcitationLimits<double>::defaults();
  const ExcitationCheck<double> at_target =
      check_excitation(model<double>(), workspace<double>(), m, orientation_at(start_pose()), lim0);
  ASSERT_EQ(at_target.status, ExcitationStatus::kOk);
  ExcitationLimits<double> lim = lim0;
  lim.torque(0) = at_target.torque(0) * (1 + 1e-9);
  const Prepared<double> p = prepare<double>(start_pose(), lim);
  ASSERT_EQ(p.check.status, ExcitationStatus::kOk);
  EXPECT_NEAR(p.check.scale, target, 1e-12);
  EXPECT_LE(p.check.torque(0), lim.torque(0));
  EXPECT_NEAR(p.check.speed(0), target / base.check.scale * base.check.speed(0), 1e-6);
}

TEST(Excitation, ASwingThroughTheWristSingularityIsNearSingular) {
  OSC_PUMA_ONLY();  // its spherical wrist: singular at q5 = 0
  Vec6<double> q0 = start_pose();
  q0(4) = 0.3;  // J5's swing (0.65 rad at full scale, 0.33 at the last cut) crosses q5 = 0
  const Prepared<double> p = prepare<double>(q0);
  EXPECT_EQ(p.check.status, ExcitationStatus::kNearSingular);
  EXPECT_EQ(p.check.joint, -1);
  EXPECT_GT(p.check.tick, 0);
  EXPECT_NEAR(p.check.scale, std::pow(params::kExcitationScaleStep, excitation::kAttempts - 1), 1e-15);
  // Further from it, a cut amplitude clears it.
  q0(4) = 0.6;
  const Prepared<double> cut = prepare<double>(q0);
  std::printf("q5 = 0.6: %s at scale %.3f, rcond %.4f\n",
              cut.check.status == ExcitationStatus::kOk ? "accepted" : "refused", cut.check.scale, cut.check.rcond);
  EXPECT_EQ(cut.check.status, ExcitationStatus::kOk);
  EXPECT_LT(cut.check.scale, 1.0);
  EXPECT_GE(cut.check.rcond, params::kPathMinRcond);
}

TEST(Excitation, TheCheckNamesTheJointAndTheTickOfASampleOverItsBounds) {
  ExcitationMotion<double> m;
  const ExcitationLimits<double> lim0 = ExcitationLimits<double>::defaults();
  ASSERT_EQ(m.plan(start_pose(), lim0), ExcitationStatus::kOk);
  const Mat3<double> R_ref = orientation_at(start_pose());
  // A speed bound below the plan's: the first tick faster than it.
  ExcitationLimits<double> lim = lim0;
  lim.speed(3) = 1.0;
  ExcitationCheck<double> r = check_excitation(model<double>(), workspace<double>(), m, R_ref, lim);
  EXPECT_EQ(r.status, ExcitationStatus::kOverLimit);
  EXPECT_EQ(r.joint, 3);
  ASSERT_GT(r.tick, 0);
  EXPECT_GT(std::abs(m.at_tick(r.tick).qd(3)), 1.0);
  EXPECT_LE(std::abs(m.at_tick(r.tick - 1).qd(3)), 1.0);
  // A joint limit narrower than the plan's: out of workspace at the first tick beyond it.
  lim = lim0;
  lim.q_max(5) = start_pose()(5) + 0.1;
  r = check_excitation(model<double>(), workspace<double>(), m, R_ref, lim);
  EXPECT_EQ(r.status, ExcitationStatus::kOutOfWorkspace);
  EXPECT_EQ(r.joint, 5);
  ASSERT_GT(r.tick, 0);
  EXPECT_GT(m.at_tick(r.tick).q(5), lim.q_max(5));
  EXPECT_LE(m.at_tick(r.tick - 1).q(5), lim.q_max(5));
}

// ---------------------------------------------------------------- the excitation

TEST(Excitation, TheDesignExcitesEveryJointAndNoTwoAlike) {
  const ExcitationLimits<double> lim = ExcitationLimits<double>::defaults();
  const Prepared<double> p = prepare<double>(start_pose());
  ASSERT_EQ(p.check.status, ExcitationStatus::kOk);
  // The six velocities over a period, and the share of it each joint spends above three quarters of its
  // peak speed (on the PUMA, whose start pose takes the design at full scale, about 1 rad/s, where the
  // Stribeck term has decayed by 63 %: 0.07 to 0.21 of the period).
  Eigen::Matrix<double, kDof, kDof> gram = Eigen::Matrix<double, kDof, kDof>::Zero();
  Vec6<double> fast = Vec6<double>::Zero();
  for (std::uint32_t n = 0; n < P; ++n) {
    const Vec6<double> qd = p.motion.at_tick(n).qd;
    gram += qd * qd.transpose();
    for (int i = 0; i < kDof; ++i) fast(i) += std::abs(qd(i)) > 0.75 * p.check.speed(i) ? 1.0 / P : 0.0;
  }
  const Vec6<double> norm = gram.diagonal().cwiseSqrt();
  const Eigen::Matrix<double, kDof, kDof> corr = gram.cwiseQuotient(norm * norm.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, kDof, kDof>> eig(corr);
  double worst = 0, cross = 0;
  for (int i = 0; i < kDof; ++i)
    for (int j = 0; j < i; ++j) {
      worst = std::max(worst, std::abs(corr(i, j)));
      if ((i + j) % 2 == 1) cross = std::max(cross, std::abs(corr(i, j)));  // a cosine joint and a sine joint
    }
  std::printf("velocities' correlation: largest %.3f (cosine with sine %.1e); eigenvalues %.3f .. %.3f\n", worst, cross,
              eig.eigenvalues().minCoeff(), eig.eigenvalues().maxCoeff());
  std::printf("share of the period above 3/4 of the peak speed: %.2f %.2f %.2f %.2f %.2f %.2f\n", fast(0), fast(1),
              fast(2), fast(3), fast(4), fast(5));
  EXPECT_LT(cross, 1e-9);
  EXPECT_LT(worst, 0.65);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.3);
  for (int i = 0; i < kDof; ++i) {
    // Each joint at its speed bound (less the fill) times its travel's cut and the scale it was accepted at,
    // and that within the bounded cut.
    const double cut = p.check.scale * p.motion.fit_gain()(i) / p.motion.speed_gain()(i);
    EXPECT_NEAR(p.check.speed(i), cut * params::kExcitationPlanFill * lim.speed(i), 1e-4) << "J" << i + 1;
    EXPECT_GE(p.check.speed(i), params::kExcitationMinScale * params::kExcitationMaxSpeed * 0.85) << "J" << i + 1;
    EXPECT_GT(fast(i), 0.05) << "J" << i + 1;
    int harmonics = 0;  // power on 3 to 5 harmonics each
    for (int k = 0; k < params::kExcitationHarmonics; ++k)
      harmonics += params::kExcitationCos[i][k] != 0 || params::kExcitationSin[i][k] != 0;
    EXPECT_GE(harmonics, 3) << i;
  }
}

// ---------------------------------------------------------------- float and fixed point

/// Tolerances: q [rad], qd [rad/s], qdd [rad/s^2] at every tick of a period, the peak torques [N m] and the
/// smallest rcond: about three to ten times what was measured (float 9.4e-7, 2.2e-6, 5.8e-6, 6.4e-6, 1.4e-8;
/// Q12.19 1.9e-5, 4.4e-5, 1.1e-4, 1.4e-4, 3.2e-6: ten of its resolutions in q, the phase's rounding).
template <class S>
void compare_scalar(const double (&tol)[5], const char* name) {
  const Prepared<double> d = prepare<double>(start_pose());
  const Prepared<S> s = prepare<S>(start_pose());
  ASSERT_EQ(s.check.status, d.check.status);
  EXPECT_NEAR(static_cast<double>(s.check.scale), d.check.scale, 1e-5);
  double worst[3] = {0, 0, 0};
  for (std::uint64_t n = 0; n <= P; ++n) {
    const JointSample<double> a = d.motion.at_tick(n);
    const JointSample<S> b = s.motion.at_tick(n);
    worst[0] = std::max(worst[0], (b.q.template cast<double>() - a.q).cwiseAbs().maxCoeff());
    worst[1] = std::max(worst[1], (b.qd.template cast<double>() - a.qd).cwiseAbs().maxCoeff());
    worst[2] = std::max(worst[2], (b.qdd.template cast<double>() - a.qdd).cwiseAbs().maxCoeff());
  }
  const double torque = (s.check.torque.template cast<double>() - d.check.torque).cwiseAbs().maxCoeff();
  std::printf("%s against double: q %.1e rad, qd %.1e rad/s, qdd %.1e rad/s^2, peak torques %.1e N m, rcond %.1e\n",
              name, worst[0], worst[1], worst[2], torque, std::abs(static_cast<double>(s.check.rcond) - d.check.rcond));
  EXPECT_LT(worst[0], tol[0]);
  EXPECT_LT(worst[1], tol[1]);
  EXPECT_LT(worst[2], tol[2]);
  EXPECT_LT(torque, tol[3]);
  EXPECT_LT(std::abs(static_cast<double>(s.check.rcond) - d.check.rcond), tol[4]);
  EXPECT_LT((s.check.speed.template cast<double>() - d.check.speed).cwiseAbs().maxCoeff(), tol[1]);
}

TEST(Excitation, FloatFollowsDouble) { compare_scalar<float>({1e-5, 1e-5, 3e-5, 5e-5, 1e-6}, "float"); }
TEST(Excitation, FixedPointFollowsDouble) { compare_scalar<Fixed>({1e-4, 2e-4, 5e-4, 1e-3, 3e-5}, "Q12.19"); }

TEST(Excitation, FixedPointKeepsTheCallersFlags) {
  // J1's torque limit at 0: refused at every cut (its check stops at the first tick that moves J1).
  ExcitationLimits<Fixed> lim = ExcitationLimits<Fixed>::defaults();
  lim.torque(0) = Fixed(0);
  for (const std::uint32_t caller : {0u, std::uint32_t{fixed::kOverflow}}) {
    fixed::take_flags();
    if (caller != 0) {
      volatile double big = 4000;
      EXPECT_EQ(Fixed(big) + Fixed(big), Fixed::max());  // saturates: the caller's own flag
    }
    const Prepared<Fixed> p = prepare<Fixed>(start_pose(), lim);
    EXPECT_EQ(p.check.status, ExcitationStatus::kOverLimit);
    EXPECT_EQ(fixed::take_flags(), caller);
  }
}

}  // namespace
