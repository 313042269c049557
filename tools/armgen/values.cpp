// The sheet's numbers (expressions), the header's printing of doubles, and the frame arithmetic
// with its snapping rules.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "armgen.hpp"

namespace armgen {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// a op b in C++ text: when both are integers (literals or their sums and products), the left one
/// is written as a double literal ("150.0 / 101"), so that C++ never divides (or multiplies into an
/// overflow) in integers where the generator computed in doubles.
Value binary(double v, const Value& a, const char* op, const Value& b) {
  Value r{v, (a.integer && b.integer ? as_double(a.text) : a.text) + " " + op + " " + b.text, false};
  return r;
}

/// A recursive-descent parser of expr := term {(+|-) term}; term := unary {(*|/) unary};
/// unary := - unary | primary; primary := number | pi | ( expr ). It evaluates as C++ does (the
/// same operations in the same order, each rounded once) and rebuilds the text.
class Parser {
 public:
  Parser(const std::string& src, const std::string& where) : s_(src), where_(where) {}

  Value parse() {
    Value v = expr();
    skip();
    if (i_ != s_.size()) fail("unexpected '" + s_.substr(i_) + "'");
    if (!std::isfinite(v.v)) throw Error("not_finite", where_ + ": " + s_ + " is not a finite number");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw Error("sheet_value", where_ + ": cannot read \"" + s_ + "\" as a number or expression (" + what + ")");
  }
  void skip() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t')) ++i_;
  }
  bool take(char c) {
    skip();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  Value expr() {
    Value a = term();
    for (;;) {
      if (take('+')) {
        const Value b = term();
        a = binary(a.v + b.v, a, "+", b);
      } else if (take('-')) {
        const Value b = term();
        a = binary(a.v - b.v, a, "-", b);
      } else {
        return a;
      }
    }
  }
  Value term() {
    Value a = unary();
    for (;;) {
      if (take('*')) {
        const Value b = unary();
        a = binary(a.v * b.v, a, "*", b);
      } else if (take('/')) {
        const Value b = unary();
        a = binary(a.v / b.v, a, "/", b);
      } else {
        return a;
      }
    }
  }
  Value unary() {
    if (take('-')) {
      const Value a = unary();
      return {-a.v, a.text[0] == '-' ? "-(" + a.text + ")" : "-" + a.text, a.simple && a.text[0] != '-', a.integer};
    }
    return primary();
  }
  Value primary() {
    skip();
    if (take('(')) {
      const Value a = expr();
      if (!take(')')) fail("missing ')'");
      return {a.v, "(" + a.text + ")", false, a.integer};
    }
    if (s_.compare(i_, 2, "pi") == 0) {
      i_ += 2;
      return {kPi, "kPi", true};
    }
    const char* begin = s_.c_str() + i_;
    if (i_ >= s_.size() || !(std::isdigit(static_cast<unsigned char>(*begin)) || *begin == '.')) fail("a number");
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    if (end == begin) fail("a number");
    i_ += static_cast<std::size_t>(end - begin);
    if (!std::isfinite(v)) throw Error("not_finite", where_ + ": " + s_ + " is not a finite number");
    const std::string text = number(v);
    return {v, text, true, as_double(text) != text};
  }

  std::string s_, where_;
  std::size_t i_ = 0;
};

}  // namespace

Value parse_value(const std::string& src, const std::string& where) {
  std::string lower;
  for (char c : src)
    if (c != ' ') lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* special : {".nan", "nan", ".inf", "inf", "+.inf", "-.inf", "-inf", "+inf"})
    if (lower == special) throw Error("not_finite", where + ": " + src + " is not a finite number");
  return Parser(src, where).parse();
}

std::string as_double(const std::string& text) {
  const std::size_t digits = text[0] == '-' ? 1 : 0;
  if (text.size() > digits && text.find_first_not_of("0123456789", digits) == std::string::npos) return text + ".0";
  return text;
}

std::string number(double v) {
  if (v == 0) return "0";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.15g", v);
  return buf;
}

std::string angle(double v) {
  const double d = std::round(v * 180 / kPi);
  if (std::abs(v - d * kPi / 180) > 1e-12) return number(v);
  if (d == 0) return "0";
  return number(d) + " * kPi / 180";
}

Mat3 snap_rotation(const Mat3& R) {
  Mat3 S = R;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (double target : {0.0, 1.0, -1.0})
        if (std::abs(S(i, j) - target) <= 1e-12) S(i, j) = target;
  return S;
}

Vec3 snap_translation(const Vec3& p) {
  Vec3 s = p;
  for (int i = 0; i < 3; ++i)
    if (std::abs(s(i)) <= 1e-15) s(i) = 0;
  return s;
}

Frame compose(const Frame& a, const Frame& b) { return {snap_rotation(a.R * b.R), snap_translation(a.R * b.p + a.p)}; }

Frame inverse(const Frame& a) {
  const Mat3 Rt = a.R.transpose();
  return {Rt, snap_translation(-(Rt * a.p))};
}

Mat3 rpy_rotation(double roll, double pitch, double yaw) {
  const Mat3 Rx = snap_rotation(
      (Mat3() << 1, 0, 0, 0, std::cos(roll), -std::sin(roll), 0, std::sin(roll), std::cos(roll)).finished());
  const Mat3 Ry = snap_rotation(
      (Mat3() << std::cos(pitch), 0, std::sin(pitch), 0, 1, 0, -std::sin(pitch), 0, std::cos(pitch)).finished());
  const Mat3 Rz =
      snap_rotation((Mat3() << std::cos(yaw), -std::sin(yaw), 0, std::sin(yaw), std::cos(yaw), 0, 0, 0, 1).finished());
  return snap_rotation(Rz * Ry * Rx);
}

}  // namespace armgen
