#include "plant.hpp"

#include <cmath>

#include "osc/kernels/dynamics.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/robot.hpp"
#include "osc/robot.hpp"

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
/// [a; b]. (Not Eigen's comma initializer: GCC 12 under -march=native reads the initializer of a
/// 6-vector from two 3-vectors as an AVX load past the end of the second, a false -Warray-bounds.)
Vec6 join(const Vec3& a, const Vec3& b) {
  Vec6 out;
  out.head<3>() = a;
  out.tail<3>() = b;
  return out;
}
/// Spatial cross products at a common point, ordering [angular; linear].
Vec6 cross_motion(const Vec6& v, const Vec6& m) {
  return join(v.head<3>().cross(m.head<3>()), v.head<3>().cross(m.tail<3>()) + v.tail<3>().cross(m.head<3>()));
}
Vec6 cross_force(const Vec6& v, const Vec6& f) {
  return join(v.head<3>().cross(f.head<3>()) + v.tail<3>().cross(f.tail<3>()), v.head<3>().cross(f.tail<3>()));
}

}  // namespace

ArticulatedBody::ArticulatedBody(double link_scale) {
  const osc::LinkParams* kLinks = osc::robot::kArm.links;
  for (int i = 0; i < 6; ++i) {
    const auto& L = kLinks[i];
    // Link i in its joint frame B_i = F_{i-1} Rz(q_i): F_i = B_i Tz(d) Tx(a) Rx(alpha).
    const Mat3 Ra = rot_x(L.alpha);
    const Vec3 c = Vec3(L.a, 0, L.d) + Ra * Vec3(L.com[0], L.com[1], L.com[2]);
    const Mat3 Ic = Ra * Vec3(L.inertia[0], L.inertia[1], L.inertia[2]).asDiagonal() * Ra.transpose() * link_scale;
    const double m = L.mass * link_scale;
    body_[i] = Body{m, c, Ic};
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
  Mat6 IA[6];
  Vec6 S[6], c[6], pA[6], U[6];
  double D[6], u[6];
  // Pass 1, base to tip: joint frames, axes S = [z; o x z], velocities, velocity-product
  // accelerations c = V x S qd, link inertias at the base origin and bias forces V x* I V.
  Mat3 W = Mat3::Identity();
  Vec3 o = Vec3::Zero();
  Vec6 V = Vec6::Zero();
  for (int i = 0; i < 6; ++i) {
    o += W * pos_fixed_[i];
    const double cq = std::cos(q(i)), sq = std::sin(q(i));
    Mat3 Rz;
    Rz << cq, -sq, 0, sq, cq, 0, 0, 0, 1;
    W = W * rot_fixed_[i] * Rz;
    const Vec3 z = W.col(2);
    S[i] = join(z, o.cross(z));
    const Vec6 vJ = S[i] * qd(i);
    V += vJ;
    c[i] = cross_motion(V, vJ);
    const Body& b = body_[i];
    const Vec3 com = o + W * b.com;
    const Mat3 C = skew(com);
    Mat6& I = IA[i];
    I.topLeftCorner<3, 3>() = W * b.inertia * W.transpose() + b.mass * C * C.transpose();
    I.topRightCorner<3, 3>() = b.mass * C;
    I.bottomLeftCorner<3, 3>() = b.mass * C.transpose();
    I.bottomRightCorner<3, 3>() = b.mass * Mat3::Identity();
    pA[i] = cross_force(V, I * V);
  }
  // Pass 2, tip to base: articulated inertias and bias forces (no transforms: all at the origin).
  for (int i = 5; i >= 0; --i) {
    U[i].noalias() = IA[i] * S[i];
    D[i] = S[i].dot(U[i]) + armature_[i];
    u[i] = tau(i) - S[i].dot(pA[i]);
    if (i > 0) {
      const double invD = 1.0 / D[i];
      const Mat6 Ia = IA[i] - invD * U[i] * U[i].transpose();
      IA[i - 1] += Ia;
      pA[i - 1] += pA[i] + Ia * c[i] + U[i] * (u[i] * invD);
    }
  }
  // Pass 3, base to tip: accelerations; gravity as an upward base acceleration.
  Vec6 a;
  a << 0, 0, 0, 0, 0, osc::robot::kArm.gravity;
  Vec6 qdd;
  for (int i = 0; i < 6; ++i) {
    a += c[i];
    qdd(i) = (u[i] - U[i].dot(a)) / D[i];
    a += S[i] * qdd(i);
  }
  return qdd;
}

Plant::Plant(const PlantConfig& cfg)
    : cfg_(cfg), body_(cfg.link_scale), friction_(osc::FrictionParams<double>::from(cfg.friction, cfg.tau_dec)) {}

void Plant::reset(const Vec6& q0, const Vec6& qd0) {
  q_ = q0;
  qd_ = qd0;
  t_ = 0;
}

Vec6 Plant::friction(const Vec6& qd) const { return osc::friction_torque(friction_, qd); }

Vec6 Plant::acceleration(const Vec6& q, const Vec6& qd, const Vec6& tau) const {
  ++evaluations_;
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

bool Plant::rk4_smooth(const Vec6& tau, double h) {
  const Vec6 k1q = qd_, k1v = acceleration(q_, qd_, tau);
  const Vec6 k2q = qd_ + 0.5 * h * k1v, k2v = acceleration(q_ + 0.5 * h * k1q, k2q, tau);
  const Vec6 k3q = qd_ + 0.5 * h * k2v, k3v = acceleration(q_ + 0.5 * h * k2q, k3q, tau);
  const Vec6 k4q = qd_ + h * k3v, k4v = acceleration(q_ + h * k3q, k4q, tau);
  const Vec6 qd1 = qd_ + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  // Friction (2) is smooth along the step only if every velocity it was evaluated at, and the
  // end velocity, has the start's strict sign.
  for (int i = 0; i < 6; ++i) {
    const double v = qd_(i);
    if (v == 0) return false;
    if (v > 0 ? (k2q(i) <= 0 || k3q(i) <= 0 || k4q(i) <= 0 || qd1(i) <= 0)
              : (k2q(i) >= 0 || k3q(i) >= 0 || k4q(i) >= 0 || qd1(i) >= 0))
      return false;
  }
  q_ += h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
  qd_ = qd1;
  t_ += h;
  return true;
}

void Plant::integrate(const Vec6& tau, double duration) {
  if (duration <= 0) return;
  const int n = static_cast<int>(std::ceil(duration / cfg_.substep - 1e-9));
  const double h = duration / n;
  // Chunks of up to smooth_steps substeps: one RK4 step over the chunk where the friction is
  // smooth, the fixed substep through a velocity reversal (where sgn() makes RK4 first order).
  for (int k = 0; k < n;) {
    const int m = std::min(cfg_.smooth_steps, n - k);
    if (m < 2 || !rk4_smooth(tau, m * h))
      for (int j = 0; j < m; ++j) rk4(tau, h);
    k += m;
  }
}

void Plant::advance_sample(const Vec6& tau_old, const Vec6& tau_new, double dt) {
  if (braked_) {  // the brakes hold every joint: time passes, nothing moves
    qd_.setZero();
    t_ += dt;
    return;
  }
  const double d = std::min(cfg_.compute_delay, dt);
  integrate(tau_old, d);
  integrate(tau_new, dt - d);
}

double Plant::energy() const {
  // Uses the kernels' CRBA only as an energy probe; the dynamics above never call it.
  const osc::Model<double> model = osc::Model<double>::of(osc::robot::kArm, cfg_.link_scale - 1.0);
  osc::Data<double> data;
  osc::forward_kinematics(model, data, q_);
  osc::joint_inertia(model, data);
  double V = 0;
  for (int i = 1; i <= 6; ++i) V += model.link[i - 1].mass * model.gravity * data.com[i].z();
  return 0.5 * qd_.dot(data.A * qd_) + V;
}

}  // namespace sim
