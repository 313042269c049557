// The generated arm tables (firmware/robots/include/osc/robots/<arm>.hpp, tools/armgen) against
// their descriptions, computed here another way: each arm's URDF walked link by link (its joint
// origins and axis-angle rotations composed directly, no placements), its inertials summed per moving
// link; the table's kinematics, gravity and joint inertia (the firmware's kernels) must agree at
// random poses. The UR5e also against UR's own DH table and its printed centres of mass (frames UR
// states, not the URDF's), and its start pose against the singularities. The third arm, twisted
// (tests/tools/armgen_cases/twisted.urdf, its table generated at build time), exercises what the
// PUMA and the UR5e do not: axes other than +z, general rotations, a continuous joint, masses on
// fixed links lumped into their moving link, an operational point on a fixed frame with an offset.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <urdf_parser/urdf_parser.h>

#include "osc/kernels/dynamics.hpp"
#include "osc/kernels/kinematics.hpp"
#include "osc/robots/puma560.hpp"
#include "osc/robots/twisted.hpp"
#include "osc/robots/ur5e.hpp"

using namespace osc;
using Iso = Eigen::Isometry3d;

namespace {

Iso pose(const urdf::Pose& p) {
  Iso T = Iso::Identity();
  T.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return T;
}

/// A moving link's mass properties in the world frame: mass, COM, inertia about the COM.
struct Body {
  double m = 0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
};

/// The URDF at joint angles q: every link's world frame, each moving joint's world axis and origin,
/// and the six moving links' mass properties (the fixed links' inertials added to the moving link
/// they hang from; the links before joint 1 do not move and are left out).
struct UrdfState {
  std::map<std::string, Iso> frame;
  Eigen::Vector3d axis[kDof], origin[kDof];
  Body body[kDof];
};

class UrdfArm {
 public:
  explicit UrdfArm(const std::string& path) : model_(urdf::parseURDFFile(path)) {}
  bool ok() const { return model_ != nullptr; }

  UrdfState at(const Vec6<double>& q) const {
    UrdfState s;
    int next = 0;
    walk(*model_->getRoot(), Iso::Identity(), -1, q, next, s);
    for (Body& b : s.body) {
      if (b.m == 0) continue;
      b.c /= b.m;
      b.I -= b.m * (b.c.squaredNorm() * Eigen::Matrix3d::Identity() - b.c * b.c.transpose());  // about the COM
    }
    return s;
  }
  /// The joint limits (continuous: +-2 pi).
  void limits(double (&lo)[kDof], double (&hi)[kDof]) const {
    int k = 0;
    for (const std::string& name : moving_names()) {
      const urdf::JointConstSharedPtr j = model_->getJoint(name);
      const bool cont = j->type == urdf::Joint::CONTINUOUS;
      lo[k] = cont ? -2 * kPi : j->limits->lower, hi[k] = cont ? 2 * kPi : j->limits->upper, ++k;
    }
  }

