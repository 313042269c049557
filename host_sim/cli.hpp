// Strict command-line value parsing: a bad value is an error with a message, never a default.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace sim {

/// Parses a finite double in [lo, hi]; on failure fills err and returns false.
inline bool parse_number(const std::string& flag, const char* text, double lo, double hi, double& out,
                         std::string& err) {
  if (text == nullptr) {
    err = flag + " needs a value";
    return false;
  }
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0') {
    err = flag + ": '" + text + "' is not a number";
    return false;
  }
  if (!std::isfinite(v)) {
    err = flag + ": value must be finite, got '" + std::string(text) + "'";
    return false;
  }
  if (v < lo || v > hi) {
    char range[64];
    std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
    err = flag + ": " + text + " is out of range " + range;
    return false;
  }
  out = v;
  return true;
}

}  // namespace sim
