#include "plant.hpp"

#include <cmath>

#include "osc/dynamics.hpp"
#include "osc/puma560.hpp"

namespace sim {
namespace {

Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}
Mat3 rot_x(double a) {
  Mat3 m;
  m << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  return m;
}
Mat3 rot_z(double a) {
  Mat3 m;
  m << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return m;
}
/// Motion-vector transform [w; v] from a parent frame to a child frame with rotation E and origin r
/// (both expressed in the parent): w_c = E^T w_p, v_c = E^T (v_p - r x w_p).
Mat6 motion_transform(const Mat3& E, const Vec3& r) {
  Mat6 X = Mat6::Zero();
  X.topLeftCorner<3, 3>() = E.transpose();
  X.bottomRightCorner<3, 3>() = E.transpose();
  X.bottomLeftCorner<3, 3>() = -E.transpose() * skew(r);
  return X;
}
/// Spatial cross products for motion (crm) and force (crf) vectors, ordering [angular; linear].
Vec6 cross_motion(const Vec6& v, const Vec6& m) {
  Vec6 out;
  out << v.head<3>().cross(m.head<3>()), v.head<3>().cross(m.tail<3>()) + v.tail<3>().cross(m.head<3>());
  return out;
}
Vec6 cross_force(const Vec6& v, const Vec6& f) {
  Vec6 out;
  out << v.head<3>().cross(f.head<3>()) + v.tail<3>().cross(f.tail<3>()), v.head<3>().cross(f.tail<3>());
  return out;
}

}  // namespace

ArticulatedBody::ArticulatedBody(double link_scale) {
  using osc::puma560::kLinks;
  for (int i = 0; i < 6; ++i) {
    const auto& L = kLinks[i];
    // Link i in its joint frame B_i = F_{i-1} Rz(q_i): F_i = B_i Tz(d) Tx(a) Rx(alpha).
    const Mat3 Ra = rot_x(L.alpha);
    const Vec3 c = Vec3(L.a, 0, L.d) + Ra * Vec3(L.com[0], L.com[1], L.com[2]);
    const Mat3 Ic = Ra * Vec3(L.inertia[0], L.inertia[1], L.inertia[2]).asDiagonal() * Ra.transpose() * link_scale;
    const double m = L.mass * link_scale;
    Mat6 I;
    I.topLeftCorner<3, 3>() = Ic + m * skew(c) * skew(c).transpose();
    I.topRightCorner<3, 3>() = m * skew(c);
    I.bottomLeftCorner<3, 3>() = m * skew(c).transpose();
    I.bottomRightCorner<3, 3>() = m * Mat3::Identity();
    inertia_[i] = I;
    armature_[i] = L.gear_ratio * L.gear_ratio * L.motor_inertia;
    if (i == 0) {
      rot_fixed_[i] = Mat3::Identity();
      pos_fixed_[i] = Vec3::Zero();
    } else {
      const auto& P = kLinks[i - 1];
      rot_fixed_[i] = rot_x(P.alpha);
      pos_fixed_[i] = Vec3(P.a, 0, P.d);
    }
  }
}

