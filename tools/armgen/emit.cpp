// The generated header: data and static_asserts over arm.hpp's generic functions. The rules for
// its numbers are in its banner (kRules below).
#include <cctype>
#include <sstream>
#include <string>
#include <vector>

#include "armgen.hpp"

namespace armgen {

namespace {

constexpr int kWidth = 118;

const char* const kRules =
    "The numbers: each double of the URDF and of the conversion is printed with 15 significant digits (the "
    "descriptions' numbers have fewer: the last-bit noise of the frame conversions goes); a rotation entry within "
    "1e-12 of 0 or +-1 is that value exactly (quarter-turn rpy give signed permutations, the kernels' fast path), a "
    "translation or centre-of-mass coordinate within 1e-15 of 0 is 0, an inertia entry within 1e-12 of the tensor's "
    "largest is 0; a joint limit within 1e-12 rad of a whole number d of degrees is written d * kPi / 180; the "
    "sheet's expressions (numbers, pi, + - * /) are copied as the sheet writes them (pi as kPi); a placement that "
    "is a standard DH row Tz(d) Tx(a) Rx(alpha) is written dh_placement(a, d, alpha).";

/// `text` as comment lines: `prefix` before each, words wrapped at kWidth; the text's own line
/// breaks kept, a line starting "- " a bullet whose wrapped lines are indented.
void comment(std::ostream& o, const std::string& prefix, const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    while (!line.empty() && line.back() == ' ') line.pop_back();
    if (line.empty()) {
      std::string p = prefix;
      while (!p.empty() && p.back() == ' ') p.pop_back();
      o << p << "\n";
      continue;
    }
    const bool bullet = line.rfind("- ", 0) == 0;
    std::istringstream words(line);
    std::string word, current = prefix;
    bool first = true;
    while (words >> word) {
      if (!first && current.size() + 1 + word.size() > static_cast<std::size_t>(kWidth)) {
        o << current << "\n";
        current = prefix + (bullet ? "  " : "");
        first = true;
      }
      current += (first ? "" : " ") + word;
      first = false;
    }
    o << current << "\n";
  }
}

/// A group's comment: what it is, then its source and estimate.
void group(std::ostream& o, const std::string& prefix, const std::string& what, const Text& t) {
  std::string text = what;
  for (const auto& [label, body] : {std::pair{"Source: ", &t.source}, std::pair{"Estimate: ", &t.estimate}}) {
    if (body->empty()) continue;
    if (!text.empty()) text += '\n';
    text.append(label).append(body->rfind("- ", 0) == 0 ? "\n" : "").append(*body);
  }
  comment(o, prefix, text);
}

std::string six(const Six& v) {
  std::string s = "{";
  for (int i = 0; i < 6; ++i) s += (i ? ", " : "") + v[i].text;
  return s + "}";
}

std::string paren(const Value& v) { return v.simple ? v.text : "(" + v.text + ")"; }

std::string absolute(const Value& v) {
  if (v.simple) return v.text[0] == '-' ? v.text.substr(1) : v.text;
  return "abs_of(" + v.text + ")";
}

std::string cstr(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c == '\n' ? ' ' : c;
  }
  return out + "\"";
}

std::string camel(const std::string& name) {
  std::string out;
  bool up = true;
  for (char c : name) {
    if (c == '_') {
      up = true;
      continue;
    }
    out += up ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
    up = false;
  }
  return out;
}

