// Google Benchmark: every kernel in double, float and Q12.19 fixed point (osc::Fixed), the full
// control step, the plant, and KDL computing the same quantities. Not a test: run
// build/host/tests/osc_bench.
#include <benchmark/benchmark.h>

#include <kdl/chaindynparam.hpp>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacdotsolver.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <memory>

#include "kdl_puma.hpp"
#include "osc/control/controller.hpp"
#include "osc/control/jerk_profile.hpp"
#include "osc/kernels/lu.hpp"
#include "plant.hpp"

using namespace osc;

namespace {

template <class S>
struct Fixture {
  Model<S> model = Model<S>::of(robot::kArm);
  Data<S> data{};
  ArmOpSpace<S> os{};
  Vec6<S> q, qd, v;
  Mat3<S> R_ref;
  Fixture() {
    q = joint_vector<S>(robot::kQStart);
    qd << S(0.1), S(-0.2), S(0.3), S(0.05), S(-0.1), S(0.2);
    v << S(0.05), S(-0.02), S(0.03), S(0.01), S(0.02), S(-0.01);
    forward_kinematics(model, data, q);
    R_ref = data.R[kDof];
    opspace_update(model, data, os, q, R_ref);
  }
};

template <class S>
void BM_forward_kinematics(benchmark::State& st) {
  Fixture<S> f;
  for (auto _ : st) {
    forward_kinematics(f.model, f.data, f.q);
    benchmark::DoNotOptimize(f.data.o[kDof]);
  }
}
template <class S>
void BM_geometric_jacobian(benchmark::State& st) {
  Fixture<S> f;
  for (auto _ : st) {
    geometric_jacobian(f.data);
    benchmark::DoNotOptimize(f.data.J);
  }
}
template <class S>
void BM_joint_inertia(benchmark::State& st) {
  Fixture<S> f;
  for (auto _ : st) {
    joint_inertia(f.model, f.data);
    benchmark::DoNotOptimize(f.data.A);
  }
}
template <class S>
void BM_gravity(benchmark::State& st) {
  Fixture<S> f;
  for (auto _ : st) benchmark::DoNotOptimize(gravity_torques(f.model, f.data));
}
template <class S>
void BM_velocity_products(benchmark::State& st) {
  Fixture<S> f;
  for (auto _ : st) benchmark::DoNotOptimize(velocity_products(f.model, f.data, f.qd));
}
template <class S>
void BM_friction_regressor(benchmark::State& st) {
  Fixture<S> f;
  const Vec6<S> dec = Vec6<S>::Ones();
  for (auto _ : st) benchmark::DoNotOptimize(friction_regressor(f.qd, dec));
}
/// A factor of J (F: the spherical wrist's block factor, or the pivoted LU of osc/kernels/lu.hpp for
/// arms without one) at the fixture's J: compute + solve, compute alone (with its rcond), a solve alone.
template <class S, template <class> class F>
void factor_solve(benchmark::State& st) {
  Fixture<S> f;
  F<S> jf;
  for (auto _ : st) {
    jf.compute(f.os.Ja);
    benchmark::DoNotOptimize(jf.solve(f.v));
  }
}
template <class S, template <class> class F>
void factor_compute(benchmark::State& st) {
  Fixture<S> f;
  F<S> jf;
  for (auto _ : st) {
    jf.compute(f.os.Ja);
    benchmark::DoNotOptimize(jf.rcond);
    benchmark::ClobberMemory();
  }
}
template <class S, template <class> class F>
void factor_solve_only(benchmark::State& st) {
  Fixture<S> f;
  F<S> jf;
  jf.compute(f.os.Ja);
  for (auto _ : st) benchmark::DoNotOptimize(jf.solve(f.v));
}
template <class S>
void BM_jacobian_factor_solve(benchmark::State& st) {
  factor_solve<S, SphericalWristJacobianFactor>(st);
}
template <class S>
void BM_jacobian_factor_compute(benchmark::State& st) {
  factor_compute<S, SphericalWristJacobianFactor>(st);
}
template <class S>
void BM_jacobian_factor_solve_only(benchmark::State& st) {
  factor_solve_only<S, SphericalWristJacobianFactor>(st);
}
template <class S>
void BM_lu_factor_solve(benchmark::State& st) {
  factor_solve<S, PivotedLuJacobianFactor>(st);
}
template <class S>
void BM_lu_factor_compute(benchmark::State& st) {
  factor_compute<S, PivotedLuJacobianFactor>(st);
}
template <class S>
void BM_lu_factor_solve_only(benchmark::State& st) {
  factor_solve_only<S, PivotedLuJacobianFactor>(st);
}
template <class S>
void BM_operational_inertia(benchmark::State& st) {
  Fixture<S> f;
  for (auto _ : st) benchmark::DoNotOptimize(operational_inertia(f.data.A, f.os.Jf));
}
template <class S>
void BM_opspace_update(benchmark::State& st) {
  Fixture<S> f;
  for (auto _ : st) {
    opspace_update(f.model, f.data, f.os, f.q, f.R_ref);
    benchmark::DoNotOptimize(f.os.A_ldlt);
  }
}
template <class S>
void BM_psi_quadratic(benchmark::State& st) {
  Fixture<S> f;
  for (auto _ : st) benchmark::DoNotOptimize(psi_quadratic(f.model, f.data, f.os, f.v));
}
template <class S>
void BM_control_step(benchmark::State& st) {
  Fixture<S> f;
  const Gains<S> g = Gains<S>::paper();
  auto cs = std::make_unique<ControllerState<S>>();
  controller_init(f.model, *cs, f.q);
  const PaperMotion<S> paper{g.trajectory, cs->data.o[kDof]};
  Vec6<S> q = f.q;
  int k = 0;
  for (auto _ : st) {
    q(1) = f.q(1) + static_cast<S>(1e-6 * (k % 100));
    // The paper's motion and the step: what the tick computes.
    benchmark::DoNotOptimize(
        control_step(f.model, g, FrictionMode::kAdaptive, *cs, q, paper.at_time(static_cast<S>(1e-3 * (k % 1000)))));
    ++k;
  }
}

/// The jerk-limited profile: plan() from a moving start (the general case: a bisection on the peak velocity) and at()
/// at every 1 ms of the move, as the tick calls it.
template <class S>
void BM_jerk_profile_plan(benchmark::State& st) {
  JerkProfile<S> pr;
  const JerkLimits<S> lim{S(1), S(5), S(50)};
  int k = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(pr.plan(S(0.2), S(0.8), S(2), S(0.38 + 1e-4 * (k++ % 100)), lim));
    benchmark::ClobberMemory();
  }
}
template <class S>
void BM_jerk_profile_at(benchmark::State& st) {
  JerkProfile<S> pr;
  pr.plan(S(0.2), S(0.8), S(2), S(0.9), JerkLimits<S>{S(1), S(5), S(50)});
  int k = 0;
  for (auto _ : st) {
    benchmark::DoNotOptimize(pr.at(math::ratio<S>(static_cast<std::uint64_t>(k), 1000)));
    k = k == 860 ? 0 : k + 1;
  }
}

