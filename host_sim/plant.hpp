// Simulated PUMA 560: rigid-body dynamics (1) in double by the articulated-body algorithm (its own
// code path, independent of the controller's CRBA/RNEA/operational-space kernels), true friction
// by model (2), RK4 integration at a fine step, zero-order-hold torques applied after the
// controller's computation delay inside each sample. Optionally (PlantConfig, issue 24) the drive
// train's own dynamics: a motor inertia set, the wrist coupling, the amplifiers (current loop lag,
// current limit, gain error, offset), torque ripple, friction drift, elastic joints and backlash on
// J1-J3; all off, the plant is the rigid one above, bit for bit. Optionally (Contact) a contact at
// the tip: a force step or pulse, or a stiff wall; none, the plant is the one above, bit for bit.
#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Core>

#include "injection.hpp"
#include "osc/control/params.hpp"
#include "osc/kernels/friction.hpp"
#include "osc/kernels/model.hpp"
#include "osc/robot.hpp"

namespace sim {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

struct PlantConfig {
  osc::FrictionCoefficients friction = *osc::robot::kFrictionPresets[0];  ///< the sheet's first preset (PUMA: paper)
  double tau_dec = osc::params::kTauDec;
  double substep = 1e-4;  ///< RK4 step [s] (10 kHz) wherever a joint's velocity changes sign
  /// Away from velocity reversals (every joint's velocity keeps its sign through the step, so the
  /// friction of model (2) is smooth) RK4 takes this many substeps at once; 1 = fixed step.
  int smooth_steps = 8;
  double compute_delay = osc::params::kActuationDelay;  ///< from the encoder sample to the DAC update [s]
  double link_scale = 1.0;                              ///< scales every link mass and inertia (model-error studies)
  osc::Payload payload;  ///< the payload the arm carries at its flange (link 6): plant.payload_*, unscaled

  // The drive train's dynamics (issue 24), each off by default; all off, the plant computes exactly
  // what it did without them (the articulated-body path, bit for bit). The inputs of advance_sample()
  // and integrate() are the amplifier channels' torques, each referred to its joint (what the DACs
  // command): the joint torques themselves unless `coupling` is on.
  /// Motor inertias of the armature G^2 Jm: nullptr, the model's own (kArm.links[i].motor_inertia);
  /// or e.g. &osc::robot::kDriveTrain.motor_inertia_alt (the PUMA's: AKB86's).
  const osc::MotorInertias* motor_inertia = nullptr;
  /// The wrist coupling (kDriveTrain.encoders: q = C e) in the dynamics: the motors turn at
  /// e_dot = C^-1 q_dot, the channels' torques reach the joints as C^-T tau_m, the motors' inertias
  /// and friction act on the motor side.
  bool coupling = false;
  double amp_lag = 0;              ///< amplifier current loop, first-order time constant [s]; 0: none
  bool amp_current_limit = false;  ///< each channel limited at kDriveTrain.motor_torque_limit |G| (joint-referred)
  double amp_gain_error[6] = {};   ///< relative, per channel: torque = (1 + err) command + offset
  double amp_offset[6] = {};       ///< [N m] joint-referred, per channel
  double ripple = 0;               ///< torque ripple, relative amplitude: tau (1 + ripple sin(cycles G e))
  int ripple_cycles = 0;           ///< ripple periods per motor revolution (the motor's pole frequency)
  /// Friction scales by (1 + friction_drift sin(2 pi t / friction_drift_period)), t the plant's time.
  double friction_drift = 0;
  double friction_drift_period = 3600;  ///< [s]
  /// Joint elasticity on J1-J3: the locked-motor resonance [Hz] at the start pose (kQStart), each joint
  /// alone (the others held: K = (2 pi f)^2 M_ii(kQStart)); 0: rigid. With all three elastic and every
  /// motor held, J1-J3 are inertially coupled: at 20 Hz their modes are 16.8, 19.4 and 27.7 Hz.
  double elastic_hz = 0;
  /// Gear backlash on J1-J3: the total dead band at the joint [rad]; 0: none. Without elasticity the
  /// gears are then a stiff spring (kBacklashStiffHz) with that dead band.
  double backlash = 0;

