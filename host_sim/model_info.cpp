// osc_model_info: prints the PUMA 560 model quantities at a named pose or given joint angles.
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

#include "cli.hpp"
#include "osc/kernels/opspace.hpp"
#include "osc/robot.hpp"

namespace {

const char* kUsage =
    "usage: osc_model_info [--pose qn|qz|qr|qs | --q q1,q2,q3,q4,q5,q6] [--qd v1,...,v6]\n"
    "  prints forward kinematics, Jacobians, A(q), g(q), c(q,qd), Lambda and the Jacobian condition\n";

template <class M>
void print(const char* name, const M& m) {
  std::printf("%s =\n", name);
  for (int i = 0; i < m.rows(); ++i) {
    for (int j = 0; j < m.cols(); ++j) std::printf(" %10.5f", m(i, j));
    std::printf("\n");
  }
}

bool parse_vec(const std::string& flag, const char* text, osc::Vec6<double>& v, std::string& err) {
  if (!text) return err = flag + " needs six comma-separated numbers", false;
  std::string s = text;
  for (int i = 0; i < 6; ++i) {
    const size_t comma = s.find(',');
    const std::string item = s.substr(0, comma);
    if (!sim::parse_number(flag, item.c_str(), -100, 100, v(i), err)) return false;
    if ((comma == std::string::npos) != (i == 5)) return err = flag + " needs exactly six comma-separated numbers", false;
    s = comma == std::string::npos ? "" : s.substr(comma + 1);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace osc;
  Vec6<double> q = joint_vector<double>(puma560::kQn), qd = Vec6<double>::Zero();
  std::string name = "qn", err;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* v = i + 1 < argc ? argv[++i] : nullptr;
    if (a == "--help" || a == "-h") {
      std::cout << kUsage;
      return 0;
    } else if (a == "--pose") {
      const std::string p = v ? v : "";
      const double* src = p == "qn" ? puma560::kQn : p == "qz" ? puma560::kQz : p == "qr" ? puma560::kQr
                        : p == "qs" ? puma560::kQs : nullptr;
      if (!src) {
        std::cerr << "osc_model_info: --pose: unknown pose '" << p << "' (qn, qz, qr, qs)\n" << kUsage;
        return 2;
      }
      for (int k = 0; k < kDof; ++k) q(k) = src[k];
      name = p;
    } else if (a == "--q") {
      if (!parse_vec(a, v, q, err)) break;
      name = "given q";
    } else if (a == "--qd") {
      if (!parse_vec(a, v, qd, err)) break;
    } else {
      err = "unknown option '" + a + "'";
      break;
    }
  }
  if (!err.empty()) {
    std::cerr << "osc_model_info: " << err << "\n" << kUsage;
    return 2;
  }

  const Model<double> model = Model<double>::of(robot::kArm);
  Data<double> data;
  OpSpace<double> os;
  forward_kinematics(model, data, q);
  const Mat3<double> R_ref = data.R[kDof];  // orientation coordinates relative to this pose
  opspace_update(model, data, os, q, R_ref);
  std::printf("PUMA 560 at %s: q = [%g %g %g %g %g %g] rad\n", name.c_str(), q(0), q(1), q(2), q(3), q(4), q(5));
  print("frame-6 origin p [m]", data.o[kDof].transpose());
  print("R06", data.R[kDof]);
  print("geometric Jacobian J0 [v; w]", data.J);
  print("A(q) incl. armature", data.A);
  print("g(q) [N m]", os.g.transpose());
  print("c(q, qd) [N m]", velocity_products(model, data, qd).c.transpose());
  std::printf("Jacobian reciprocal condition (worse 3x3 block): %.3e%s\n", os.Jf.rcond,
              os.Jf.rcond < 1e-3 ? "  (near-singular: Lambda not computed)" : "");
  if (os.Jf.rcond >= 1e-3) {
    SphericalWristJacobianFactor<double> Jg;
    Jg.compute(data.J);
    print("Lambda with the geometric Jacobian", operational_inertia(data.A, Jg));
    print("Lambda with the analytic Jacobian (orientation relative to this pose)", os.Lambda);
    print("p(x) = J^-T g", operational_gravity(os).transpose());
  }
  return 0;
}
