// osc_model_info: prints the built arm's model quantities at a named pose or given joint angles.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>
#include <vector>

#include "cli_parse.hpp"
#include "osc/control/arm_opspace.hpp"
#include "osc/robot.hpp"

namespace {

template <class M>
void print(const char* name, const M& m) {
  std::printf("%s =\n", name);
  for (int i = 0; i < m.rows(); ++i) {
    for (int j = 0; j < m.cols(); ++j) std::printf(" %10.5f", m(i, j));
    std::printf("\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace osc;
  CLI::App app(
      "Prints forward kinematics, Jacobians, A(q), g(q), c(q, qd), Lambda and the Jacobian condition "
      "of the built arm's model (OSC_ROBOT) at one of its named poses or given joint angles.",
      "osc_model_info");
  std::string pose = "start";
  std::vector<double> qv, qdv;
  std::vector<std::string> names;
  for (const NamedPose& p : robot::kNamedPoses) names.emplace_back(p.name);
  auto* pose_opt =
      app.add_option("--pose", pose, "one of the arm's named poses (default start)")->check(CLI::IsMember(names));
  app.add_option("--q", qv, "joint angles q1,...,q6 [rad]")
      ->delimiter(',')
      ->expected(6)
      ->check(CLI::Range(-100.0, 100.0))
      ->excludes(pose_opt);
  app.add_option("--qd", qdv, "joint speeds [rad/s] for c(q, qd) (default 0)")
      ->delimiter(',')
      ->expected(6)
      ->check(CLI::Range(-100.0, 100.0));
  if (const int status = sim::parse_command_line(app, argc, argv, "osc_model_info"); status >= 0) return status;
  const double* named = robot::kNamedPoses[robot::named_pose_code(pose)].q;
  Vec6<double> q = Eigen::Map<const Vec6<double>>(named), qd = Vec6<double>::Zero();
  std::string name = pose;
  if (!qv.empty()) q = Eigen::Map<const Vec6<double>>(qv.data()), name = "given q";
  if (!qdv.empty()) qd = Eigen::Map<const Vec6<double>>(qdv.data());

  const Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  ArmOpSpace<double> os;
  forward_kinematics(model, data, q);
  const Mat3<double> R_ref = data.R[kDof];  // orientation coordinates relative to this pose
  opspace_update(model, data, os, q, R_ref);
  std::printf("The arm at %s: q = [%g %g %g %g %g %g] rad\n", name.c_str(), q(0), q(1), q(2), q(3), q(4), q(5));
  print("frame-6 origin p [m]", data.o[kDof].transpose());
  print("R06", data.R[kDof]);
  print("geometric Jacobian J0 [v; w]", data.J);
  print("A(q) incl. armature", data.A);
  print("g(q) [N m]", os.g.transpose());
  print("c(q, qd) [N m]", velocity_products(model, data, qd).c.transpose());
  std::printf("Jacobian reciprocal condition (worse 3x3 block with a spherical wrist, else of J): %.3e%s\n",
              os.Jf.rcond, os.Jf.rcond < 1e-3 ? "  (near-singular: Lambda not computed)" : "");
  if (os.Jf.rcond >= 1e-3) {
    ArmJacobianFactor<double> Jg;
    Jg.compute(data.J);
    print("Lambda with the geometric Jacobian", operational_inertia(data.A, Jg));
    print("Lambda with the analytic Jacobian (orientation relative to this pose)", operational_inertia(data, os));
    print("p(x) = J^-T g", operational_gravity(os).transpose());
  }
  return 0;
}