  /// True when every drive-train feature above is at its neutral value (the rigid, ideal drive train).
  bool ideal_drives() const;
};

/// A contact at the tip (the frame-6 origin: the wrist centre the controller tracks) from time `at`
/// on: a force F on the tip, base frame, that acts on the arm as the joint torques J_v(q)^T F (J_v the
/// geometric Jacobian's translational rows), evaluated at every RK4 stage from the stage's state.
/// A force step or pulse along `direction`, or a stiff wall normal to it.
struct Contact {
  enum class Kind : std::uint8_t { kNone, kForce, kWall };
  /// The wall's default stiffness [N/m]: 1 mm of penetration per 100 N.
  static constexpr double kWallStiffness = 1e5;
  /// The wall's default damping for stiffness k [N s/m]: 2 zeta sqrt(m k), an estimate with zeta =
  /// 0.2 on an effective tip mass m = 10 kg (the translational rows of Lambda span about 0.2 to 40 kg
  /// over the arm's range): the contact rings and decays within a few periods.
  static double default_damping(double k) { return 2 * 0.2 * std::sqrt(10 * k); }

  Kind kind = Kind::kNone;
  Vec3 direction = Vec3::UnitZ();  ///< unit, base frame
  double at = 0;                   ///< from this time of the plant's on [s]
  double force = 0;                ///< kForce: along direction [N]
  double duration = -1;            ///< kForce: a pulse's length [s]; negative: for good
  /// kWall: the plane's distance from the tip at `at`, along direction [m]. The tip penetrates by
  /// d = direction . p - plane; for d > 0 the wall pushes back along -direction with
  /// max(0, stiffness d + damping d_dot): it never pulls.
  double distance = 0;
  double stiffness = kWallStiffness;                 ///< kWall [N/m]
  double damping = default_damping(kWallStiffness);  ///< kWall [N s/m]

  /// The contact of a collision or wall injection (injection.hpp); none for the other kinds.
  static Contact of(const Injection& inj);
};

/// The locked-motor resonance of the gear mesh when backlash is on and elastic_hz is 0 [Hz]: stiff
/// enough to be far above the control bandwidth, soft enough for the plant's RK4 step.
constexpr double kBacklashStiffHz = 60.0;

/// Articulated-body forward dynamics of the built arm (armature on each joint's scalar inertia),
/// Featherstone's algorithm with every spatial quantity expressed at the base origin in base axes,
/// so that no transform is needed between links.
class ArticulatedBody {
 public:
  explicit ArticulatedBody(double link_scale = 1.0, const osc::Payload& payload = {});
  /// With a given armature (joint-referred, on each joint's scalar inertia) instead of the model's G^2 Jm.
  ArticulatedBody(double link_scale, const double armature[6], const osc::Payload& payload = {});
  /// q_dd for joint torques tau (friction already subtracted), gravity along -z0.
  Vec6 forward_dynamics(const Vec6& q, const Vec6& qd, const Vec6& tau) const;
  /// The composite-rigid-body inertia M(q) (this body's scalar armature on its diagonal) and the bias
  /// h(q, qd) = C(q, qd) qd + g(q), from the same spatial quantities as forward_dynamics().
  void inertia_and_bias(const Vec6& q, const Vec6& qd, Mat6& M, Vec6& h) const;
  /// q_dd with a full joint-space armature matrix added to M(q): (M + armature) q_dd = tau - h,
  /// solved by Cholesky (for an armature that is not diagonal, e.g. the coupled wrist's).
  Vec6 forward_dynamics(const Vec6& q, const Vec6& qd, const Vec6& tau, const Mat6& armature) const;
  double armature(int i) const { return armature_[i]; }

 private:
  struct Body {
    double mass;
    Vec3 com;      // COM in the joint frame B_i (origin o_{i-1}, z = axis i)
    Mat3 inertia;  // about the COM, axes of B_i
  };
  Body body_[6];
  Mat3 rot_fixed_[6];  // rotation of F_{i-1} in B_{i-1} (of F_0 in the base frame for i = 0)
  Vec3 pos_fixed_[6];  // origin of F_{i-1} in B_{i-1}: (a_{i-1}, 0, d_{i-1}) for a DH row
  double armature_[6];
};

/// The robot: state, drive train, friction, integration.
class Plant {
 public:
  explicit Plant(const PlantConfig& cfg = {});
  /// Joint state q0, qd0, at time 0. Elastic joints start with the static deflection that holds the
  /// links against gravity at q0 (motor angle q0 + dz^-1(g(q0) / K), its rate qd0), so that an arm whose
  /// motors hold the gravity torques does not ring at the start; the amplifiers start at zero torque.
  void reset(const Vec6& q0, const Vec6& qd0 = Vec6::Zero());
  /// Advances one control sample of length dt: tau_old is held for the computation delay, then tau_new.
  /// The torques are the amplifier channels' commands, each referred to its joint.
  void advance_sample(const Vec6& tau_old, const Vec6& tau_new, double dt);
  /// The holding brakes: engaged, advance_sample() keeps every joint where it is, at rest (a PUMA's
  /// brakes hold the arm while its power is off; the commanded-motion simulation engages them while
  /// the controller is disabled or in fault). Elastic joints' motors are held too; the amplifiers
  /// still follow their commands.
  void set_brakes(bool engaged) { braked_ = engaged; }
  bool brakes() const { return braked_; }
  /// The amplifiers' enable line (a board's fault output disables them): off, they deliver no
  /// torque at all, their offsets included (category 0).
  void set_amplifiers(bool on) { amplifiers_on_ = on; }
  /// Integrates for duration with constant command tau (the amplifier channels', joint-referred).
  void integrate(const Vec6& tau, double duration);

