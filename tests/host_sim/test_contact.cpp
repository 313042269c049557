// Contacts at the tip of the simulated arm (Plant::set_contact, the collision and wall injections)
// and the drive faults of its amplifiers (dac-zero, dac-full, amp-off: plant_hal.hpp): tau_ext =
// J_v^T F against KDL's inverse dynamics with an external wrench; the force's effect on the tip's
// acceleration against Lambda^-1 F from the kernels' joint-space inertia (not the plant's
// articulated body); a wall at rest penetrated by |F| / k; a contact that does not push leaves the
// closed loop bit for bit; each drive fault on its own channel from its time on; the parser.
#include <gtest/gtest.h>

#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "experiment.hpp"
#include "kdl_puma.hpp"
#include "motion_sim.hpp"
#include "osc/kernels/dynamics.hpp"
#include "osc/runtime/io.hpp"
#include "plant_hal.hpp"
#include "plant_preset.hpp"
#include "test_util.hpp"

using namespace sim;

namespace {

using Mat36 = Eigen::Matrix<double, 3, 6>;
constexpr double kDt = osc::params::kDt;

Vec6 q_start() { return osc::joint_vector<double>(osc::robot::kQStart); }

/// The kernels' kinematics and inertia (armature included, as the ideal plant's), independent of the
/// plant's articulated body.
struct Kernels {
  osc::Model<double> model = osc::Model<double>::of(osc::robot::kArm);
  osc::Data<double> data;
  explicit Kernels(const Vec6& q) {
    osc::forward_kinematics(model, data, q);
    osc::geometric_jacobian(data);
    osc::joint_inertia(model, data);
  }
  Vec3 tip() const { return data.o[osc::kDof]; }
  Mat36 jv() const { return data.J.topRows<3>(); }
  /// Lambda_v^-1 = J_v A^-1 J_v^T: the tip's acceleration per newton.
  Mat3 lambda_inv() const { return jv() * data.A.llt().solve(jv().transpose()); }
  /// g(q), the torques that hold the arm.
  Vec6 gravity() { return osc::rnea(model, data, Vec6::Zero(), Vec6::Zero(), true).tau; }
};

Vec3 tip(const Vec6& q) { return Kernels(q).tip(); }
Vec6 gravity(const Vec6& q) { return Kernels(q).gravity(); }

/// A force of `newtons` along the unit vector dir on the tip from `at` on (for `duration`, or for good).
Contact push(const Vec3& dir, double newtons, double at = 0, double duration = -1) {
  Contact c;
  c.kind = Contact::Kind::kForce;
  c.direction = dir;
  c.force = newtons;
  c.at = at;
  c.duration = duration;
  return c;
}

PlantConfig frictionless() {
  PlantConfig c;
  c.friction = osc::kFrictionNone;
  return c;
}

// ---------------------------------------------------------------------------------------------

TEST(Contact, ExternalTorqueIsJvTransposeFAgainstKdl) {
  // KDL's recursive Newton-Euler with a wrench on the last segment (at its origin, in its frame)
  // needs J^T F less torque than without: a force propagation of its own, no Jacobian.
  const KDL::Chain chain = osc::test::puma560_chain();
  KDL::ChainIdSolver_RNE id(chain, KDL::Vector(0, 0, -osc::robot::kArm.gravity));
  KDL::ChainFkSolverPos_recursive fk(chain);
  osc::test::RandomStates rs;
  double worst = 0, wrist = 0;
  for (int k = 0; k < 24; ++k) {
    const Vec6 q = k < 6 ? q_start() : Vec6(rs.q_nonsingular()), qd = rs.vec(1.0);
    // The six directions of the injection at the start pose, then random ones.
    Injection inj;
    inj.enabled = true;
    inj.kind = InjectionKind::kCollision;
    inj.direction = k % 6;
    inj.magnitude = 80;
    Contact c = Contact::of(inj);
    if (k >= 6) c = push(Vec3(rs.vec(1.0).head<3>()).normalized(), 80);
    Plant plant;
    plant.reset(q);
    plant.set_contact(c);
    plant.advance_sample(Vec6::Zero(), Vec6::Zero(), kDt);  // now acting
    const Vec6 tau = plant.external_torque(q, qd);
    const Vec3 F = c.force * c.direction;
    EXPECT_EQ(plant.contact_force(q, qd), F);

    KDL::Frame f6;
    ASSERT_GE(fk.JntToCart(osc::test::to_kdl(q), f6), 0);
    KDL::Wrenches none(chain.getNrOfSegments(), KDL::Wrench::Zero()), pushed = none;  // the base segment too
    pushed.back() = KDL::Wrench(f6.M.Inverse(KDL::Vector(F.x(), F.y(), F.z())), KDL::Vector::Zero());
    KDL::JntArray t0(osc::kDof), t1(osc::kDof), zero(osc::kDof);
    ASSERT_GE(id.CartToJnt(osc::test::to_kdl(q), osc::test::to_kdl(qd), zero, none, t0), 0);
    ASSERT_GE(id.CartToJnt(osc::test::to_kdl(q), osc::test::to_kdl(qd), zero, pushed, t1), 0);
    const Vec6 expected = osc::test::from_kdl(t0) - osc::test::from_kdl(t1);
    worst = std::max(worst, (tau - expected).norm() / expected.norm());
    wrist = std::max(wrist, tau.tail<3>().norm());  // the wrist's axes meet at the tip
  }
  std::printf("tau_ext vs KDL: worst relative error %.2e, largest wrist torque %.2e N m\n", worst, wrist);
  EXPECT_LT(worst, 1e-12);
  if constexpr (osc::has_spherical_wrist(osc::robot::kArm)) {
    EXPECT_LT(wrist, 1e-12);  // without one, the force at the tip turns the wrist too
  }
}

/// The tip's position after one sample from (q, qd) under the torque that holds the arm against
/// gravity, with contact c (or none).
Vec3 tip_after_a_sample(const PlantConfig& cfg, const Vec6& q, const Vec6& qd, const Contact* c) {
  Plant plant(cfg);
  plant.reset(q, qd);
  if (c) plant.set_contact(*c);
  const Vec6 g = gravity(q);
  plant.advance_sample(g, g, kDt);
  return tip(plant.q());
}

TEST(Contact, TipAccelerationChangeIsLambdaInverseF) {
  // Two runs over one sample from the same state, with and without the force: the tip's positions
  // differ by (1/2) dt^2 Lambda_v^-1 F, to first order in dt. The rigid plant and the drive-train
  // path (a negligible amplifier offset takes the plant there: the same rigid, uncoupled arm).
  PlantConfig drives = frictionless();
  drives.amp_offset[0] = 1e-12;
  osc::test::RandomStates rs;
  for (const PlantConfig& cfg : {frictionless(), drives}) {
    double worst = 0;
    for (int k = 0; k < 8; ++k) {
      const Vec6 q = k == 0 ? q_start() : Vec6(rs.q_nonsingular()), qd = rs.vec(0.5);
      const Contact c = push(Vec3(rs.vec(1.0).head<3>()).normalized(), 100);
      const Vec3 dp = tip_after_a_sample(cfg, q, qd, &c) - tip_after_a_sample(cfg, q, qd, nullptr);
      const Vec3 expected = 0.5 * kDt * kDt * Kernels(q).lambda_inv() * (c.force * c.direction);
      worst = std::max(worst, (dp - expected).norm() / expected.norm());
    }
    std::printf("%s plant: tip displacement by the force vs (1/2) dt^2 Lambda^-1 F: worst relative error %.2e\n",
                cfg.ideal_drives() ? "rigid" : "drive-train", worst);
    EXPECT_LT(worst, 1e-2);
  }
}

TEST(Contact, APulseInsideSamplesGivesItsImpulse) {
  // A pulse from 0.4 ms to 1.7 ms (neither a sample's bound nor the computation delay's): the tip's
  // velocity changes by Lambda_v^-1 F T (the arm barely moves meanwhile), and from its end on the
  // force is gone. The peak is sampled at the samples' ends: 1 ms only.
  const Vec6 q = q_start(), g = gravity(q);
  const Contact c = push(Vec3(0.6, 0, -0.8), 120, 0.4e-3, 1.3e-3);
  Plant a(frictionless()), b(frictionless());
  a.reset(q);
  b.reset(q);
  b.set_contact(c);
  for (int k = 0; k < 3; ++k) {
    a.advance_sample(g, g, kDt);
    b.advance_sample(g, g, kDt);
  }
  const Kernels ka(a.q()), kb(b.q());
  const Vec3 dv = kb.jv() * b.qd() - ka.jv() * a.qd();
  const Vec3 expected = Kernels(q).lambda_inv() * (c.force * c.direction) * c.duration;
  std::printf("pulse: tip velocity change %.5f m/s, Lambda^-1 F T %.5f m/s\n", dv.norm(), expected.norm());
  EXPECT_LT((dv - expected).norm(), 1e-2 * expected.norm());
  EXPECT_EQ(b.external_torque(b.q(), b.qd()), Vec6::Zero());
  EXPECT_EQ(b.peak_contact_force(), 120);
}

TEST(Contact, WallAtRestIsPenetratedByForceOverStiffness) {
  // The arm held against gravity, damped, and pushed down with 200 N at the tip (J_v^T F in its
  // torque) onto a wall 2 mm below the tip: at rest the wall's force balances the push, and the
  // tip is in the wall by |F| / k. Both measured here: the penetration from the kernels' kinematics
  // against the wall's plane, the force from the statics (J_v^T F_wall = g - tau).
  Plant plant(frictionless());
  const Vec6 q0 = q_start();
  plant.reset(q0);
  Contact wall;
  wall.kind = Contact::Kind::kWall;
  wall.direction = -Vec3::UnitZ();
  wall.distance = 2e-3;
  plant.set_contact(wall);
  const Vec3 down = wall.direction * 200;
  Vec6 kd;
  kd << 40, 40, 20, 2, 2, 2;  // [N m s/rad]
  Vec6 before = Vec6::Zero(), tau = Vec6::Zero();
  for (int k = 0; k < 3000; ++k) {
    Kernels kin(plant.q());
    tau = kin.gravity() - kd.cwiseProduct(plant.qd()) + kin.jv().transpose() * down;
    plant.advance_sample(before, tau, kDt);
    before = tau;
  }
  ASSERT_LT(plant.qd().norm(), 1e-6);
  const Vec6 q = plant.q();
  Kernels kin(q);
  const double d = wall.direction.dot(kin.tip() - tip(q0)) - wall.distance;
  const Vec3 F = plant.contact_force(q, plant.qd());
  const Vec3 statics = kin.jv().leftCols<3>().transpose().lu().solve(Vec6(kin.gravity() - tau).head<3>());
  std::printf("wall at rest: penetration %.6f mm, |F| / k %.6f mm, |F| %.3f N, statics %.3f N, peak %.1f N\n", d * 1e3,
              F.norm() / wall.stiffness * 1e3, F.norm(), statics.norm(), plant.peak_contact_force());
  EXPECT_NEAR(F.norm() / wall.stiffness, d, 1e-3 * d);
  EXPECT_LT((F - statics).norm(), 1e-3 * F.norm());
  EXPECT_LT((F + down).norm(), 1e-3 * F.norm());  // the push alone holds it there
  EXPECT_GE(plant.peak_contact_force(), F.norm());
}

/// The closed loop's samples (every one logged) for an injection.
ExperimentResult closed_loop(const Injection& inj, const std::string& preset) {
  ExperimentConfig c;
  EXPECT_TRUE(apply_plant_preset(preset, c));
  c.duration = 1.5;
  c.final_window = 0.5;
  c.log_period = kDt;
  c.injection = inj;
  return run_experiment(c);
}

TEST(Contact, AContactThatDoesNotPushLeavesTheRunBitForBit) {
  // A zero force from 0.5 s for 0.3 s (the parser refuses it: built here) and a wall 1 m above the
  // tip: the plant's kinematics run at every stage, the intervals are cut at the switches, yet every
  // sample's tracking error and torque are today's, on the rigid and on the realistic plant.
  Injection zero;
  zero.enabled = true;
  zero.kind = InjectionKind::kCollision;
  zero.direction = 4;
  zero.at = 0.5;
  zero.duration = 0.3;
  Injection far = zero;
  far.kind = InjectionKind::kWall;
  far.magnitude = 1000;
  for (const char* preset : {"ideal", "realistic"}) {
    const ExperimentResult none = closed_loop(Injection{}, preset);
    for (const Injection& inj : {zero, far}) {
      const ExperimentResult r = closed_loop(inj, preset);
      ASSERT_EQ(r.log.size(), none.log.size());
      for (std::size_t k = 0; k < r.log.size(); ++k) {
        ASSERT_EQ(std::memcmp(r.log[k].e, none.log[k].e, sizeof r.log[k].e), 0) << preset << " sample " << k;
        ASSERT_EQ(std::memcmp(r.log[k].tau, none.log[k].tau, sizeof r.log[k].tau), 0) << preset << " sample " << k;
      }
      EXPECT_EQ(r.injection.peak_contact_force, 0) << preset;
      EXPECT_EQ(r.injection.first_contact, -1) << preset << ": it never pushed";
    }
  }
}

TEST(Contact, TheExperimentAndTheCommandedArmReportTheirContact) {
  // puma_experiment's loop: a 50 N step at 1 s, its peak in the injection's record.
  Injection step;
  std::string err;
  ASSERT_TRUE(parse_injection("collision:+z:50@1", step, err)) << err;
  const ExperimentResult r = closed_loop(step, "ideal");
  EXPECT_EQ(r.injection.peak_contact_force, 50);
  EXPECT_NEAR(r.injection.first_contact, 1.001, 1e-9) << "the end of the sample it began in";
  // MotionSim (the scripts' in-process arm): a wall 5 mm below the tip stops a move 10 mm down.
  Injection wall;
  ASSERT_TRUE(parse_injection("wall:-z:5@0", wall, err)) << err;
  MotionSim<double> sim(q_start(), wall);
  const double z0 = sim.tip().z();
  sim.command(osc::MotionVerb::kEnable, 1);
  for (int k = 0; k < 100; ++k) sim.tick();
  osc::MoveRequest<double> down;
  down.relative = true;
  down.position = osc::Vec3<double>(0, 0, -0.010);
  sim.move_to(down, 2);
  double lowest = z0, reached = -1;  // when the tip first went 5 mm down [s]
  EXPECT_EQ(sim.plant().first_contact_time(), -1);
  for (int k = 0; k < 2000; ++k) {
    sim.tick();
    lowest = std::min(lowest, sim.tip().z());
    if (reached < 0 && z0 - lowest >= 5e-3) reached = sim.plant().time();
  }
  std::printf("a move 10 mm down onto a wall 5 mm below: the tip went %.3f mm down, peak force %.1f N\n",
              (z0 - lowest) * 1e3, sim.plant().peak_contact_force());
  EXPECT_GT(sim.plant().peak_contact_force(), 0);
  EXPECT_NEAR(sim.plant().first_contact_time(), reached, 1.5e-3) << "its first push is the tip reaching it";
  EXPECT_LT(z0 - lowest, 5e-3 + sim.plant().peak_contact_force() / Contact::kWallStiffness + 1e-4);
}

// ---------------------------------------------------------------------------------------------

TEST(DriveFaults, EachActsOnItsJointFromItsTime) {
  // Six samples, the same codes written in each, the fault at 2.5 ms: from the third sample on, on
  // its joint (every joint without one). The fault line still disables every amplifier.
  const std::int32_t codes[6] = {1000, -2000, 3000, -4000, 5000, -6000};
  for (const char* spec : {"dac-zero:3@0.0025", "dac-full:3@0.0025", "amp-off:3@0.0025", "dac-zero@0.0025",
                           "dac-full@0.0025", "amp-off@0.0025"}) {
    Injection inj;
    std::string err;
    ASSERT_TRUE(parse_injection(spec, inj, err)) << err;
    Plant plant;
    plant.reset(q_start());
    PlantHal hal(plant, q_start(), SensorConfig{}, inj);
    for (int k = 0; k < 6; ++k) {
      hal.begin_sample(k * kDt);
      hal.write_dacs(codes);
      const Vec6 t = hal.torque();
      for (int i = 0; i < 6; ++i) {
        const bool hit = k >= 3 && inj.hits(i);
        std::int32_t code = codes[i];
        if (hit && inj.kind == InjectionKind::kDacZero) code = 0;
        if (hit && inj.kind == InjectionKind::kDacFull) code = static_cast<std::int32_t>(osc::kDacMaxCode);
        EXPECT_EQ(hal.code(i), code) << spec << " sample " << k << " channel " << i;
        EXPECT_EQ(t(i), hit && inj.kind == InjectionKind::kAmpOff ? 0.0 : osc::code_to_torque(i, code))
            << spec << " sample " << k << " channel " << i;
        if (hit && inj.kind == InjectionKind::kDacFull) {
          EXPECT_EQ(t(i), osc::robot::kDrives.torque_limit[i]);
        }
      }
      hal.fault_output(true);
      EXPECT_EQ(hal.torque(), Vec6::Zero()) << spec;
      hal.fault_output(false);
    }
  }
}

/// The realistic plant with current monitors at their stated bounds' halves (gain 1 %, offset 0.1 %, noise
/// 2 codes), the paper's motion, the drive check armed.
ExperimentConfig realistic_with_current_monitors(double duration) {
  ExperimentConfig c;
  EXPECT_TRUE(apply_plant_preset("realistic", c));
  c.sensors.current_monitor = true;
  c.sensors.current_noise = 2;
  for (int i = 0; i < 6; ++i) {
    c.sensors.current_gain[i] = i % 2 ? -0.01 : 0.01;
    c.sensors.current_offset[i] = i % 2 ? -0.001 : 0.001;
  }
  c.duration = duration;
  c.final_window = 1;
  return c;
}

TEST(DriveCheckClosedLoop, TheRealisticPlantsDrivesStayWithinHalfTheirThresholds) {
  // Its coupling, lag, delay and light wrist joints, which answer the dither with steps of their own: no fault,
  // each channel's error and dither fade below half of what faults (measured 0.39 and 0.17 over 120 s).
  const ExperimentResult r = run_experiment(realistic_with_current_monitors(30));
  EXPECT_EQ(r.status, 0u) << osc::fault_name(r.status);
  for (int c = 0; c < 6; ++c) {
    EXPECT_LT(r.drive_peak_ratio[c], 0.5) << c;
    EXPECT_GT(r.drive_peak_ratio[c], 0.05) << c << ": the readings are checked";
    EXPECT_LT(r.dither_peak_fade[c], 0.5 * 0.5) << c;
  }
}

TEST(DriveCheckClosedLoop, AFrozenDacAndADeadCurrentMonitorAreFoundAndNamedADriveFault) {
  // A frozen DAC shows only through the dither until the command moves away; a monitor reading zero reads as a
  // drive giving none (docs/safety.md, "What a current reading cannot tell"): both category 0, drive_fault.
  for (const char* spec : {"dac-stuck:2@10", "dac-stuck:5@10", "current-zero:3@10", "amp-off:1@10"}) {
    ExperimentConfig c = realistic_with_current_monitors(11);
    std::string err;
    ASSERT_TRUE(parse_injection(spec, c.injection, err)) << err;
    const ExperimentResult r = run_experiment(c);
    EXPECT_EQ(r.status, osc::kFaultDriveFault) << spec << ": " << osc::fault_name(r.status);
    ASSERT_GE(r.drive_detected_s, 10.0) << spec;
    EXPECT_LE(r.drive_detected_s, 10.045) << spec;
    EXPECT_EQ(r.drive_channel, c.injection.joint) << spec;
  }
}

// ---------------------------------------------------------------------------------------------

TEST(InjectionParser, GoodFormsRoundTrip) {
  for (const char* good :
       {"collision:+z:50@1.5", "collision:-x:12.5:0.2@0", "collision:+y:0.001:0.00001@3", "wall:-z:5@1",
        "wall:+y:0@2.25", "wall:-x:5:20000@1", "dac-zero@3", "dac-zero:2@1.5", "dac-full:6@0", "amp-off:1@10",
        "dac-stuck:4@2", "encoder-stuck:3@12.5", "overrun@1", "estop@0.5"}) {
    Injection inj;
    std::string err;
    ASSERT_TRUE(parse_injection(good, inj, err)) << good << ": " << err;
    EXPECT_EQ(to_string(inj), good);
  }
  Injection w;
  std::string err;
  ASSERT_TRUE(parse_injection("wall:-y:2.5:30000@0.75", w, err)) << err;
  EXPECT_EQ(w.kind, InjectionKind::kWall);
  EXPECT_EQ(w.direction, 3);
  EXPECT_EQ(w.magnitude, 2.5);
  EXPECT_EQ(w.stiffness, 30000);
  EXPECT_EQ(w.duration, -1);
  EXPECT_EQ(w.at, 0.75);
  EXPECT_EQ(w.joint, -1);
  const Contact c = Contact::of(w);
  EXPECT_EQ(c.kind, Contact::Kind::kWall);
  EXPECT_EQ(c.direction, -Vec3::UnitY());
  EXPECT_EQ(c.distance, 2.5e-3);
  EXPECT_EQ(c.damping, 2 * 0.2 * std::sqrt(10 * 30000.0));
  // Every value reads back as itself.
  Injection odd;
  odd.enabled = true;
  odd.kind = InjectionKind::kCollision;
  odd.direction = 5;
  odd.magnitude = 0.1 + 0.2;
  odd.duration = 1.0 / 3;
  odd.at = 1e-7;
  Injection back;
  ASSERT_TRUE(parse_injection(to_string(odd), back, err)) << to_string(odd) << ": " << err;
  EXPECT_EQ(back.magnitude, odd.magnitude);
  EXPECT_EQ(back.duration, odd.duration);
  EXPECT_EQ(back.at, odd.at);
}

TEST(InjectionParser, BadFormsFailWithTheirMessage) {
  const std::pair<const char*, const char*> bad[] = {
      {"collision:+z:50", "expected KIND[:ARGS]@SECONDS"},
      {"push:+z:50@1", "unknown kind 'push'"},
      {"collision@1", "collision: needs :DIR:NEWTONS[:SECONDS] before @SECONDS"},
      {"collision:+z@1", "collision: needs :DIR:NEWTONS[:SECONDS] before @SECONDS"},
      {"collision:up:50@1", "collision: direction must be one of +x -x +y -y +z -z, got 'up'"},
      {"collision:z:50@1", "direction must be one of +x -x +y -y +z -z, got 'z'"},
      {"collision:+z:0@1", "collision: force must be a finite number of newtons > 0, got '0'"},
      {"collision:+z:-5@1", "force must be a finite number of newtons > 0, got '-5'"},
      {"collision:+z:inf@1", "force must be a finite number of newtons > 0, got 'inf'"},
      {"collision:+z:nan@1", "force must be a finite number of newtons > 0, got 'nan'"},
      {"collision:+z:50N@1", "force must be a finite number of newtons > 0, got '50N'"},
      {"collision:+z::1@1", "force must be a finite number of newtons > 0, got ''"},
      {"collision:+z:50:-0.1@1", "collision: duration must be a finite number of seconds > 0, got '-0.1'"},
      {"collision:+z:50:0@1", "duration must be a finite number of seconds > 0, got '0'"},
      {"collision:+z:50:@1", "duration must be a finite number of seconds > 0, got ''"},
      {"collision:+z:50:1:2@1", "collision: unexpected ':2' after :DIR:NEWTONS[:SECONDS]"},
      {"wall@1", "wall: needs :DIR:MM[:N_PER_M] before @SECONDS"},
      {"wall:-z@1", "wall: needs :DIR:MM[:N_PER_M] before @SECONDS"},
      {"wall:down:5@1", "wall: direction must be one of +x -x +y -y +z -z, got 'down'"},
      {"wall:-z:-1@1", "wall: distance must be a finite number of millimetres >= 0, got '-1'"},
      {"wall:-z:nan@1", "distance must be a finite number of millimetres >= 0, got 'nan'"},
      {"wall:-z:5:0@1", "wall: stiffness must be a finite number of N/m > 0, got '0'"},
      {"wall:-z:5:-1e5@1", "stiffness must be a finite number of N/m > 0, got '-1e5'"},
      {"wall:-z:5:1e400@1", "stiffness must be a finite number of N/m > 0, got '1e400'"},
      {"wall:-z:5:1e5:3@1", "wall: unexpected ':3' after :DIR:MM[:N_PER_M]"},
      {"wall:-z:5@", "time must be a finite number of seconds >= 0, got ''"},
      {"wall:-z:5@1s", "time must be a finite number of seconds >= 0, got '1s'"},
      {"wall:-z:5@-1", "time must be a finite number of seconds >= 0, got '-1'"},
      {"dac-zero:7@1", "joint must be 1 to 6, got '7'"},
      {"dac-full:x@1", "joint must be 1 to 6, got 'x'"},
      {"amp-off:1:2@1", "joint must be 1 to 6, got '1:2'"},
      {"estop:1@1", "estop takes no joint"},
  };
  for (const auto& [text, message] : bad) {
    Injection inj;
    std::string err;
    EXPECT_FALSE(parse_injection(text, inj, err)) << text;
    EXPECT_NE(err.find(message), std::string::npos) << text << ": " << err;
    EXPECT_EQ(err.rfind("--inject: ", 0), 0u) << text << ": " << err;
    EXPECT_FALSE(inj.enabled) << text;
  }
}

}  // namespace
