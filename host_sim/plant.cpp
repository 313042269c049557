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
/// A parent-to-child frame change: child rotation E and origin r, both expressed in the parent.
struct Transform {
  Mat3 E;
  Vec3 r;
  /// Motion vector to the child: w_c = E^T w_p, v_c = E^T (v_p - r x w_p).
  void motion_to_child(const Vec3& w, const Vec3& v, Vec3& wc, Vec3& vc) const {
    wc.noalias() = E.transpose() * w;
    vc.noalias() = E.transpose() * (v - r.cross(w));
  }
  /// Force vector to the parent: f_p = E f_c, n_p = E n_c + r x f_p.
  void force_to_parent(const Vec3& n, const Vec3& f, Vec3& np, Vec3& fp) const {
    fp.noalias() = E * f;
    np.noalias() = E * n;
    np += r.cross(fp);
  }
  /// Spatial inertia to the parent, X^T I X with X the motion transform above.
  void add_inertia_to_parent(const SpatialInertia& I, SpatialInertia& out) const {
    const Mat3 Ib = E * I.Ib * E.transpose();
    const Mat3 H = E * I.H * E.transpose();
    const Mat3 M = E * I.M * E.transpose();
    const Mat3 R = skew(r);
    const Mat3 RM = R * M;
    out.Ib += Ib + R * H.transpose() - H * R - RM * R;
    out.H += H + RM;
    out.M += M;
  }
};

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
    inertia_[i] = SpatialInertia{Ic + m * skew(c) * skew(c).transpose(), m * skew(c), m * Mat3::Identity()};
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
  Transform X[6];
  SpatialInertia IA[6];
  Vec3 w[6], v[6], cw[6], cv[6], pn[6], pf[6], Ut[6], Ub[6];
  double D[6], u[6];
  // Pass 1, base to tip: link velocities, velocity-product accelerations c, bias forces p.
  Vec3 wp = Vec3::Zero(), vp = Vec3::Zero();
  for (int i = 0; i < 6; ++i) {
    const double cq = std::cos(q(i)), sq = std::sin(q(i));
    Mat3 Rz;
    Rz << cq, -sq, 0, sq, cq, 0, 0, 0, 1;
    X[i].E.noalias() = rot_fixed_[i] * Rz;
    X[i].r = pos_fixed_[i];
    X[i].motion_to_child(wp, vp, w[i], v[i]);
    const Vec3 wJ(0, 0, qd(i));  // S qd, S = z (angular)
    w[i] += wJ;
    cw[i] = w[i].cross(wJ);
    cv[i] = v[i].cross(wJ);
    IA[i] = inertia_[i];
    const Vec3 hn = inertia_[i].Ib * w[i] + inertia_[i].H * v[i];   // I v: angular part
    const Vec3 hf = inertia_[i].H.transpose() * w[i] + inertia_[i].M * v[i];  // linear part
    pn[i] = w[i].cross(hn) + v[i].cross(hf);
    pf[i] = w[i].cross(hf);
    wp = w[i];
    vp = v[i];
  }
  // Pass 2, tip to base: articulated inertias and bias forces.
  for (int i = 5; i >= 0; --i) {
    Ut[i] = IA[i].Ib.col(2);
    Ub[i] = IA[i].H.row(2).transpose();
    D[i] = Ut[i](2) + armature_[i];
    u[i] = tau(i) - pn[i](2);
    if (i > 0) {
      SpatialInertia Ia = IA[i];
      const double invD = 1.0 / D[i];
      Ia.Ib.noalias() -= invD * Ut[i] * Ut[i].transpose();
      Ia.H.noalias() -= invD * Ut[i] * Ub[i].transpose();
      Ia.M.noalias() -= invD * Ub[i] * Ub[i].transpose();
      const Vec3 an = pn[i] + Ia.Ib * cw[i] + Ia.H * cv[i] + Ut[i] * (u[i] * invD);
      const Vec3 af = pf[i] + Ia.H.transpose() * cw[i] + Ia.M * cv[i] + Ub[i] * (u[i] * invD);
      X[i].add_inertia_to_parent(Ia, IA[i - 1]);
      Vec3 np, fp;
      X[i].force_to_parent(an, af, np, fp);
      pn[i - 1] += np;
      pf[i - 1] += fp;
    }
  }
  // Pass 3, base to tip: accelerations; gravity as an upward base acceleration.
  Vec3 ap = Vec3::Zero(), lp(0, 0, osc::puma560::kGravity);
  Vec6 qdd;
  for (int i = 0; i < 6; ++i) {
    Vec3 a, l;
    X[i].motion_to_child(ap, lp, a, l);
    a += cw[i];
    l += cv[i];
    qdd(i) = (u[i] - Ut[i].dot(a) - Ub[i].dot(l)) / D[i];
    a(2) += qdd(i);
    ap = a;
    lp = l;
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