std::string placement(const Frame& P, bool identity_name) {
  const Mat3& R = P.R;
  if (identity_name && R == Mat3::Identity() && P.p == Vec3::Zero()) return "kIdentityPlacement";
  if (P.p(1) == 0 && R(0, 0) == 1 && R(0, 1) == 0 && R(0, 2) == 0 && R(1, 0) == 0 && R(2, 0) == 0 &&
      R(1, 2) == -R(2, 1) && R(2, 2) == R(1, 1)) {
    const double c = R(1, 1), s = R(2, 1);
    const char* alpha = c == 1 && s == 0    ? "0"
                        : c == 0 && s == 1  ? "kPi / 2"
                        : c == -1 && s == 0 ? "kPi"
                        : c == 0 && s == -1 ? "-kPi / 2"
                                            : nullptr;
    if (alpha) return "dh_placement(" + number(P.p(0)) + ", " + number(P.p(2)) + ", " + alpha + ")";
  }
  std::string s = "{{";
  for (int r = 0; r < 3; ++r)
    s += std::string(r ? ", " : "") + "{" + number(R(r, 0)) + ", " + number(R(r, 1)) + ", " + number(R(r, 2)) + "}";
  return s + "}, {" + number(P.p(0)) + ", " + number(P.p(1)) + ", " + number(P.p(2)) + "}}";
}

void emit_arm(std::ostream& o, const Sheet& s, const Chain& c) {
  const std::string jm = "kMotorInertia" + camel(s.motor_sets[0].name);
  for (const MotorSet& m : s.motor_sets) {
    group(o, "/// ",
          "Motor inertias [kg m^2], motor side: set \"" + m.name + "\"" +
              (&m == &s.motor_sets[0] ? " (the model's: kArm)" : "") + ".",
          m.text);
    o << "inline constexpr MotorInertias kMotorInertia" << camel(m.name) << " = {" << cstr(m.name) << ", " << six(m.jm)
      << "};\n";
  }
  o << "/// The model's set (the first).\n";
  o << "inline constexpr const MotorInertias& kMotorInertiaModel = " << jm << ";\n";
  if (!s.motor_text.source.empty() || !s.motor_text.estimate.empty()) group(o, "/// ", "Motor inertias:", s.motor_text);
  o << "\n";
  group(o, "/// ",
        "The arm, from " + c.root + " (the base frame) to " + c.joints[5].child + ": kinematics and inertia.",
        s.kinematics);
  group(o, "/// ", "Gear ratios G (signed, motor turns per joint turn).", s.gear_text);
  group(o, "/// ", "Gravity [m/s^2], along -z of the base frame.", s.gravity_text);
  o << "constexpr ArmDescription kArm = {\n    " << cstr(s.name) << ",\n    " << placement(c.base, true)
    << ",\n    {\n";
  for (int i = 0; i < 6; ++i) {
    const Inertial& L = c.link[i];
    const Joint& j = c.joints[i];
    o << "        // " << j.child << " (joint " << j.name << (j.continuous ? ", continuous: limits +-2 pi" : "")
      << ")\n";
    const auto ex = s.inertial_exceptions.find(j.child);
    if (ex != s.inertial_exceptions.end()) group(o, "        // ", "Its inertial is no body's:", ex->second);
    o << "        {" << placement(c.placement[i], false) << ", " << number(L.mass) << ", {" << number(L.com(0)) << ", "
      << number(L.com(1)) << ", " << number(L.com(2)) << "}, {" << number(L.inertia(0, 0)) << ", "
      << number(L.inertia(1, 1)) << ", " << number(L.inertia(2, 2)) << ", " << number(L.inertia(0, 1)) << ", "
      << number(L.inertia(0, 2)) << ", " << number(L.inertia(1, 2)) << "}, " << jm << ".jm[" << i << "], "
      << s.gear[i].text << "},\n";
  }
  o << "    },\n    " << s.gravity.text << ",\n";
  group(o, "    // ", "Joint limits [rad] (the URDF's).", s.joint_limits);
  std::string lo = "{", hi = "{";
  for (int i = 0; i < 6; ++i) {
    lo.append(i ? ", " : "").append(angle(c.joints[i].lower));
    hi.append(i ? ", " : "").append(angle(c.joints[i].upper));
  }
  o << "    " << lo << "},\n    " << hi << "},\n};\n";
  bool spherical = true;
  for (int i = 3; i < 6; ++i)
    for (int k = 0; k < 3; ++k)
      if (c.placement[i].p(k) != 0 && !(i == 3 && k == 2)) spherical = false;
  if (spherical)
    o << "static_assert(has_spherical_wrist(kArm), \"the wrist axes meet at the frame-6 origin\");\n\n";
  else
    o << "static_assert(!has_spherical_wrist(kArm), \"the wrist axes do not meet at the frame-6 origin\");\n\n";

  group(o, "/// ",
        "The operational point (frame 6 of kArm) in the last moving link's URDF frame (" + c.joints[5].child +
            "), from " + c.tool_frame + ".",
        s.op_text);
  o << "constexpr Placement kToolOffset = " << placement(c.tool, true) << ";\n\n";
}