#define OSC_BENCH(name)             \
  BENCHMARK_TEMPLATE(name, double); \
  BENCHMARK_TEMPLATE(name, float);  \
  BENCHMARK_TEMPLATE(name, Fixed)
OSC_BENCH(BM_forward_kinematics);
OSC_BENCH(BM_geometric_jacobian);
OSC_BENCH(BM_joint_inertia);
OSC_BENCH(BM_gravity);
OSC_BENCH(BM_velocity_products);
OSC_BENCH(BM_friction_regressor);
OSC_BENCH(BM_jacobian_factor_solve);
OSC_BENCH(BM_jacobian_factor_compute);
OSC_BENCH(BM_jacobian_factor_solve_only);
OSC_BENCH(BM_lu_factor_solve);
OSC_BENCH(BM_lu_factor_compute);
OSC_BENCH(BM_lu_factor_solve_only);
OSC_BENCH(BM_operational_inertia);
OSC_BENCH(BM_opspace_update);
OSC_BENCH(BM_psi_quadratic);
OSC_BENCH(BM_control_step);
BENCHMARK_TEMPLATE(BM_jerk_profile_plan, double);
BENCHMARK_TEMPLATE(BM_jerk_profile_plan, float);
BENCHMARK_TEMPLATE(BM_jerk_profile_at, double);
BENCHMARK_TEMPLATE(BM_jerk_profile_at, float);