Vec6 ArticulatedBody::forward_dynamics(const Vec6& q, const Vec6& qd, const Vec6& tau) const {
  Mat6 X[6], IA[6];
  Vec6 v[6], c[6], pA[6], U[6];
  double D[6], u[6];
  // Pass 1: link velocities, velocity-product accelerations, bias forces.
  for (int i = 0; i < 6; ++i) {
    X[i] = motion_transform(rot_fixed_[i] * rot_z(q(i)), pos_fixed_[i]);
    Vec6 vJ = Vec6::Zero();
    vJ(2) = qd(i);  // S = e_z (angular)
    v[i] = (i == 0 ? vJ : Vec6(X[i] * v[i - 1] + vJ));
    c[i] = cross_motion(v[i], vJ);
    IA[i] = inertia_[i];
    pA[i] = cross_force(v[i], inertia_[i] * v[i]);
  }
  // Pass 2: articulated inertias and bias forces, tip to base.
  for (int i = 5; i >= 0; --i) {
    U[i] = IA[i].col(2);
    D[i] = U[i](2) + armature_[i];
    u[i] = tau(i) - pA[i](2);
    if (i > 0) {
      const Mat6 Ia = IA[i] - U[i] * U[i].transpose() / D[i];
      const Vec6 pa = pA[i] + Ia * c[i] + U[i] * (u[i] / D[i]);
      IA[i - 1] += X[i].transpose() * Ia * X[i];
      pA[i - 1] += X[i].transpose() * pa;
    }
  }
  // Pass 3: accelerations, base to tip; gravity as an upward base acceleration.
  Vec6 a0 = Vec6::Zero();
  a0(5) = osc::puma560::kGravity;
  Vec6 qdd, a_prev = a0;
  for (int i = 0; i < 6; ++i) {
    Vec6 a = X[i] * a_prev + c[i];
    qdd(i) = (u[i] - U[i].dot(a)) / D[i];
    a(2) += qdd(i);
    a_prev = a;
  }
  return qdd;
}

Plant::Plant(const PlantConfig& cfg) : cfg_(cfg), body_(cfg.link_scale) {}

void Plant::reset(const Vec6& q0, const Vec6& qd0) {
  q_ = q0;
  qd_ = qd0;
  t_ = 0;
}

Vec6 Plant::friction(const Vec6& qd) const {
  Vec6 f;
  for (int i = 0; i < 6; ++i) {
    const double s = qd(i) > 0 ? 1.0 : (qd(i) < 0 ? -1.0 : 0.0);
    f(i) = cfg_.friction.vis[i] * qd(i) +
           (cfg_.friction.cou[i] + cfg_.friction.sti[i] * std::exp(-cfg_.tau_dec * qd(i) * qd(i))) * s;
  }
  return f;
}

Vec6 Plant::acceleration(const Vec6& q, const Vec6& qd, const Vec6& tau) const {
  return body_.forward_dynamics(q, qd, tau - friction(qd));
}

void Plant::rk4(const Vec6& tau, double h) {
  const Vec6 k1q = qd_, k1v = acceleration(q_, qd_, tau);
  const Vec6 k2q = qd_ + 0.5 * h * k1v, k2v = acceleration(q_ + 0.5 * h * k1q, k2q, tau);
  const Vec6 k3q = qd_ + 0.5 * h * k2v, k3v = acceleration(q_ + 0.5 * h * k2q, k3q, tau);
  const Vec6 k4q = qd_ + h * k3v, k4v = acceleration(q_ + h * k3q, k4q, tau);
  q_ += h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
  qd_ += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  t_ += h;
}

void Plant::integrate(const Vec6& tau, double duration) {
  if (duration <= 0) return;
  const int n = static_cast<int>(std::ceil(duration / cfg_.substep - 1e-9));
  const double h = duration / n;
  for (int k = 0; k < n; ++k) rk4(tau, h);
}

void Plant::advance_sample(const Vec6& tau_old, const Vec6& tau_new, double dt) {
  const double d = std::min(cfg_.compute_delay, dt);
  integrate(tau_old, d);
  integrate(tau_new, dt - d);
}

double Plant::energy() const {
  // Uses the kernels' CRBA only as an energy probe; the dynamics above never call it.
  const osc::Model<double> model = osc::Model<double>::puma560(cfg_.link_scale - 1.0);
  osc::Data<double> data;
  osc::forward_kinematics(model, data, q_);
  osc::joint_inertia(model, data);
  double V = 0;
  for (int i = 1; i <= 6; ++i) V += model.link[i - 1].mass * model.gravity * data.com[i].z();
  return 0.5 * qd_.dot(data.A * qd_) + V;
}

}  // namespace sim