void emit_poses(std::ostream& o, const Sheet& s) {
  group(o, "/// ", "Start pose of the task [rad].", s.start_text);
  o << "constexpr double kQStart[kDof] = " << six(s.start.q) << ";\n";
  if (!s.named.empty()) group(o, "/// ", "Named poses [rad]:", s.named_text);
  for (const Pose& p : s.named)
    if (!p.symbol.empty())
      o << "constexpr double " << p.symbol << "[kDof] = " << six(p.q) << ";  // " << p.name << "\n";
  if (!s.reference.empty()) {
    group(o, "/// ", "Reference poses [rad] (not declarable, not held to the joint limits):", s.reference_text);
    for (const Pose& p : s.reference) {
      if (!p.doc.empty()) comment(o, "/// ", p.doc);
      o << "constexpr double " << p.symbol << "[kDof] = " << six(p.q) << ";\n";
    }
  }
  o << "/// The poses an operator may declare (declare_pose), in code order; the first is the start pose.\n"
    << "constexpr NamedPose kNamedPoses[] = {\n";
  std::vector<const Pose*> all{&s.start};
  for (const Pose& p : s.named) all.push_back(&p);
  for (const Pose* p : all) o << "    {" << cstr(p->name) << ", " << six(p->q) << ", " << cstr(p->doc) << "},\n";
  o << "};\n"
    << "constexpr int kNamedPoseCount = sizeof(kNamedPoses) / sizeof(*kNamedPoses);\n"
    << "/// The code of the named pose `name` (its index in kNamedPoses), or -1.\n"
    << "constexpr int named_pose_code(std::string_view name) { return find_named_pose(kNamedPoses, name); }\n"
    << "static_assert(named_poses_valid(kNamedPoses, kQStart, kArm),\n"
    << "              \"each named pose within the joint limits, the first the start pose, codes in a byte\");\n\n";
}

std::string encoder_counts(const Sheet& s, int i) {
  const Value& e = s.encoder[i];
  if (s.encoder_unit == "rad_per_count") return "1 / " + paren(e);
  if (s.encoder_unit == "counts_per_motor_rev")
    return as_double(paren(e)) + " * " + as_double(absolute(s.gear[i])) + " / (2 * kPi)";
  return as_double(paren(e)) + " / (2 * kPi)";
}