 private:
  std::vector<std::string> moving_names() const {
    std::vector<std::string> names;
    const urdf::Link* link = model_->getRoot().get();
    while (link) {
      const urdf::Link* next = nullptr;
      for (const urdf::JointSharedPtr& j : link->child_joints) {
        const urdf::Link* child = model_->getLink(j->child_link_name).get();
        if (j->type != urdf::Joint::FIXED) names.push_back(j->name);
        if (j->type != urdf::Joint::FIXED || !child->child_joints.empty()) next = child;
      }
      link = next;
    }
    return names;
  }
  // Sums first moments m c and inertias about the world origin (I_c + m (|c|^2 1 - c c^T)); at()
  // turns them into the COM and the inertia about it.
  void walk(const urdf::Link& link, const Iso& T, int body, const Vec6<double>& q, int& next, UrdfState& s) const {
    s.frame[link.name] = T;
    if (body >= 0 && link.inertial) {
      const urdf::Inertial& in = *link.inertial;
      const Iso C = T * pose(in.origin);
      Eigen::Matrix3d Ic;
      Ic << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
      const Eigen::Vector3d c = C.translation();
      Body& b = s.body[body];
      b.m += in.mass;
      b.c += in.mass * c;
      b.I += C.linear() * Ic * C.linear().transpose() +
             in.mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
    }
    for (const urdf::JointSharedPtr& j : link.child_joints) {
      const urdf::Link& child = *model_->getLink(j->child_link_name);
      const Iso O = T * pose(j->parent_to_joint_origin_transform);
      if (j->type == urdf::Joint::FIXED) {
        walk(child, O, body, q, next, s);
        continue;
      }
      const int k = next++;
      const Eigen::Vector3d a = Eigen::Vector3d(j->axis.x, j->axis.y, j->axis.z).normalized();
      s.axis[k] = O.linear() * a;
      s.origin[k] = O.translation();
      walk(child, O * Eigen::AngleAxisd(q(k), a), k, q, next, s);
    }
  }
  urdf::ModelInterfaceSharedPtr model_;
};

double potential(const UrdfState& s, double g) {
  double v = 0;
  for (const Body& b : s.body) v += b.m * g * b.c.z();
  return v;
}

/// The table's kernels against the URDF walked directly, at random poses within the limits.
void check_against_urdf(const ArmDescription& arm, const std::string& urdf, const std::string& op_frame,
                        const Iso& op_offset) {
  const UrdfArm u(urdf);
  ASSERT_TRUE(u.ok()) << urdf;
  double lo[kDof], hi[kDof];
  u.limits(lo, hi);
  for (int i = 0; i < kDof; ++i) {
    EXPECT_NEAR(arm.q_min[i], lo[i], 1e-12) << "joint " << i + 1;
    EXPECT_NEAR(arm.q_max[i], hi[i], 1e-12) << "joint " << i + 1;
  }
  const Model<double> model = Model<double>::of(arm);
  Data<double> data;
  std::mt19937_64 rng(55);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int n = 0; n < 40; ++n) {
    Vec6<double> q;
    for (int i = 0; i < kDof; ++i) q(i) = arm.q_min[i] + (arm.q_max[i] - arm.q_min[i]) * unit(rng);
    forward_kinematics(model, data, q);
    joint_inertia(model, data);
    const Vec6<double> g = gravity_torques(model, data);
    const UrdfState s = u.at(q);

    const Iso op = s.frame.at(op_frame) * op_offset;
    EXPECT_LT((data.o[kDof] - op.translation()).norm(), 1e-12) << "operational point at pose " << n;
    EXPECT_LT((data.R[kDof] - op.linear()).norm(), 1e-12) << "operational frame at pose " << n;
    Mat6<double> A = Mat6<double>::Zero();
    for (int k = 0; k < kDof; ++k) {
      const Body& b = s.body[k];
      EXPECT_NEAR(model.link[k].mass, b.m, 1e-12) << "link " << k + 1;
      if (b.m > 0) {
        EXPECT_LT((data.com[k + 1] - b.c).norm(), 1e-12) << "link " << k + 1 << "'s COM at pose " << n;
      }
      EXPECT_LT((data.Ic[k + 1] - b.I).norm(), 1e-12 * std::max(1.0, b.I.norm())) << "link " << k + 1 << "'s inertia";
      // The link's contribution to A: m Jv^T Jv + Jw^T I Jw, its columns the joints up to it.
      Eigen::Matrix<double, 3, kDof> Jv = Eigen::Matrix<double, 3, kDof>::Zero(), Jw = Jv;
      for (int j = 0; j <= k; ++j) Jv.col(j) = s.axis[j].cross(b.c - s.origin[j]), Jw.col(j) = s.axis[j];
      A += b.m * Jv.transpose() * Jv + Jw.transpose() * b.I * Jw;
      A(k, k) += model.armature(k);
    }
    EXPECT_LT((data.A - A).norm(), 1e-10 * A.norm()) << "A(q) at pose " << n;
    // g(q) = dV/dq, V the links' potential energy, by central differences.
    Vec6<double> dV;
    for (int i = 0; i < kDof; ++i) {
      Vec6<double> qp = q, qm = q;
      qp(i) += 1e-6, qm(i) -= 1e-6;
      dV(i) = (potential(u.at(qp), arm.gravity) - potential(u.at(qm), arm.gravity)) / 2e-6;
    }
    EXPECT_LT((g - dV).norm(), 1e-6 * std::max(1.0, dV.norm())) << "g(q) at pose " << n;
  }
}

