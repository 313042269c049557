#include "injection.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace sim {
namespace {}  // namespace

const char* syntax(InjectionForm f) {
  switch (f) {
    case InjectionForm::kJoint:
      return "[:JOINT]";
    case InjectionForm::kForce:
      return ":DIR:NEWTONS[:SECONDS]";
    case InjectionForm::kWall:
      return ":DIR:MM[:N_PER_M]";
    default:
      return "";
  }
}

namespace {

std::string kinds() {
  std::string s;
  for (int k = 0; k < kInjectionKindCount; ++k)
    s += std::string(k ? ", " : " ") + kInjections[k].name + syntax(kInjections[k].form);
  std::string dirs;
  for (const char* d : kDirections) dirs += std::string(dirs.empty() ? "" : " ") + d;
  return s + "; JOINT 1 to 6; DIR one of " + dirs + ")";
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out(1);
  for (char c : s)
    if (c == sep)
      out.emplace_back();
    else
      out.back() += c;
  return out;
}

/// The whole of text as a finite number (no trailing junk).
bool finite_number(const std::string& text, double& x) {
  char* end = nullptr;
  x = std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0' && std::isfinite(x);
}

/// The shortest text that reads back as x, without an exponent where it fits ("100000", not "1e+05").
std::string shortest(double x) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::fixed);
  if (r.ec != std::errc()) r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

bool parse_joint(const std::vector<std::string>& f, Injection& inj, std::string& err) {
  if (f.size() == 1) return true;
  const std::string& joint = f[1];
  if (f.size() > 2 || joint.size() != 1 || joint[0] < '1' || joint[0] > '6')
    return err = "--inject: joint must be 1 to 6, got '" + joint + (f.size() > 2 ? ":" + f[2] : "") + "'", false;
  inj.joint = joint[0] - '1';
  return true;
}

/// DIR:NEWTONS[:SECONDS] or DIR:MM[:N_PER_M] (f[0] is the kind).
bool parse_contact(const std::vector<std::string>& f, Injection& inj, std::string& err) {
  const bool wall = inj.kind == InjectionKind::kWall;
  const std::string what = std::string("--inject: ") + info(inj.kind).name + ": ";
  if (f.size() < 3)
    return err = what + "needs " + syntax(info(inj.kind).form) + " before @SECONDS, e.g. " +
                 (wall ? "wall:-z:5@1" : "collision:+z:50@1.5"),
           false;
  if (f.size() > 4) return err = what + "unexpected ':" + f[4] + "' after " + syntax(info(inj.kind).form), false;
  for (int d = 0; d < static_cast<int>(std::size(kDirections)); ++d)
    if (f[1] == kDirections[d]) inj.direction = d;
  if (inj.direction < 0) return err = what + "direction must be one of +x -x +y -y +z -z, got '" + f[1] + "'", false;
  double m = 0;
  if (!finite_number(f[2], m) || (wall ? m < 0 : m <= 0))
    return err = what +
                 (wall ? "distance must be a finite number of millimetres >= 0"
                       : "force must be a finite number of newtons > 0") +
                 ", got '" + f[2] + "'",
           false;
  inj.magnitude = m;
  if (f.size() < 4) return true;
  double x = 0;
  if (!finite_number(f[3], x) || x <= 0)
    return err = what +
                 (wall ? "stiffness must be a finite number of N/m > 0"
                       : "duration must be a finite number of seconds > 0") +
                 ", got '" + f[3] + "'",
           false;
  (wall ? inj.stiffness : inj.duration) = x;
  return true;
}

}  // namespace

bool parse_injection(const std::string& text, Injection& out, std::string& err) {
  const auto at = text.find('@');
  if (at == std::string::npos)
    return err = "--inject: expected KIND[:ARGS]@SECONDS (KIND one of" + kinds() + ", got '" + text + "'", false;
  const std::vector<std::string> f = split(text.substr(0, at), ':');
  const std::string when = text.substr(at + 1);
  Injection inj;
  int kind = -1;
  for (int k = 0; k < kInjectionKindCount; ++k)
    if (f[0] == kInjections[k].name) kind = k;
  if (kind < 0) return err = "--inject: unknown kind '" + f[0] + "' (one of" + kinds(), false;
  inj.kind = static_cast<InjectionKind>(kind);
  switch (kInjections[kind].form) {
    case InjectionForm::kNone:
      if (f.size() > 1) return err = "--inject: " + f[0] + " takes no joint", false;
      break;
    case InjectionForm::kJoint:
      if (!parse_joint(f, inj, err)) return false;
      break;
    default:
      if (!parse_contact(f, inj, err)) return false;
  }
  double t = 0;
  if (!finite_number(when, t) || t < 0)
    return err = "--inject: time must be a finite number of seconds >= 0, got '" + when + "'", false;
  inj.at = t;
  inj.enabled = true;
  out = inj;
  return true;
}

std::string to_string(const Injection& inj) {
  std::string s = info(inj.kind).name;
  if (inj.joint >= 0) s += ':' + std::to_string(inj.joint + 1);
  if (inj.contact()) {
    s += std::string(":") + kDirections[inj.direction] + ':' + shortest(inj.magnitude);
    if (inj.kind == InjectionKind::kCollision && inj.duration >= 0) s += ':' + shortest(inj.duration);
    if (inj.kind == InjectionKind::kWall && inj.stiffness > 0) s += ':' + shortest(inj.stiffness);
  }
  return s + '@' + shortest(inj.at);
}

std::string inject_help() {
  std::string kinds;
  for (const InjectionInfo& k : kInjections) kinds += std::string(kinds.empty() ? "" : " | ") + k.name + syntax(k.form);
  return "inject a fault of the simulated hardware, or a contact at the tip, at S seconds: " + kinds +
         " (JOINT 1..6, default every joint; DIR +x -x +y -y +z -z, base frame; docs/safety.md)";
}

}  // namespace sim