void emit_drives(std::ostream& o, const Sheet& s) {
  group(o, "/// ", "Drive electronics (kDrives): the model's encoders, counts per motor revolution.",
        s.model_encoder_text);
  group(o, "/// ", "DACs: bits, bipolar; full scale = these joint torques [N m].", s.dac_text);
  group(o, "/// ", "Plausible joint speeds [rad/s].", s.joint_speed_text);
  o << "constexpr DriveParams kDrives = {" << s.model_cpr.text << ", " << s.dac_bits << ", " << six(s.dac_full_scale)
    << ", " << six(s.joint_speed) << "};\n\n"
    << "/// The model's encoders (kDrives) on every motor shaft, each reading its own joint: the firmware's\n"
    << "/// default and the ideal plant's.\n"
    << "constexpr EncoderMap kEncodersUniform = uniform_encoders(\"uniform\", kArm, "
       "kDrives.encoder_counts_per_motor_rev);\n\n";

  o << "/// The arm's own drive train.\nconstexpr DriveTrain kDriveTrain = {\n";
  group(o, "    // ",
        "Encoders (" + s.encoder_unit + ", " + (s.absolute ? "absolute" : "incremental") + "):", s.encoder_text);
  o << "    {" << cstr(s.encoder_name) << ",\n     {";
  for (int i = 0; i < 6; ++i) o << (i ? ", " : "") << encoder_counts(s, i);
  o << "},\n     " << s.coupling.size() << ",\n     {";
  for (std::size_t k = 0; k < s.coupling.size(); ++k)
    o << (k ? ", " : "") << "{" << s.coupling[k].joint - 1 << ", " << s.coupling[k].motor - 1 << ", "
      << s.coupling[k].c.text << "}";
  o << "}},\n    " << (s.absolute ? "EncoderKind::kAbsolute" : "EncoderKind::kIncremental") << ",\n";
  o << "    kMotorInertia" << camel(s.motor_sets[s.motor_alt].name) << ",\n";
  group(o, "    // ", "Torque constants K_m [N m/A].", s.torque_constant_text);
  o << "    " << six(s.torque_constant) << ",\n";
  group(o, "    // ", "Motor torque limits [N m], motor side.", s.motor_torque_limit_text);
  o << "    " << six(s.motor_torque_limit) << ",\n";
  if (s.pots) {
    group(o, "    // ", "Potentiometers: ADC bits, joint angle at code 0 and at full scale [rad].", s.pot_text);
    o << "    " << s.pot_bits << ",\n    " << six(s.pot_min) << ",\n    " << six(s.pot_max) << ",\n";
  } else {
    o << "    // No potentiometers.\n    0,\n    {0, 0, 0, 0, 0, 0},\n    {0, 0, 0, 0, 0, 0},\n";
  }
  if (s.index) {
    group(o, "    // ", "Index pulses: the motor shaft's angle at its pulse [rad].", s.index_text);
    o << "    true,\n    " << six(s.index_angle) << ",\n";
  } else {
    o << "    // No index pulses.\n    false,\n    {0, 0, 0, 0, 0, 0},\n";
  }
  if (s.current) {
    group(o, "    // ",
          "Current monitors: ADC bits, span (times the DAC's full-scale current), gain error, offset (of the full "
          "scale) and noise (ADC codes, standard deviation) at most.",
          s.current_text);
    o << "    {" << s.current_bits << ", " << s.current_range.text << ", " << s.current_gain.text << ", "
      << s.current_offset.text << ", " << s.current_noise.text << "},\n";
  } else {
    o << "    // No current readback.\n    {0, 1, 0, 0, 0},\n";
  }
  o << "};\nstatic_assert(kDriveTrain.encoders.coupling_terms <= kMaxCouplingTerms);\n\n";
}

