// The URDF's chain of six revolute joints in the table's terms (docs/arms.md, "The conversion").
//
// Joint j's origin T_j (with the fixed joints between the moving links before it) and unit axis
// a_j; A_j turns z onto a_j (I for +z, Rx(pi) for -z, else the shortest rotation). The turned frame
// is B_j = L_{j-1} T_j A_j Rz(q) and the table's frame F_j = B_j P_j, with
//   base = (fixed joints from the root) T_1 A_1,  P_j = A_j^T T_{j+1} A_{j+1} (j < 6),
//   P_6 = A_6^T (the operational point in the last link's URDF frame);
// the URDF link frame L_j = F_j (A_j P_j)^-1, so link j's inertial (COM c, inertia I in L_j) is
// com = Q_R^T (c - Q_p), I_F = Q_R^T I Q_R with Q = A_j P_j.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <urdf_parser/urdf_parser.h>

#include "armgen.hpp"

namespace armgen {

namespace {

constexpr double kPi = 3.14159265358979323846;

void require_finite(std::initializer_list<double> values, const std::string& where) {
  for (double v : values)
    if (!std::isfinite(v)) throw Error("not_finite", where + ": a value is not a finite number");
}

Frame pose_frame(const urdf::Pose& pose, const std::string& where) {
  const urdf::Rotation& q = pose.rotation;
  require_finite({pose.position.x, pose.position.y, pose.position.z, q.x, q.y, q.z, q.w}, where);
  Mat3 R;
  R << 1 - 2 * (q.y * q.y + q.z * q.z), 2 * (q.x * q.y - q.z * q.w), 2 * (q.x * q.z + q.y * q.w),
      2 * (q.x * q.y + q.z * q.w), 1 - 2 * (q.x * q.x + q.z * q.z), 2 * (q.y * q.z - q.x * q.w),
      2 * (q.x * q.z - q.y * q.w), 2 * (q.y * q.z + q.x * q.w), 1 - 2 * (q.x * q.x + q.y * q.y);
  return {snap_rotation(R), snap_translation(Vec3(pose.position.x, pose.position.y, pose.position.z))};
}

/// A rotation that turns z onto the unit vector a.
Mat3 axis_rotation(const Vec3& a) {
  if (a == Vec3(0, 0, 1)) return Mat3::Identity();
  if (a == Vec3(0, 0, -1)) return Mat3(Eigen::Vector3d(1, -1, -1).asDiagonal());
  const Vec3 k = Vec3::UnitZ().cross(a);  // sin(angle) times the unit axis
  const double c = a.z(), s2 = k.squaredNorm();
  Mat3 K;
  K << 0, -k.z(), k.y(), k.z(), 0, -k.x(), -k.y(), k.x(), 0;
  return snap_rotation(Mat3::Identity() + K + K * K * ((1 - c) / s2));
}

/// A link's inertial in its URDF frame, checked: a positive mass, an inertia positive definite that
/// meets the triangle inequality (a body's). `exempt`: the sheet's inertial_exceptions names the
/// link (mass >= 0, the inertia positive semi-definite).
Inertial link_inertial(const urdf::Link& link, bool exempt) {
  const urdf::Inertial& in = *link.inertial;
  const std::string where = "link " + link.name + "'s inertial";
  require_finite({in.mass, in.ixx, in.ixy, in.ixz, in.iyy, in.iyz, in.izz}, where);
  if (in.mass < 0 || (!exempt && in.mass == 0))
    throw Error("mass_not_positive", where + ": mass " + number(in.mass) +
                                         (exempt ? " is negative" : " (a moving link needs a positive mass)"));
  Mat3 Ic;
  Ic << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  const Eigen::Vector3d l = Eigen::SelfAdjointEigenSolver<Mat3>(Ic).eigenvalues();  // ascending
  const double tol = 1e-12 * std::max(1e-300, l.cwiseAbs().maxCoeff());
  if (exempt ? l(0) < -tol : l(0) <= 0)
    throw Error("inertia_not_positive_definite", where + ": principal moments " + number(l(0)) + ", " + number(l(1)) +
                                                     ", " + number(l(2)) +
                                                     (exempt ? " (one negative)" : " (each must be > 0)"));
  if (!exempt && l(0) + l(1) < l(2) - tol)
    throw Error("inertia_not_positive_definite", where + ": principal moments " + number(l(0)) + ", " + number(l(1)) +
                                                     ", " + number(l(2)) + " break the triangle inequality (" +
                                                     "no body has them)");
  const Frame C = pose_frame(in.origin, where);
  Inertial out;
  out.mass = in.mass;
  out.com = C.p;
  out.inertia = C.R * Ic * C.R.transpose();
  return out;
}

/// `b` placed by `T` (in the frame T is given in), then added to `a` (parallel axis theorem).
Inertial lump(const Inertial& a, const Inertial& b, const Frame& T) {
  const Vec3 cb = T.R * b.com + T.p;
  const Mat3 Ib = T.R * b.inertia * T.R.transpose();
  Inertial s;
  s.mass = a.mass + b.mass;
  if (s.mass == 0) return a;
  s.com = (a.mass * a.com + b.mass * cb) / s.mass;
  const auto shift = [&](double m, const Vec3& c) {
    const Vec3 d = c - s.com;
    return Mat3(m * (d.squaredNorm() * Mat3::Identity() - d * d.transpose()));
  };
  s.inertia = a.inertia + shift(a.mass, a.com) + Ib + shift(b.mass, cb);
  return s;
}

struct Moving {
  urdf::JointConstSharedPtr joint;
  int parent_body;  ///< -1: the root's, fixed
  Frame origin;     ///< the joint frame in the parent body's link frame
};

/// The tree walked from the root: the moving joints in depth-first order, each link's body (the
/// moving link it is fixed to, -1 for the root's) and frame in that body's link frame, and the
/// inertials of fixed links lumped into their body.
struct Walk {
  const urdf::ModelInterface* model;
  const Sheet* sheet;
  std::vector<Moving> moving;
  std::map<std::string, std::pair<int, Frame>> links;
  std::map<int, std::vector<std::pair<Inertial, Frame>>> lumped;

