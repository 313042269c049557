#include "injection.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace sim {

bool parse_injection(const std::string& text, Injection& out, std::string& err) {
  const std::string usage = "--inject: expected KIND[:JOINT]@SECONDS (KIND one of";
  auto kinds = [] {
    std::string s;
    for (int k = 0; k < kInjectionKindCount; ++k) s += std::string(k ? ", " : " ") + kInjections[k].name;
    return s + "; JOINT 1 to 6)";
  };
  const auto at = text.find('@');
  if (at == std::string::npos) return err = usage + kinds() + ", got '" + text + "'", false;
  std::string head = text.substr(0, at);
  const std::string when = text.substr(at + 1);
  std::string joint;
  if (const auto colon = head.find(':'); colon != std::string::npos) {
    joint = head.substr(colon + 1);
    head.resize(colon);
  }
  Injection inj;
  int kind = -1;
  for (int k = 0; k < kInjectionKindCount; ++k)
    if (head == kInjections[k].name) kind = k;
  if (kind < 0) return err = "--inject: unknown kind '" + head + "' (one of" + kinds(), false;
  inj.kind = static_cast<InjectionKind>(kind);
  if (!joint.empty() || text.find(':') != std::string::npos) {
    if (!kInjections[kind].per_joint) return err = "--inject: " + head + " takes no joint", false;
    if (joint.size() != 1 || joint[0] < '1' || joint[0] > '6')
      return err = "--inject: joint must be 1 to 6, got '" + joint + "'", false;
    inj.joint = joint[0] - '1';
  }
  char* end = nullptr;
  const double t = std::strtod(when.c_str(), &end);
  if (when.empty() || *end != '\0' || !std::isfinite(t) || t < 0)
    return err = "--inject: time must be a finite number of seconds >= 0, got '" + when + "'", false;
  inj.at = t;
  inj.enabled = true;
  out = inj;
  return true;
}

std::string to_string(const Injection& inj) {
  std::ostringstream os;
  os << info(inj.kind).name;
  if (inj.joint >= 0) os << ':' << inj.joint + 1;
  os << '@' << inj.at;
  return os.str();
}

}  // namespace sim