void emit_friction(std::ostream& o, const Sheet& s) {
  o << "/// Friction presets, model (2), link side.\n";
  bool first_motor = true;
  for (const FrictionPreset& f : s.friction) {
    const std::string sym = "kFriction" + camel(f.name);
    if (f.motor) {
      group(o, "/// ",
            "\"" + f.name + "\": motor-side viscous B and Coulomb Tc+, Tc-, referred to the link " +
                "(friction_from_motor).",
            f.text);
      o << "constexpr MotorFriction kMotorFriction" << camel(f.name) << " = {" << six(f.a) << ", " << six(f.b) << ", "
        << six(f.c) << "};\n";
      if (first_motor) {
        o << "/// The first motor-side preset's data by their own names.\n";
        for (const char* field : {"Viscous", "CoulombPos", "CoulombNeg"}) {
          const std::string member = field[0] == 'V' ? "viscous" : field[7] == 'P' ? "coulomb_pos" : "coulomb_neg";
          o << "inline constexpr const double (&kMotor" << field << ")[kDof] = kMotorFriction" << camel(f.name) << "."
            << member << ";\n";
        }
        first_motor = false;
      }
      o << "constexpr FrictionCoefficients " << sym << " = friction_from_motor(" << cstr(f.name) << ", kMotorFriction"
        << camel(f.name) << ", kArm);\n";
    } else {
      group(o, "/// ", "\"" + f.name + "\":", f.text);
      o << "constexpr FrictionCoefficients " << sym << " = {" << cstr(f.name) << ", " << six(f.a) << ", " << six(f.b)
        << ", " << six(f.c) << "};\n";
    }
  }
  o << "/// Every preset, for command lines and tests.\nconstexpr const FrictionCoefficients* kFrictionPresets[] = {";
  for (const FrictionPreset& f : s.friction) o << "&kFriction" << camel(f.name) << ", ";
  o << "&kFrictionNone};\n\n";

  group(o, "/// ",
        "The model's error bounds (docs/safety.md, \"The residual monitor\"): link inertia, amplifier gain, offset "
        "(of full scale), ripple, current-loop lag [s], encoder edge [counts], and the friction band.",
        s.bounds_text);
  o << "constexpr const FrictionCoefficients* kFrictionBandPresets[] = {";
  for (std::size_t k = 0; k < s.band.size(); ++k) o << (k ? ", " : "") << "&kFriction" << camel(s.band[k]);
  o << "};\nconstexpr ModelErrorBounds kModelErrorBounds = with_friction_band(\n    {" << s.link_inertia.text << ", "
    << s.amp_gain.text << ", " << s.amp_offset.text << ", " << s.ripple.text << ", " << s.amp_lag.text << ", "
    << s.encoder_edge.text << ", {\"band_lo\", {}, {}, {}}, {\"band_hi\", {}, {}, {}}},\n    kFrictionBandPresets, "
    << s.drift.text << ");\n\n";

  group(o, "/// ",
        "Cartesian maxima of the operational point's translation: velocity [m/s], acceleration [m/s^2], jerk [m/s^3]: "
        "a move's and a stream's configured maxima (params::kMoveLinear).",
        s.cart_text);
  o << "constexpr CartesianMaxima kCartesianMaxima = {" << s.cart_velocity.text << ", " << s.cart_acceleration.text
    << ", " << s.cart_jerk.text << "};\n\n";

  group(o, "/// ",
        "The rated payload at the flange (frame 6) [kg], the reach of its centre of mass in frame 6 (each "
        "coordinate) [m], and the largest principal moment of its inertia [kg m^2]: the runtime parameters "
        "payload_*'s ranges.",
        s.payload_text);
  o << "constexpr PayloadRating kPayloadRating = {" << s.payload_mass.text << ", " << s.payload_com_reach.text << ", "
    << s.payload_inertia.text << "};\n\n";
}

}  // namespace

std::string emit_header(const Sheet& s, const Chain& c, const std::string& sheet_name, const std::string& urdf_name) {
  std::ostringstream o;
  comment(o, "// ",
          s.name + ": the arm's constant table (osc/robots/arm.hpp's format), generated by tools/armgen from " +
              urdf_name + " (kinematics, inertia, joint limits) and " + sheet_name +
              " (drives, friction, poses, bounds; each group's source or estimate is copied here). "
              "Do not edit: change the description and regenerate with scripts/gen_arms.sh (the host "
              "build fails while this file differs from what its description generates).");
  if (!s.about.empty()) {
    o << "//\n";
    comment(o, "// ", s.about);
  }
  o << "//\n";
  comment(o, "// ", kRules);
  o << "#pragma once\n\n#include <string_view>\n\n#include \"osc/robots/arm.hpp\"\n\n// clang-format off\nnamespace "
       "osc::"
    << s.arm << " {\n\n";
  emit_arm(o, s, c);
  emit_poses(o, s);
  emit_drives(o, s);
  emit_friction(o, s);
  o << "}  // namespace osc::" << s.arm << "\n// clang-format on\n";
  return o.str();
}

}  // namespace armgen