  void visit(const urdf::Link& link, int body, const Frame& T) {
    links[link.name] = {body, T};
    for (const urdf::JointSharedPtr& j : link.child_joints) {
      const urdf::LinkConstSharedPtr child = model->getLink(j->child_link_name);
      const Frame O = compose(T, pose_frame(j->parent_to_joint_origin_transform, "joint " + j->name + "'s origin"));
      if (j->type == urdf::Joint::FIXED) {
        if (body >= 0 && child->inertial)
          lumped[body].push_back({link_inertial(*child, sheet->inertial_exceptions.count(child->name) > 0), O});
        visit(*child, body, O);
      } else if (j->type == urdf::Joint::REVOLUTE || j->type == urdf::Joint::CONTINUOUS) {
        moving.push_back({j, body, O});
        visit(*child, static_cast<int>(moving.size()) - 1, Frame{});
      } else {
        const char* kind = j->type == urdf::Joint::PRISMATIC  ? "prismatic"
                           : j->type == urdf::Joint::PLANAR   ? "planar"
                           : j->type == urdf::Joint::FLOATING ? "floating"
                                                              : "of unknown type";
        throw Error("joint_type",
                    "joint " + j->name + " is " + kind + ": an arm's joints are revolute (or continuous) and fixed");
      }
    }
  }
};

void check_serial(const Walk& w) {
  std::string names;
  for (const Moving& m : w.moving) names += (names.empty() ? "" : ", ") + m.joint->name;
  if (w.moving.size() != 6)
    throw Error("chain_joints", std::to_string(w.moving.size()) + " moving joints (" + names +
                                    "), not 6 revolute joints in a serial chain");
  for (int i = 0; i < 6; ++i)
    if (w.moving[i].parent_body != i - 1)
      throw Error("chain_joints", "joint " + w.moving[i].joint->name + " does not follow " +
                                      (i == 0 ? std::string("the root") : "joint " + w.moving[i - 1].joint->name) +
                                      ": the moving joints (" + names + ") are not a serial chain");
}

Joint read_joint(const urdf::Joint& j) {
  Joint out;
  out.name = j.name;
  out.child = j.child_link_name;
  require_finite({j.axis.x, j.axis.y, j.axis.z}, "joint " + j.name + "'s axis");
  const Vec3 a(j.axis.x, j.axis.y, j.axis.z);
  if (a.norm() < 1e-12) throw Error("zero_axis", "joint " + j.name + "'s axis is zero");
  out.axis = snap_translation(a / a.norm());
  for (int i = 0; i < 3; ++i)
    for (double t : {1.0, -1.0})
      if (std::abs(out.axis(i) - t) <= 1e-12) out.axis(i) = t;
  out.continuous = j.type == urdf::Joint::CONTINUOUS;
  if (out.continuous) {
    out.lower = -2 * kPi, out.upper = 2 * kPi;
  } else {
    require_finite({j.limits->lower, j.limits->upper}, "joint " + j.name + "'s limits");
    out.lower = j.limits->lower, out.upper = j.limits->upper;
    if (out.lower >= out.upper)
      throw Error("limits_inverted",
                  "joint " + j.name + ": lower limit " + number(out.lower) + " >= upper limit " + number(out.upper));
  }
  return out;
}

/// The URDF's numbers checked before urdfdom reads them: urdfdom drops an inertial it cannot read
/// (a NaN mass becomes a link without mass) and refuses infinities as text. Every number of the
/// elements the conversion reads (origin, axis, mass, inertia, limit) must be a finite number.
void scan_numbers(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("urdf_parse", path + ": cannot be read");
  std::stringstream text;
  text << in.rdbuf();
  const std::string xml = text.str();
  static const std::regex element(R"(<(origin|axis|mass|inertia|limit)\b([^>]*)>)");
  static const std::regex attribute(R"re((\w+)\s*=\s*"([^"]*)")re");
  for (auto e = std::sregex_iterator(xml.begin(), xml.end(), element); e != std::sregex_iterator(); ++e) {
    const std::string attrs = (*e)[2];
    const long line = 1 + std::count(xml.begin(), xml.begin() + e->position(), '\n');
    for (auto a = std::sregex_iterator(attrs.begin(), attrs.end(), attribute); a != std::sregex_iterator(); ++a) {
      const std::string name = (*a)[1], value = (*a)[2];
      if (name == "name" || name == "joint") continue;
      std::istringstream tokens(value);
      std::string token;
      while (tokens >> token) {
        const std::string where =
            path + ":" + std::to_string(line) + ": <" + std::string((*e)[1]) + " " + name + "=\"" + value + "\">";
        char* end = nullptr;
        const double v = std::strtod(token.c_str(), &end);
        if (end != token.c_str() + token.size()) throw Error("urdf_parse", where + ": " + token + " is not a number");
        if (!std::isfinite(v)) throw Error("not_finite", where + ": " + token + " is not a finite number");
      }
    }
  }
}

}  // namespace

Chain read_chain(const std::string& urdf_path, const Sheet& sheet) {
  scan_numbers(urdf_path);
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDFFile(urdf_path);
  if (!model) throw Error("urdf_parse", urdf_path + ": not a URDF urdfdom reads (its message above)");
  for (const auto& [name, j] : model->joints_)
    if (j->mimic) throw Error("mimic_joint", "joint " + name + " mimics " + j->mimic->joint_name + ": not supported");
  Walk w{model.get(), &sheet, {}, {}, {}};
  w.visit(*model->getRoot(), -1, Frame{});
  check_serial(w);

  Chain c;
  c.root = model->getRoot()->name;
  std::array<Mat3, 6> A;
  std::array<Inertial, 6> inertial_L;
  for (int i = 0; i < 6; ++i) {
    c.joints[i] = read_joint(*w.moving[i].joint);
    A[i] = axis_rotation(c.joints[i].axis);
    const urdf::LinkConstSharedPtr link = model->getLink(c.joints[i].child);
    if (!link->inertial)
      throw Error("missing_inertial",
                  "link " + link->name + " moves (joint " + c.joints[i].name + ") but has no <inertial>");
    inertial_L[i] = link_inertial(*link, sheet.inertial_exceptions.count(link->name) > 0);
    for (const auto& [in, T] : w.lumped[i]) inertial_L[i] = lump(inertial_L[i], in, T);
  }
  for (const auto& [name, why] : sheet.inertial_exceptions)
    if (!w.links.count(name))
      throw Error("sheet_value", "inertial_exceptions." + name + ": no link " + name + " in " + urdf_path);

  c.tool_frame = sheet.op_frame.empty() ? c.joints[5].child : sheet.op_frame;
  const auto it = w.links.find(c.tool_frame);
  if (it == w.links.end() || it->second.first != 5)
    throw Error("operational_frame", "operational_point.frame " + c.tool_frame + " is not a link fixed to " +
                                         c.joints[5].child + " (the last moving link)");
  Frame offset;
  offset.p = snap_translation(Vec3(sheet.op_xyz[0].v, sheet.op_xyz[1].v, sheet.op_xyz[2].v));
  offset.R = rpy_rotation(sheet.op_rpy[0].v, sheet.op_rpy[1].v, sheet.op_rpy[2].v);
  c.tool = compose(it->second.second, offset);

  c.base = compose(w.moving[0].origin, Frame{A[0], Vec3::Zero()});
  for (int i = 0; i < 6; ++i) {
    const Frame next = i < 5 ? compose(w.moving[i + 1].origin, Frame{A[i + 1], Vec3::Zero()}) : c.tool;
    c.placement[i] = compose(Frame{A[i].transpose(), Vec3::Zero()}, next);
    const Frame Q = compose(Frame{A[i], Vec3::Zero()}, c.placement[i]);
    Inertial& L = c.link[i];
    L.mass = inertial_L[i].mass;
    L.com = snap_translation(Q.R.transpose() * (inertial_L[i].com - Q.p));
    Mat3 I = Q.R.transpose() * inertial_L[i].inertia * Q.R;
    I = (I + I.transpose()) / 2;
    const double scale = I.diagonal().cwiseAbs().maxCoeff();
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k)
        if (std::abs(I(r, k)) <= 1e-12 * scale) I(r, k) = 0;
    L.inertia = I;
  }
  return c;
}

}  // namespace armgen