const std::string kRobots = OSC_SOURCE_DIR "/firmware/robots/";

TEST(ArmTables, Puma560AgreesWithItsUrdf) {
  check_against_urdf(puma560::kArm, kRobots + "puma560/puma560.urdf", "link6", Iso::Identity());
}

TEST(ArmTables, Ur5eAgreesWithItsUrdf) {
  check_against_urdf(ur5e::kArm, kRobots + "ur5e/ur5e.urdf", "tool0", Iso::Identity());
}

TEST(ArmTables, TwistedFixtureAgreesWithItsUrdf) {
  Iso offset = Iso::Identity();
  offset.translation() = Eigen::Vector3d(0, 0, 0.1);
  check_against_urdf(twisted::kArm, ARMGEN_CASES "/twisted.urdf", "flange", offset);
}

/// UR's standard DH table (UR's article; arms-and-tools.md section 1.1): the frames UR states.
Iso ur_dh(const Vec6<double>& q, int upto) {
  const double a[kDof] = {0, -0.425, -0.3922, 0, 0, 0}, d[kDof] = {0.1625, 0, 0, 0.1333, 0.0997, 0.0996};
  const double alpha[kDof] = {kPi / 2, 0, 0, kPi / 2, -kPi / 2, 0};
  Iso T = Iso::Identity();
  for (int i = 0; i < upto; ++i)
    T = T * Eigen::AngleAxisd(q(i), Eigen::Vector3d::UnitZ()) * Eigen::Translation3d(a[i], 0, d[i]) *
        Eigen::AngleAxisd(alpha[i], Eigen::Vector3d::UnitX());
  return T;
}

TEST(ArmTables, Ur5eMatchesUrsDhTableAndPrintedCentresOfMass) {
  // UR's base frame is the URDF's base_link turned by pi about z; tool0 is DH frame 6.
  const Model<double> model = Model<double>::of(ur5e::kArm);
  Data<double> data;
  const Iso base(Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitZ()));
  // UR's masses and centres of mass as it prints them, in its DH frames i.
  const double m[kDof] = {3.761, 8.058, 2.846, 1.37, 1.3, 0.365};
  const double c[kDof][3] = {{0, -0.02561, 0.00193}, {0.2125, 0, 0.11336}, {0.15, 0, 0.0265},
                             {0, -0.0018, 0.01634},  {0, 0.0018, 0.01634}, {0, 0, -0.001159}};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-kPi, kPi);
  for (int n = 0; n < 40; ++n) {
    Vec6<double> q;
    for (int i = 0; i < kDof; ++i) q(i) = u(rng);
    forward_kinematics(model, data, q);
    const Iso F6 = base * ur_dh(q, kDof);
    EXPECT_LT((data.o[kDof] - F6.translation()).norm(), 1e-12);
    EXPECT_LT((data.R[kDof] - F6.linear()).norm(), 1e-12);
    const auto V = [&](const Vec6<double>& x) {
      double v = 0;
      for (int i = 0; i < kDof; ++i)
        v += m[i] * ur5e::kArm.gravity * (ur_dh(x, i + 1) * Eigen::Vector3d(c[i][0], c[i][1], c[i][2])).z();
      return v;
    };
    Vec6<double> dV;
    for (int i = 0; i < kDof; ++i) {
      Vec6<double> qp = q, qm = q;
      qp(i) += 1e-6, qm(i) -= 1e-6;
      dV(i) = (V(qp) - V(qm)) / 2e-6;
    }
    EXPECT_LT((gravity_torques(model, data) - dV).norm(), 1e-6 * std::max(1.0, dV.norm())) << "pose " << n;
  }
}