  /// A contact at the tip (none by default); reset() takes it back to before its start.
  void set_contact(const Contact& c);
  const Contact& contact() const { return contact_; }
  /// The contact's force on the tip at state (q, qd) as it acts now [N, base frame]: zero before its
  /// start, after a pulse, and off the wall.
  Vec3 contact_force(const Vec6& q, const Vec6& qd) const;
  /// Its joint torques J_v(q)^T F at (q, qd): tau_ext.
  Vec6 external_torque(const Vec6& q, const Vec6& qd) const;
  /// The largest |F| of the contact since reset(), sampled at the end of each advance_sample() [N].
  double peak_contact_force() const { return peak_contact_; }
  /// The end of the first sample in which the contact pushed (|F| > 0) [s]; -1: none yet.
  double first_contact_time() const { return first_contact_; }

  /// The joint torques of the drive train's friction at joint rates qd (model (2); with the coupling,
  /// C^-T f(C^-1 qd), the motors' friction referred to the joints; with the drift, at the plant's
  /// time; on an elastic joint, the friction its motor would have at the joint's rate).
  Vec6 friction(const Vec6& qd) const;
  /// The joint accelerations for the amplifier channels' torques tau, as delivered to the motors, at
  /// (q, qd): the rigid plant (today's articulated body) or, with drive-train features, the rigid
  /// drive train with the configured armature, coupling and friction (elastic joints taken rigid).
  Vec6 acceleration(const Vec6& q, const Vec6& qd, const Vec6& tau) const;
  /// Kinetic plus potential energy (for integration checks): links and armature, and with elastic
  /// joints their motors' kinetic energy and the springs' energy.
  double energy() const;

  const Vec6& q() const { return q_; }
  /// The motors' angles, each referred to its joint through its gears: what the encoders count and
  /// where the index pulses fire. C^-1 q with the coupling; an elastic joint's motor-side angle; the
  /// joint angles themselves on the rigid, uncoupled plant.
  Vec6 motor_angles() const;
  /// The motors' rates, referred to their joints, likewise.
  Vec6 motor_velocities() const;
  const Vec6& qd() const { return qd_; }
  double time() const { return t_; }
  const PlantConfig& config() const { return cfg_; }
  /// Dynamics evaluations since construction (cost accounting for tests and benchmarks): the
  /// articulated-body (or, with the coupling, composite-rigid-body) solves, one per RK4 stage.
  long evaluations() const { return evaluations_; }

  /// False on the ideal plant (every drive-train feature off: today's path, bit for bit).
  bool drive_dynamics() const { return !ideal_; }
  /// The torques the motors produce now (joint-referred, per channel) for the last command: after
  /// the amplifiers' lag, current limit, gain error and offset, and the ripple.
  Vec6 motor_torques() const;
  /// The amplifiers' currents now, each as the torque it gives (joint-referred, per channel): what a current
  /// monitor measures (motor_torques() without the ripple, which is the motor's, not the current's).
  Vec6 amplifier_currents() const;
  /// The elastic joints' spring torques K dz(theta - q) (zero on rigid joints).
  Vec6 spring_torques() const;
  /// The elastic joints' stiffness K [N m/rad] (zero on rigid joints).
  const Vec6& stiffness() const { return stiffness_; }
  /// The motor-side state of the elastic joints (angles and rates referred to the joints; the other
  /// entries are ignored), e.g. to start a test from a given gear contact.
  void set_motor_state(const Vec6& theta, const Vec6& theta_d);

