#include "plant.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <limits>

#include "osc/kernels/dynamics.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/kernels/kinematics.hpp"
#include "osc/robot.hpp"

namespace sim {
namespace {

Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
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

constexpr double kNoArmature[6] = {0, 0, 0, 0, 0, 0};

/// The coupling C of the arm's encoders (q = C e), unit lower triangular.
Mat6 coupling_matrix() {
  const osc::EncoderMap& map = osc::robot::kDriveTrain.encoders;
  Mat6 C = Mat6::Identity();
  for (int k = 0; k < map.coupling_terms; ++k) C(map.coupling[k].row, map.coupling[k].col) += map.coupling[k].c;
  return C;
}

/// The joints with a motor-side state: J1-J3 when elastic or with backlash.
bool is_elastic(const PlantConfig& cfg, int i) { return i < 3 && (cfg.elastic_hz > 0 || cfg.backlash > 0); }

/// G^2 Jm of channel i, joint-referred, from the configured set.
double motor_armature(const PlantConfig& cfg, int i) {
  const osc::LinkParams& L = osc::robot::kArm.links[i];
  const double jm = cfg.motor_inertia ? cfg.motor_inertia->jm[i] : L.motor_inertia;
  return L.gear_ratio * L.gear_ratio * jm;
}

/// The plant's articulated body: the model's (ideal drives), else the scalar armature of each rigid,
/// uncoupled joint (an elastic joint's motor is a state of its own; with the coupling the armature is a
/// full matrix, solved by the composite-rigid-body path instead).
ArticulatedBody make_body(const PlantConfig& cfg) {
  if (cfg.ideal_drives()) return ArticulatedBody(cfg.link_scale, cfg.payload);
  double a[6];
  for (int i = 0; i < 6; ++i) a[i] = cfg.coupling || is_elastic(cfg, i) ? 0.0 : motor_armature(cfg, i);
  return ArticulatedBody(cfg.link_scale, a, cfg.payload);
}

int sign_of(double v) { return v > 0 ? 1 : (v < 0 ? -1 : 0); }

/// A contact's switch within this much of an interval's end happens at that end [s]: a sample's
/// bound, at its time as the sum of its substeps rounds it.
constexpr double kContactEdge = 1e-9;

}  // namespace

Contact Contact::of(const Injection& inj) {
  Contact c;
  if (!inj.enabled || !inj.contact()) return c;
  c.direction = Vec3::Unit(inj.direction / 2) * (inj.direction % 2 != 0 ? -1.0 : 1.0);
  c.at = inj.at;
  if (inj.kind == InjectionKind::kCollision) {
    c.kind = Kind::kForce;
    c.force = inj.magnitude;
    c.duration = inj.duration;
    return c;
  }
  c.kind = Kind::kWall;
  c.distance = inj.magnitude * 1e-3;
  if (inj.stiffness > 0) {
    c.stiffness = inj.stiffness;
    c.damping = default_damping(c.stiffness);
  }
  return c;
}

bool PlantConfig::ideal_drives() const {
  for (int i = 0; i < 6; ++i)
    if (amp_gain_error[i] != 0 || amp_offset[i] != 0) return false;
  return motor_inertia == nullptr && !coupling && amp_lag == 0 && !amp_current_limit && ripple == 0 &&
         friction_drift == 0 && elastic_hz == 0 && backlash == 0;
}

namespace {
/// A placement's rotation and translation as Eigen values.
Mat3 rotation_of(const osc::Placement& P) {
  Mat3 R;
  R << P.R[0][0], P.R[0][1], P.R[0][2], P.R[1][0], P.R[1][1], P.R[1][2], P.R[2][0], P.R[2][1], P.R[2][2];
  return R;
}
Vec3 translation_of(const osc::Placement& P) { return Vec3(P.p[0], P.p[1], P.p[2]); }
}  // namespace

ArticulatedBody::ArticulatedBody(double link_scale, const osc::Payload& payload) {
  const osc::ArmDescription& arm = osc::robot::kArm;
  for (int i = 0; i < 6; ++i) {
    // The link scaled (model-error studies), then link 6 with the payload it carries (not scaled).
    osc::LinkParams L = arm.links[i];
    L.mass *= link_scale;
    for (double& v : L.inertia) v *= link_scale;
    if (i == 5) L = osc::with_payload(L, payload);
    // Link i in its joint frame B_i = F_{i-1} Rz(q_i): F_i = B_i P_i, P_i = (R, p) its placement.
    const Mat3 R = rotation_of(L.placement);
    const Vec3 c = translation_of(L.placement) + R * Vec3(L.com[0], L.com[1], L.com[2]);
    Mat3 I;  // about the COM, axes of F_i
    I << L.inertia[0], L.inertia[3], L.inertia[4], L.inertia[3], L.inertia[1], L.inertia[5], L.inertia[4], L.inertia[5],
        L.inertia[2];
    body_[i] = Body{L.mass, c, R * I * R.transpose()};
    armature_[i] = L.gear_ratio * L.gear_ratio * L.motor_inertia;
    // F_{i-1} in B_{i-1} (F_0 in the base frame for the first joint).
    const osc::Placement& P = i == 0 ? arm.base : arm.links[i - 1].placement;
    rot_fixed_[i] = rotation_of(P);
    pos_fixed_[i] = translation_of(P);
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

ArticulatedBody::ArticulatedBody(double link_scale, const double armature[6], const osc::Payload& payload)
    : ArticulatedBody(link_scale, payload) {
  for (int i = 0; i < 6; ++i) armature_[i] = armature[i];
}

namespace {
/// A spatial inertia at the base origin in its compact form: mass m, first moment h = m c (c the
/// centre of mass) and the rotational inertia I about the origin; I [w; v] = [I w + h x v; m v - h x w].
/// Sums and products at 13 and 24 numbers instead of a 6 x 6 matrix's 36.
struct RigidInertia {
  double m;
  Vec3 h;
  Mat3 I;
  Vec6 operator*(const Vec6& s) const {
    const Vec3 w = s.head<3>(), v = s.tail<3>();
    return join(I * w + h.cross(v), m * v - h.cross(w));
  }
  RigidInertia& operator+=(const RigidInertia& o) {
    m += o.m;
    h += o.h;
    I += o.I;
    return *this;
  }
};
}  // namespace

namespace {
/// W Rz(q): the columns 0 and 1 of W turned, 6 products instead of 27.
void turn_z(Mat3& W, double c, double s) {
  const Vec3 w0 = W.col(0), w1 = W.col(1);
  W.col(0) = c * w0 + s * w1;
  W.col(1) = c * w1 - s * w0;
}
}  // namespace

void ArticulatedBody::inertia_and_bias(const Vec6& q, const Vec6& qd, Mat6& M, Vec6& h) const {
  RigidInertia Ic[6];
  Vec6 S[6], f[6];
  // Pass 1, base to tip, as in forward_dynamics() (every quantity at the base origin, in base axes):
  // axes S = [z; o x z], velocities V = [w; v], link inertias; the accelerations at q_dd = 0 (gravity
  // as an upward base acceleration, plus the velocity products V x S qd) and each link's force
  // I a + V x* I V (recursive Newton-Euler). The joint rotations turn two columns at a time (turn_z).
  Mat3 W = Mat3::Identity();
  Vec3 o = Vec3::Zero(), w = Vec3::Zero(), v = Vec3::Zero();
  Vec3 aw = Vec3::Zero(), av(0, 0, osc::robot::kArm.gravity);
  for (int i = 0; i < 6; ++i) {
    o += W * pos_fixed_[i];
    W = W * rot_fixed_[i];
    turn_z(W, std::cos(q(i)), std::sin(q(i)));
    const Vec3 z = W.col(2), oz = o.cross(z);
    S[i] = join(z, oz);
    const Vec3 wJ = z * qd(i), vJ = oz * qd(i);
    w += wJ;
    v += vJ;
    aw += w.cross(wJ);
    av += w.cross(vJ) + v.cross(wJ);
    const Body& b = body_[i];
    const Vec3 com = o + W * b.com;
    RigidInertia& I = Ic[i];
    I.m = b.mass;
    I.h = b.mass * com;
    // About the origin: W I_B W^T (the link's inertia about its COM, axes of B_i) plus
    // m (|c|^2 1 - c c^T) (parallel axes).
    const Mat3 Iw = W * b.inertia * W.transpose();
    const double cc = b.mass * com.squaredNorm();
    for (int r = 0; r < 3; ++r)
      for (int c = r; c < 3; ++c) {
        const double e = Iw(r, c) - b.mass * com(r) * com(c) + (r == c ? cc : 0.0);
        I.I(r, c) = I.I(c, r) = e;
      }
    // f = I a + V x* (I V): I [w; v] = [I w + h x v; m v - h x w].
    const Vec3 Lw = I.I * w + I.h.cross(v), Lv = I.m * v - I.h.cross(w);
    f[i] = join(I.I * aw + I.h.cross(av) + w.cross(Lw) + v.cross(Lv), I.m * av - I.h.cross(aw) + w.cross(Lv));
  }
  // Pass 2, tip to base: composite inertias and forces (all at the base origin: no transforms);
  // M_ji = S_j . Ic_i S_i for j <= i, h_i = S_i . F_i.
  for (int i = 5; i >= 0; --i) {
    if (i < 5) {
      Ic[i] += Ic[i + 1];
      f[i] += f[i + 1];
    }
    h(i) = S[i].dot(f[i]);
    const Vec6 Us = Ic[i] * S[i];
    M(i, i) = S[i].dot(Us) + armature_[i];
    for (int j = 0; j < i; ++j) M(i, j) = M(j, i) = S[j].dot(Us);
  }
}

Vec6 ArticulatedBody::forward_dynamics(const Vec6& q, const Vec6& qd, const Vec6& tau, const Mat6& armature) const {
  Mat6 M;
  Vec6 h;
  inertia_and_bias(q, qd, M, h);
  M += armature;
  // Cholesky, M = L L^T (M symmetric positive definite: the links' inertia plus the motors'), then
  // L y = tau - h, L^T q_dd = y; written out on the 6 x 6 (a third of Eigen's general LLT's time).
  double L[6][6], y[6];
  const Vec6 b = tau - h;
  for (int j = 0; j < 6; ++j) {
    double d = M(j, j);
    for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
    L[j][j] = std::sqrt(d);
    const double inv = 1.0 / L[j][j];
    for (int i = j + 1; i < 6; ++i) {
      double e = M(i, j);
      for (int k = 0; k < j; ++k) e -= L[i][k] * L[j][k];
      L[i][j] = e * inv;
    }
    double r = b(j);
    for (int k = 0; k < j; ++k) r -= L[j][k] * y[k];
    y[j] = r * inv;
  }
  Vec6 x;
  for (int j = 5; j >= 0; --j) {
    double r = y[j];
    for (int k = j + 1; k < 6; ++k) r -= L[k][j] * x(k);
    x(j) = r / L[j][j];
  }
  return x;
}

Plant::Plant(const PlantConfig& cfg)
    : cfg_(cfg),
      ideal_(cfg.ideal_drives()),
      body_(make_body(cfg)),
      links_(cfg.link_scale, kNoArmature, cfg.payload),
      friction_(osc::FrictionParams<double>::from(cfg.friction, cfg.tau_dec)) {
  if (ideal_) return;
  coupled_ = cfg.coupling;
  if (coupled_) {
    const Mat6 C = coupling_matrix();
    c_inv_ = C.triangularView<Eigen::UnitLower>().solve(Mat6::Identity());
    c_inv_t_ = c_inv_.transpose();
  }
  Vec6 D = Vec6::Zero();  // G^2 Jm of the rigid joints' motors (the elastic joints' are their own state)
  for (int i = 0; i < 6; ++i) {
    elastic_[i] = is_elastic(cfg, i);
    motor_inertia_(i) = motor_armature(cfg, i);
    if (!elastic_[i]) D(i) = motor_inertia_(i);
    const osc::LinkParams& L = osc::robot::kArm.links[i];
    limit_(i) = osc::robot::kDriveTrain.motor_torque_limit[i] * std::abs(L.gear_ratio);
    // Coulomb and Stribeck terms switch sign with the rate: RK4 must not step across their reversal.
    sign_sensitive_[i] = friction_.cou(i) != 0 || friction_.sti(i) != 0;
  }
  // The motors turn at e_dot = C^-1 q_dot: their kinetic energy 1/2 e_dot^T D e_dot is the joint-space
  // armature C^-T D C^-1 (diagonal without the coupling).
  armature_rigid_ = c_inv_t_ * D.asDiagonal() * c_inv_;
  armature_all_ = c_inv_t_ * motor_inertia_.asDiagonal() * c_inv_;
  if (elastic_[0] || elastic_[1] || elastic_[2]) {
    // The coupling must leave J1-J3 alone (it does on the PUMA: wrist terms only), or their motors'
    // states would enter the wrist's equations.
    for (int k = 0; k < osc::robot::kDriveTrain.encoders.coupling_terms && coupled_; ++k)
      if (osc::robot::kDriveTrain.encoders.coupling[k].col < 3 || osc::robot::kDriveTrain.encoders.coupling[k].row < 3)
        throw std::invalid_argument("Plant: the coupling involves an elastic joint");
    // Stiffness from the locked-motor resonance: the joint alone (the other joints held) on its spring,
    // K = (2 pi f)^2 M_ii(kQStart), M_ii the links' inertia about the joint at the start pose without
    // any armature (the plant's own composite-rigid-body inertia). With backlash alone, a stiff mesh
    // (kBacklashStiffHz) for the dead band to act through.
    Mat6 M;
    Vec6 h;
    links_.inertia_and_bias(osc::joint_vector<double>(osc::robot::kQStart), Vec6::Zero(), M, h);
    const double f = cfg.elastic_hz > 0 ? cfg.elastic_hz : kBacklashStiffHz;
    const double w = 2 * osc::kPi * f;
    for (int i = 0; i < 3; ++i)
      if (elastic_[i]) stiffness_(i) = w * w * M(i, i);
    half_band_ = cfg.backlash / 2;
  }
}

void Plant::reset(const Vec6& q0, const Vec6& qd0) {
  q_ = q0;
  qd_ = qd0;
  t_ = 0;
  contact_phase_ = 0;
  peak_contact_ = 0;
  first_contact_ = -1;
  if (ideal_) return;
  amp_.setZero();
  cmd_.setZero();
  th_ = q0;
  thd_ = qd0;
  if (stiffness_.any()) {
    // The static deflection: each spring holds its link's gravity torque g(q0), theta = q0 + dz^-1(g / K)
    // (on the flank that carries the load, where there is backlash).
    Mat6 M;
    Vec6 g;
    links_.inertia_and_bias(q0, Vec6::Zero(), M, g);
    for (int i = 0; i < 3; ++i)
      if (elastic_[i]) th_(i) = q0(i) + g(i) / stiffness_(i) + half_band_ * sign_of(g(i));
  }
}

void Plant::set_motor_state(const Vec6& theta, const Vec6& theta_d) {
  for (int i = 0; i < 6; ++i)
    if (elastic_[i]) {
      th_(i) = theta(i);
      thd_(i) = theta_d(i);
    }
}

Vec6 Plant::friction(const Vec6& qd) const {
  if (ideal_) return osc::friction_torque(friction_, qd);
  const Vec6 f = friction_scale(t_) * osc::friction_torque(friction_, coupled_ ? Vec6(c_inv_ * qd) : qd);
  return coupled_ ? Vec6(c_inv_t_ * f) : f;
}

Vec6 Plant::acceleration(const Vec6& q, const Vec6& qd, const Vec6& tau) const {
  ++evaluations_;
  Vec6 ext;
  const bool pushed = external(q, qd, ext);
  if (ideal_) return body_.forward_dynamics(q, qd, pushed ? Vec6(tau - friction(qd) + ext) : Vec6(tau - friction(qd)));
  const Vec6 net = Vec6(c_inv_t_ * tau) - friction(qd);
  return links_.forward_dynamics(q, qd, pushed ? Vec6(net + ext) : net, armature_all_);
}

void Plant::set_contact(const Contact& c) {
  contact_ = c;
  contact_phase_ = 0;
  peak_contact_ = 0;
  first_contact_ = -1;
}

Vec3 Plant::force_at(const Vec6& qd) const {
  if (contact_phase_ != 1 || contact_.kind == Contact::Kind::kNone) return Vec3::Zero();
  const Vec3& n = contact_.direction;
  if (contact_.kind == Contact::Kind::kForce) return contact_.force * n;
  // The wall: the penetration d and its rate n . J_v qd; it pushes back along -n and never pulls.
  const double d = n.dot(kin_.o[osc::kDof]) - wall_plane_;
  if (d <= 0) return Vec3::Zero();
  const double d_dot = n.dot(kin_.J.topRows<3>() * qd);
  return -std::max(0.0, contact_.stiffness * d + contact_.damping * d_dot) * n;
}

Vec3 Plant::contact_force(const Vec6& q, const Vec6& qd) const {
  if (contact_phase_ != 1) return Vec3::Zero();
  // The kernels' kinematics (the dynamics stay the plant's own; test_contact checks J_v^T F against KDL).
  osc::forward_kinematics(kin_model_, kin_, q);
  osc::geometric_jacobian(kin_);
  return force_at(qd);
}

bool Plant::external(const Vec6& q, const Vec6& qd, Vec6& tau_ext) const {
  if (contact_phase_ != 1) return false;
  const Vec3 f = contact_force(q, qd);
  if ((f.array() == 0.0).all()) return false;
  tau_ext = kin_.J.topRows<3>().transpose() * f;
  return true;
}

Vec6 Plant::external_torque(const Vec6& q, const Vec6& qd) const {
  Vec6 t = Vec6::Zero();
  external(q, qd, t);
  return t;
}

int Plant::contact_regime(const Vec6& q, const Vec6& qd) const {
  if (contact_phase_ != 1 || contact_.kind != Contact::Kind::kWall) return 0;
  osc::forward_kinematics(kin_model_, kin_, q);
  osc::geometric_jacobian(kin_);
  if (contact_.direction.dot(kin_.o[osc::kDof]) - wall_plane_ <= 0) return 1;
  return force_at(qd).squaredNorm() > 0 ? 2 : 3;
}

double Plant::contact_edge() const {
  if (contact_.kind == Contact::Kind::kNone) return std::numeric_limits<double>::infinity();
  if (contact_phase_ == 0) return contact_.at;
  if (contact_phase_ == 1 && contact_.kind == Contact::Kind::kForce && contact_.duration >= 0)
    return contact_.at + contact_.duration;
  return std::numeric_limits<double>::infinity();
}

void Plant::next_contact_phase() {
  ++contact_phase_;
  if (contact_phase_ != 1 || contact_.kind != Contact::Kind::kWall) return;
  osc::forward_kinematics(kin_model_, kin_, q_);
  wall_plane_ = contact_.direction.dot(kin_.o[osc::kDof]) + contact_.distance;
}

Vec6 Plant::motor_angles() const { return ideal_ ? q_ : motor_angles_of(State{q_, qd_, th_, thd_}); }
Vec6 Plant::motor_velocities() const { return ideal_ ? qd_ : motor_rates_of(State{q_, qd_, th_, thd_}); }

Vec6 Plant::motor_torques() const {
  if (ideal_) return cmd_;
  return delivered(cfg_.amp_lag > 0 ? amp_ : cmd_, State{q_, qd_, th_, thd_});
}

Vec6 Plant::spring_torques() const {
  Vec6 t = Vec6::Zero();
  for (int i = 0; i < 3; ++i)
    if (elastic_[i]) t(i) = spring(i, th_(i) - q_(i));
  return t;
}

Vec6 Plant::motor_angles_of(const State& x) const {
  Vec6 e = x.q;
  for (int i = 0; i < 3; ++i)
    if (elastic_[i]) e(i) = x.th(i);
  return coupled_ ? Vec6(c_inv_ * e) : e;
}

Vec6 Plant::motor_rates_of(const State& x) const {
  Vec6 r = x.v;
  for (int i = 0; i < 3; ++i)
    if (elastic_[i]) r(i) = x.w(i);
  return coupled_ ? Vec6(c_inv_ * r) : r;
}

double Plant::friction_scale(double t) const {
  if (cfg_.friction_drift == 0) return 1.0;
  return 1.0 + cfg_.friction_drift * std::sin(2 * osc::kPi * t / cfg_.friction_drift_period);
}

double Plant::spring(int i, double stretch) const {
  const double x = stretch > half_band_ ? stretch - half_band_ : (stretch < -half_band_ ? stretch + half_band_ : 0.0);
  return stiffness_(i) * x;
}

Vec6 Plant::amplifier(const Vec6& u, double s) const {
  if (cfg_.amp_lag <= 0) return u;
  // First order, exact for a held command: a(s) = u + (a(0) - u) exp(-s / T).
  return u + (amp_ - u) * std::exp(-s / cfg_.amp_lag);
}

Vec6 Plant::currents(const Vec6& amp) const {
  if (!amplifiers_on_) return Vec6::Zero();  // disabled: no current at all, offsets included
  Vec6 t = amp;
  if (cfg_.amp_current_limit) t = t.cwiseMax(-limit_).cwiseMin(limit_);
  for (int i = 0; i < 6; ++i) t(i) = (1 + cfg_.amp_gain_error[i]) * t(i) + cfg_.amp_offset[i];
  return t;
}

Vec6 Plant::amplifier_currents() const {
  if (ideal_) return amplifiers_on_ ? cmd_ : Vec6::Zero();
  return currents(cfg_.amp_lag > 0 ? amp_ : cmd_);
}

Vec6 Plant::delivered(const Vec6& amp, const State& x) const {
  Vec6 t = currents(amp);
  if (cfg_.ripple != 0) {
    // The motor's pole frequency: ripple_cycles periods per shaft revolution, shaft angle G e.
    const Vec6 e = motor_angles_of(x);
    for (int i = 0; i < 6; ++i)
      t(i) *= 1 + cfg_.ripple * std::sin(cfg_.ripple_cycles * osc::robot::kArm.links[i].gear_ratio * e(i));
  }
  return t;
}

Plant::State Plant::derivative(const State& x, double t, const Vec6& amp) const {
  ++evaluations_;
  // The channels' net torques on their motors (joint-referred): produced minus the motors' friction,
  // model (2) on the motor rates (with its drift).
  const Vec6 net = delivered(amp, x) - friction_scale(t) * osc::friction_torque(friction_, motor_rates_of(x));
  // To the joints through C^-T; an elastic joint's link is driven by its spring instead, its motor by
  // the net torque less the spring's.
  Vec6 tau = coupled_ ? Vec6(c_inv_t_ * net) : net;
  State d;
  d.q = x.v;
  d.th.setZero();
  d.w.setZero();
  for (int i = 0; i < 3; ++i)
    if (elastic_[i]) {
      const double ts = spring(i, x.th(i) - x.q(i));
      tau(i) = ts;
      d.th(i) = x.w(i);
      d.w(i) = (net(i) - ts) / motor_inertia_(i);
    }
  Vec6 ext;
  if (external(x.q, x.v, ext)) tau += ext;  // the contact acts on the links
  d.v = coupled_ ? links_.forward_dynamics(x.q, x.v, tau, armature_rigid_) : body_.forward_dynamics(x.q, x.v, tau);
  return d;
}

std::uint64_t Plant::regime(const State& x, const Vec6& amp) const {
  std::uint64_t code = 1;  // never 0 unless a rate is
  const Vec6 r = motor_rates_of(x);
  for (int i = 0; i < 6; ++i) {
    if (!sign_sensitive_[i]) continue;
    if (r(i) == 0) return 0;
    code |= std::uint64_t{r(i) > 0 ? 1u : 2u} << (2 * i + 1);
  }
  if (half_band_ > 0)
    for (int i = 0; i < 3; ++i) {
      if (!elastic_[i]) continue;
      const double s = x.th(i) - x.q(i);
      code |= std::uint64_t{s > half_band_ ? 1u : (s < -half_band_ ? 2u : 3u)} << (2 * i + 13);
    }
  if (cfg_.amp_current_limit)
    for (int i = 0; i < 6; ++i)
      code |= std::uint64_t{amp(i) > limit_(i) ? 1u : (amp(i) < -limit_(i) ? 2u : 3u)} << (2 * i + 19);
  return code | std::uint64_t(contact_regime(x.q, x.v)) << 31;
}

bool Plant::step(const Vec6& u, double h, bool smooth) {
  const Vec6 a0 = amplifier(u, 0), am = amplifier(u, 0.5 * h), a1 = amplifier(u, h);
  const auto axpy = [](const State& x, double c, const State& k) {
    return State{x.q + c * k.q, x.v + c * k.v, x.th + c * k.th, x.w + c * k.w};
  };
  const State x0{q_, qd_, th_, thd_};
  const std::uint64_t r0 = smooth ? regime(x0, a0) : 0;
  if (smooth && r0 == 0) return false;
  // Classic RK4; in a smooth step every stage (and the end) must stay in the start's regime, else the
  // caller redoes the interval at the fine substep. Checked as the stages are formed, to stop early.
  const State k1 = derivative(x0, t_, a0);
  const State x2 = axpy(x0, 0.5 * h, k1);
  if (smooth && regime(x2, am) != r0) return false;
  const State k2 = derivative(x2, t_ + 0.5 * h, am);
  const State x3 = axpy(x0, 0.5 * h, k2);
  if (smooth && regime(x3, am) != r0) return false;
  const State k3 = derivative(x3, t_ + 0.5 * h, am);
  const State x4 = axpy(x0, h, k3);
  if (smooth && regime(x4, a1) != r0) return false;
  const State k4 = derivative(x4, t_ + h, a1);
  const State x1{x0.q + h / 6 * (k1.q + 2 * k2.q + 2 * k3.q + k4.q), x0.v + h / 6 * (k1.v + 2 * k2.v + 2 * k3.v + k4.v),
                 x0.th + h / 6 * (k1.th + 2 * k2.th + 2 * k3.th + k4.th),
                 x0.w + h / 6 * (k1.w + 2 * k2.w + 2 * k3.w + k4.w)};
  if (smooth && regime(x1, a1) != r0) return false;
  q_ = x1.q;
  qd_ = x1.v;
  th_ = x1.th;
  thd_ = x1.w;
  amp_ = a1;
  t_ += h;
  return true;
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
  // A wall's force has a kink where the tip meets it (and where its clamp engages): the same rule.
  if (contact_.kind == Contact::Kind::kWall && contact_phase_ == 1) {
    const int r = contact_regime(q_, qd_);
    if (contact_regime(q_ + 0.5 * h * k1q, k2q) != r || contact_regime(q_ + 0.5 * h * k2q, k3q) != r ||
        contact_regime(q_ + h * k3q, k4q) != r ||
        contact_regime(q_ + h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q), qd1) != r)
      return false;
  }
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
  cmd_ = tau;
  if (duration <= 0) return;
  // A contact that starts or ends inside the interval cuts it there: no RK4 step straddles the switch.
  double left = duration;
  for (double e = contact_edge(); e < t_ + left - kContactEdge; e = contact_edge()) {
    if (e > t_ + kContactEdge) {
      const double end = t_ + left;
      integrate_span(tau, e - t_);
      left = end - t_;
    }
    next_contact_phase();
  }
  integrate_span(tau, left);
}

void Plant::integrate_span(const Vec6& tau, double duration) {
  const int n = static_cast<int>(std::ceil(duration / cfg_.substep - 1e-9));
  const double h = duration / n;
  if (!ideal_) {
    // The same chunks with the drive train's state: the fine substep through any event (a friction
    // reversal of a motor, a backlash contact change, a current limit engaging or releasing).
    for (int k = 0; k < n;) {
      const int m = std::min(cfg_.smooth_steps, n - k);
      if (m < 2 || !step(tau, m * h, true))
        for (int j = 0; j < m; ++j) step(tau, h, false);
      k += m;
    }
    return;
  }
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
    if (!ideal_) {  // the motors held too; the amplifiers follow their commands
      thd_.setZero();
      const double d = std::min(cfg_.compute_delay, dt);
      amp_ = amplifier(tau_old, d);
      amp_ = amplifier(tau_new, dt - d);
      cmd_ = tau_new;
    }
    while (contact_edge() < t_ + dt - kContactEdge) next_contact_phase();
    t_ += dt;
  } else {
    const double d = std::min(cfg_.compute_delay, dt);
    integrate(tau_old, d);
    integrate(tau_new, dt - d);
  }
  if (contact_phase_ == 1) {
    const double f = contact_force(q_, qd_).norm();
    peak_contact_ = std::max(peak_contact_, f);
    if (f > 0 && first_contact_ < 0) first_contact_ = t_;
  }
}

double Plant::energy() const {
  // Uses the kernels' CRBA only as an energy probe; the dynamics above never call it.
  osc::Model<double> model = osc::Model<double>::of(osc::robot::kArm, cfg_.link_scale - 1.0, cfg_.payload);
  if (!ideal_) model.armature.setZero();  // the links alone; the drive train's armature below
  osc::Data<double> data;
  osc::forward_kinematics(model, data, q_);
  osc::joint_inertia(model, data);
  double V = 0;
  for (int i = 1; i <= 6; ++i) V += model.link[i - 1].mass * model.gravity * data.com[i].z();
  if (ideal_) return 0.5 * qd_.dot(data.A * qd_) + V;
  // The rigid joints' motors (armature C^-T D C^-1), the elastic joints' motors and springs.
  double E = 0.5 * qd_.dot((data.A + armature_rigid_) * qd_) + V;
  for (int i = 0; i < 3; ++i)
    if (elastic_[i]) {
      const double s = spring(i, th_(i) - q_(i));
      E += 0.5 * motor_inertia_(i) * thd_(i) * thd_(i);
      if (stiffness_(i) > 0) E += 0.5 * s * s / stiffness_(i);
    }
  return E;
}

}  // namespace sim