void BM_plant_forward_dynamics(benchmark::State& st) {
  sim::ArticulatedBody body;
  Fixture<double> f;
  const sim::Vec6 tau = sim::Vec6::Constant(1.0);
  for (auto _ : st) benchmark::DoNotOptimize(body.forward_dynamics(f.q, f.qd, tau));
}
BENCHMARK(BM_plant_forward_dynamics);

// KDL computing the same quantities: its solvers built once on the same state, each call timed
// (BM_kdl/<quantity>).
struct KdlSolvers {
  KDL::Chain chain = test::puma560_chain();
  Fixture<double> f;
  KDL::JntArray q = test::to_kdl(f.q), qd = test::to_kdl(f.qd);
  KDL::ChainFkSolverPos_recursive fk{chain};
  KDL::ChainJntToJacSolver jacobian{chain};
  KDL::ChainDynParam dynamics{chain, KDL::Vector(0, 0, -9.81)};
  KDL::ChainJntToJacDotSolver jacdot{chain};
  KDL::ChainFdSolver_RNE forward_dynamics{chain, KDL::Vector(0, 0, -9.81)};
  KDL::Frame frame;
  KDL::Jacobian J{kDof};
  KDL::JntSpaceInertiaMatrix H{kDof};
  KDL::JntArray out{kDof}, tau{kDof}, qdd{kDof};
  KDL::Twist twist;
  KDL::Wrenches wrenches{chain.getNrOfSegments(), KDL::Wrench::Zero()};

  enum Quantity { kFk, kJacobian, kMass, kCoriolis, kGravity, kJacDot, kForwardDynamics };
  int compute(Quantity which) {
    switch (which) {
      case kFk:
        return fk.JntToCart(q, frame);
      case kJacobian:
        return jacobian.JntToJac(q, J);
      case kMass:
        return dynamics.JntToMass(q, H);
      case kCoriolis:
        return dynamics.JntToCoriolis(q, qd, out);
      case kGravity:
        return dynamics.JntToGravity(q, out);
      case kJacDot:
        return jacdot.JntToJacDot(KDL::JntArrayVel(q, qd), twist);
      case kForwardDynamics:
        return forward_dynamics.CartToJnt(q, qd, tau, wrenches, qdd);
    }
    return -1;
  }
};
void BM_kdl(benchmark::State& st, KdlSolvers::Quantity which) {
  auto k = std::make_unique<KdlSolvers>();
  for (auto _ : st) benchmark::DoNotOptimize(k->compute(which));
}
BENCHMARK_CAPTURE(BM_kdl, forward_kinematics, KdlSolvers::kFk);
BENCHMARK_CAPTURE(BM_kdl, jacobian, KdlSolvers::kJacobian);
BENCHMARK_CAPTURE(BM_kdl, mass, KdlSolvers::kMass);
BENCHMARK_CAPTURE(BM_kdl, coriolis, KdlSolvers::kCoriolis);
BENCHMARK_CAPTURE(BM_kdl, gravity, KdlSolvers::kGravity);
BENCHMARK_CAPTURE(BM_kdl, jacdot, KdlSolvers::kJacDot);
BENCHMARK_CAPTURE(BM_kdl, forward_dynamics, KdlSolvers::kForwardDynamics);

}  // namespace

BENCHMARK_MAIN();