 private:
  /// The state of the plant with drive-train dynamics: joints, and the elastic joints' motors (the
  /// entries of th and w of rigid joints are not used).
  struct State {
    Vec6 q, v, th, w;
  };
  void rk4(const Vec6& tau, double h);
  /// One RK4 step of h if no joint velocity changes sign at any stage; otherwise leaves the state.
  bool rk4_smooth(const Vec6& tau, double h);

  // The drive-train path (ideal_ false).
  State derivative(const State& x, double t, const Vec6& amp) const;
  /// One RK4 step of h for command u; with `smooth`, only if no event (regime()) happens in it.
  bool step(const Vec6& u, double h, bool smooth);
  /// What must not change within a smooth step: the sign of every friction-carrying motor rate, the
  /// gear contact of every backlash, the current limit's state of every channel. 0: a rate is zero.
  std::uint64_t regime(const State& x, const Vec6& amp) const;
  Vec6 delivered(const Vec6& amp, const State& x) const;
  Vec6 motor_angles_of(const State& x) const;
  Vec6 motor_rates_of(const State& x) const;
  double friction_scale(double t) const;
  // The contact.
  /// J_v(q)^T F into tau_ext; false (tau_ext untouched) when F is zero, so that a contact that does
  /// not push leaves every sum as it was without one.
  bool external(const Vec6& q, const Vec6& qd, Vec6& tau_ext) const;
  /// The contact's force at (q, qd) with the tip kinematics (kin_) already at q.
  Vec3 force_at(const Vec6& qd) const;
  /// What must not change within a smooth step: off the wall, pushed, in it but not pushed (0: no wall).
  int contact_regime(const Vec6& q, const Vec6& qd) const;
  /// The next time the contact switches (its start, a pulse's end); infinity when none is left.
  double contact_edge() const;
  /// Switches to the contact's next phase (a wall's plane is placed from where the tip is now).
  void next_contact_phase();
  /// RK4 over duration with the contact as it is (integrate() cuts the interval at its switches).
  void integrate_span(const Vec6& tau, double duration);
  double spring(int i, double stretch) const;
  /// The amplifiers' output after s more seconds of command u, from their state now.
  Vec6 amplifier(const Vec6& u, double s) const;
  /// The amplifiers' currents for their output amp (each as the torque it gives, joint-referred): their
  /// current limit, gain error and offset; zero while disabled.
  Vec6 currents(const Vec6& amp) const;

  PlantConfig cfg_;
  bool ideal_;
  ArticulatedBody body_;                  // ideal: the model; else the armature of the rigid joints (none if coupled)
  ArticulatedBody links_;                 // the links alone (no armature): inertia, bias, the coupled solve
  osc::FrictionParams<double> friction_;  // the true friction, model (2) (the kernels' friction_torque)
  Vec6 q_ = Vec6::Zero(), qd_ = Vec6::Zero();
  double t_ = 0;
  bool braked_ = false;
  bool amplifiers_on_ = true;
  mutable long evaluations_ = 0;

  // Drive train (ideal_ false).
  bool coupled_ = false, elastic_[6] = {}, sign_sensitive_[6] = {};
  Mat6 c_inv_ = Mat6::Identity(), c_inv_t_ = Mat6::Identity();
  // The rigid joints' armature, C^-T diag(G^2 Jm) C^-1 (zero on elastic joints); every channel's.
  Mat6 armature_rigid_ = Mat6::Zero(), armature_all_ = Mat6::Zero();
  Vec6 motor_inertia_ = Vec6::Zero();  // G^2 Jm, joint-referred
  Vec6 stiffness_ = Vec6::Zero();
  Vec6 limit_ = Vec6::Zero();                    // current limits, joint-referred
  double half_band_ = 0;                         // backlash / 2
  Vec6 th_ = Vec6::Zero(), thd_ = Vec6::Zero();  // elastic joints' motors
  Vec6 amp_ = Vec6::Zero();                      // the amplifiers' output (with amp_lag)
  Vec6 cmd_ = Vec6::Zero();                      // the last command

  // The contact.
  Contact contact_;
  int contact_phase_ = 0;      // 0 before its start, 1 acting, 2 after a pulse
  double wall_plane_ = 0;      // direction . p on the wall's surface [m]
  double peak_contact_ = 0;    // [N]
  double first_contact_ = -1;  // [s]
  osc::Model<double> kin_model_ = osc::Model<double>::of(osc::robot::kArm);  // the tip's kinematics
  mutable osc::Data<double> kin_;
};

}  // namespace sim