TEST(ArmTables, Ur5eStartPoseIsClearOfItsSingularities) {
  // det J = a2 a3 sin q3 sin q5 (a2 cos q2 + a3 cos(q2 + q3) + d5 sin(q2 + q3 + q4)) (arms-and-tools.md 1.4).
  const double* q = ur5e::kQStart;
  const double a2 = -0.425, a3 = -0.3922, d5 = 0.0997;
  const double shoulder = a2 * std::cos(q[1]) + a3 * std::cos(q[1] + q[2]) + d5 * std::sin(q[1] + q[2] + q[3]);
  EXPECT_GT(std::abs(std::sin(q[2])), 0.5);
  EXPECT_GT(std::abs(std::sin(q[4])), 0.5);
  EXPECT_GT(std::abs(shoulder), 0.2);
  const Model<double> model = Model<double>::of(ur5e::kArm);
  Data<double> data;
  forward_kinematics(model, data, joint_vector<double>(ur5e::kQStart));
  geometric_jacobian(data);
  EXPECT_NEAR(std::abs(data.J.determinant()), std::abs(a2 * a3 * std::sin(q[2]) * std::sin(q[4]) * shoulder), 1e-12);
}

TEST(ArmTables, PlacementsAndWristsAreAsTheKernelsExpect) {
  // Quarter-turn joint frames are exact signed permutations (the kernels' fast path); the PUMA has a
  // spherical wrist, the UR5e has not (its runtime is not built yet).
  for (const ArmDescription* arm : {&puma560::kArm, &ur5e::kArm})
    for (const LinkParams& l : arm->links) EXPECT_TRUE(is_signed_permutation(l.placement)) << arm->name;
  EXPECT_TRUE(is_signed_permutation(ur5e::kArm.base));
  EXPECT_TRUE(has_spherical_wrist(puma560::kArm));
  EXPECT_FALSE(has_spherical_wrist(ur5e::kArm));
  EXPECT_FALSE(is_signed_permutation(twisted::kArm.links[0].placement));
}

TEST(ArmTables, DriveFactsOfTheNewFields) {
  EXPECT_EQ(puma560::kDriveTrain.encoder_kind, EncoderKind::kIncremental);
  EXPECT_TRUE(puma560::kDriveTrain.index_pulses);
  EXPECT_EQ(puma560::kDriveTrain.pot_bits, 12);
  EXPECT_EQ(ur5e::kDriveTrain.encoder_kind, EncoderKind::kAbsolute);
  EXPECT_FALSE(ur5e::kDriveTrain.index_pulses);
  EXPECT_EQ(ur5e::kDriveTrain.pot_bits, 0);
  EXPECT_EQ(ur5e::kDriveTrain.encoders.coupling_terms, 0);
  EXPECT_NEAR(ur5e::kDriveTrain.encoders.counts_per_rad[0], 1048576 / (2 * kPi), 1e-9);
  // The sheet's expressions are the C++ the header carries: 150 / 101 in doubles, not integers.
  EXPECT_NEAR(ur5e::kDriveTrain.motor_torque_limit[0], 150.0 / 101, 1e-15);
  EXPECT_NEAR(ur5e::kDriveTrain.torque_constant[3], 28.0 / 101 / 4, 1e-15);
  EXPECT_EQ(puma560::kCartesianMaxima.velocity, 0.20);
  EXPECT_EQ(puma560::kCartesianMaxima.acceleration, 0.40);
  EXPECT_EQ(puma560::kCartesianMaxima.jerk, 2.5);
  EXPECT_EQ(ur5e::kCartesianMaxima.velocity, 0.10);
  EXPECT_EQ(ur5e::kCartesianMaxima.acceleration, 0.25);
  EXPECT_EQ(ur5e::kCartesianMaxima.jerk, 2.5);
  EXPECT_EQ(ur5e::named_pose_code("start"), 0);
  EXPECT_EQ(ur5e::named_pose_code("upright"), 2);
  EXPECT_EQ(ur5e::named_pose_code("nope"), -1);
  // The corke preset from its motor-side data, exactly as friction_from_motor's formula.
  const double G = abs_of(puma560::kArm.links[0].gear_ratio);
  EXPECT_EQ(puma560::kFrictionCorke.vis[0], puma560::kMotorViscous[0] * G * G);
  EXPECT_EQ(puma560::kFrictionCorke.cou[0], G * (puma560::kMotorCoulombPos[0] - puma560::kMotorCoulombNeg[0]) / 2);
}

}  // namespace
