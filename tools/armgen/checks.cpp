// The description's cross checks: the named poses against the URDF's limits, and the fixed-point
// range: the M3 firmware holds every kernel and control quantity in Q12.19
// (firmware/math/include/osc/math/fixed.hpp: range +-4096, resolution 2^-19 = 1.9e-6) and the
// hardware units in Q19.12 (range +-524288).
#include <cmath>
#include <string>

#include "armgen.hpp"

namespace armgen {

namespace {

constexpr double kRange = 4096;                  // Q12.19
constexpr double kResolution = 1.0 / (1 << 19);  // Q12.19
constexpr double kIoRange = 524288;              // Q19.12
constexpr double kPi = 3.14159265358979323846;
const char* const kJoint[] = {"1", "2", "3", "4", "5", "6"};

void range(double v, const std::string& what, double limit = kRange, const char* format = "Q12.19") {
  if (!(std::abs(v) < limit))
    throw Error("fixed_point_range",
                what + " = " + number(v) + " overflows the firmware's " + format + " (range +-" + number(limit) + ")");
}

/// In range, and not rounded to 0 or by more than 10 % (`reference`: the magnitude the rounding is
/// judged against, default |v|).
void resolved(double v, const std::string& what, double reference = 0) {
  range(v, what);
  if (v == 0) return;
  const double r = std::round(v / kResolution) * kResolution;
  const double ref = reference > 0 ? reference : std::abs(v);
  if (std::abs(r - v) > 0.1 * ref)
    throw Error("fixed_point_resolution", what + " = " + number(v) + " rounds to " + number(r) +
                                              " in the firmware's Q12.19 (resolution 1.9e-6): more than 10 % lost");
}

void check_poses(const Sheet& s, const Chain& c) {
  std::vector<const Pose*> named{&s.start};
  for (const Pose& p : s.named) named.push_back(&p);
  for (const Pose* p : named)
    for (int i = 0; i < 6; ++i)
      if (p->q[i].v < c.joints[i].lower || p->q[i].v > c.joints[i].upper)
        throw Error("pose_outside_limits", "named pose " + p->name + ": joint " + kJoint[i] + " at " +
                                               (p->q[i].text == number(p->q[i].v) ? "" : p->q[i].text + " = ") +
                                               number(p->q[i].v) + " rad, outside the limits [" +
                                               number(c.joints[i].lower) + ", " + number(c.joints[i].upper) + "] of " +
                                               c.joints[i].name);
}

void check_links(const Chain& c, double gravity) {
  for (int k = 0; k < 3; ++k) range(c.base.p(k), "the base placement's translation");
  for (int i = 0; i < 6; ++i) {
    const std::string link = "link " + std::string(kJoint[i]) + " (" + c.joints[i].child + ")";
    resolved(c.link[i].mass, link + "'s mass");
    for (int k = 0; k < 3; ++k) {
      range(c.placement[i].p(k), link + "'s placement translation");
      range(c.link[i].com(k), link + "'s centre of mass");
    }
    const Mat3& I = c.link[i].inertia;
    double smallest = 0;
    for (int k = 0; k < 3; ++k)
      if (I(k, k) > 0 && (smallest == 0 || I(k, k) < smallest)) smallest = I(k, k);
    const char* names[3][3] = {{"Ixx", "Ixy", "Ixz"}, {"Ixy", "Iyy", "Iyz"}, {"Ixz", "Iyz", "Izz"}};
    for (int r = 0; r < 3; ++r)
      for (int k = r; k < 3; ++k) resolved(I(r, k), link + "'s inertia " + names[r][k], r == k ? 0 : smallest);
  }
  // Gravity torques: joint j's at most g sum_{k>=j} m_k (sum_{l=j..k} |p_l| + |com_k|).
  for (int j = 0; j < 6; ++j) {
    double bound = 0, reach = 0;
    for (int k = j; k < 6; ++k) {
      reach += c.placement[k].p.norm();
      bound += c.link[k].mass * (reach + c.link[k].com.norm());
    }
    range(gravity * bound, "the bound on joint " + std::string(kJoint[j]) + "'s gravity torque (sum m reach g)");
  }
}

void check_drives(const Sheet& s) {
  for (int i = 0; i < 6; ++i) {
    const std::string j = std::string(" of joint ") + kJoint[i];
    const double G = s.gear[i].v;
    range(G, "the gear ratio" + j);
    for (const MotorSet& m : s.motor_sets) resolved(m.jm[i].v * G * G, "the armature G^2 Jm (" + m.name + ")" + j);
    range(s.dac_full_scale[i].v, "the DAC's full-scale torque" + j);
    range(s.motor_torque_limit[i].v * std::abs(G), "the amplifier's torque limit at the joint" + j);
    range(s.motor_torque_limit[i].v / s.torque_constant[i].v, "the amplifier's current limit" + j);
    range(s.torque_constant[i].v, "the torque constant" + j);
    range(s.joint_speed[i].v, "the plausible joint speed" + j);
    const double cpr_model = s.model_cpr.v * std::abs(G) / (2 * kPi);
    range(cpr_model, "the model's encoder counts per radian" + j, kIoRange, "Q19.12 I/O format");
    const double e = s.encoder[i].v;
    const double cpr = s.encoder_unit == "rad_per_count"          ? 1 / e
                       : s.encoder_unit == "counts_per_motor_rev" ? e * std::abs(G) / (2 * kPi)
                                                                  : e / (2 * kPi);
    range(cpr, "the arm's encoder counts per radian" + j, kIoRange, "Q19.12 I/O format");
    for (const FrictionPreset& f : s.friction) {
      const double vis = f.motor ? f.a[i].v * G * G : f.a[i].v;
      const double cou = f.motor ? std::abs(G) * (f.b[i].v - f.c[i].v) / 2 : f.b[i].v;
      const double sti = f.motor ? 0 : f.c[i].v;
      const double widen = 1 + s.drift.v;  // the band's top
      range(vis * widen, "friction " + f.name + "'s viscous coefficient (with the band's drift)" + j);
      range(cou * widen, "friction " + f.name + "'s Coulomb coefficient (with the band's drift)" + j);
      range(sti * widen, "friction " + f.name + "'s Stribeck coefficient (with the band's drift)" + j);
    }
  }
  range(s.cart_velocity.v, "the Cartesian velocity limit");
  range(s.cart_acceleration.v, "the Cartesian acceleration limit");
  range(s.cart_jerk.v, "the Cartesian jerk limit");
  range(s.gravity.v, "gravity");
}

}  // namespace

void check_description(const Sheet& s, const Chain& c) {
  check_poses(s, c);
  for (int i = 0; i < 6; ++i) {
    range(c.joints[i].lower, "joint " + std::string(kJoint[i]) + "'s lower limit");
    range(c.joints[i].upper, "joint " + std::string(kJoint[i]) + "'s upper limit");
  }
  check_links(c, s.gravity.v);
  check_drives(s);
}

}  // namespace armgen
