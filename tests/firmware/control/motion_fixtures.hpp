// What the tests of the motion generator and its moves share (test_motion.cpp,
// test_cartesian_move.cpp): a pose from a position and roll, pitch, yaw; the angular velocity of a
// reference; the trace of a generator's run of ticks and the check of its limits.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "osc/control/motion.hpp"

namespace osc::test {

constexpr std::uint32_t kHz = params::kControlHz;

inline Pose<double> pose(double x, double y, double z, const Vec3<double>& rpy) {
  return {Vec3<double>(x, y, z), rpy_rotation<double>(rpy)};
}

/// The base angular velocity and acceleration of a reference in orientation coordinates:
/// w = E(phi) phi_dot (E^{-1} inverted numerically: an independent path from the one at() takes).
inline Vec3<double> angular_velocity(const Desired<double>& d) {
  const Mat3<double> Einv = angular_to_phi_rate<double>(d.x.tail<3>());
  return Einv.inverse() * d.xd.tail<3>();
}

/// What a reference did over a run of ticks.
struct Trace {
  double v = 0, a = 0, j = 0, w = 0, wd = 0;  // peak linear speed, acceleration, jerk; angular speed, acceleration
  double jump = 0;                            // largest change of x, xd, xdd in one tick beyond what the limits allow
  double off_line = 0;                        // largest distance from the line p0 -> p1
  double derivative = 0;                      // largest mismatch of x, xd with the trapezoidal integrals of xd, xdd
  int finished = 0, stopped = 0;              // events
  std::vector<std::uint32_t> done;            // the ids of the moves done, in order
  int ticks = 0;
  Desired<double> last{};
};

/// Runs the generator from tick t0 for n ticks (or until an event when until_event), recording the
/// reference's peaks; jerk from the difference of accelerations.
template <class S>
Trace run(MotionGenerator<S>& g, std::uint64_t t0, int n, bool until_event, const Vec3<double>* line = nullptr) {
  Trace tr;
  Desired<double> prev{Vec6<double>::Zero(), Vec6<double>::Zero(), Vec6<double>::Zero()};
  Vec3<double> w_prev = Vec3<double>::Zero();
  for (int i = 0; i < n; ++i) {
    MotionEvents ev;
    const Desired<S> ds = g.at_tick(t0 + i, kHz, ev);
    Desired<double> d{ds.x.template cast<double>(), ds.xd.template cast<double>(), ds.xdd.template cast<double>()};
    tr.v = std::max(tr.v, d.xd.head<3>().norm());
    tr.a = std::max(tr.a, d.xdd.head<3>().norm());
    const Vec3<double> w = angular_velocity(d);
    tr.w = std::max(tr.w, w.norm());
    if (i > 0) {
      tr.j = std::max(tr.j, (d.xdd.head<3>() - prev.xdd.head<3>()).norm() * kHz);
      tr.wd = std::max(tr.wd, (w - w_prev).norm() * kHz);
      // Continuity: the position moves by at most v dt, the velocity by at most a dt (plus slack).
      tr.jump = std::max(tr.jump, (d.x.head<3>() - prev.x.head<3>()).norm() - 1.01 * params::kMoveLinear[0] / kHz);
      tr.jump = std::max(tr.jump, (d.xd.head<3>() - prev.xd.head<3>()).norm() - 1.01 * params::kMoveLinear[1] / kHz);
      // xd and xdd are the derivatives of x and xd: the trapezoidal rule over one tick errs by at most
      // j dt / 8 where the jerk switches inside it (3e-4 at 2.5 m/s^3, 1.25e-3 at 10 rad/s^3).
      tr.derivative = std::max(tr.derivative, ((d.x - prev.x) * kHz - (d.xd + prev.xd) / 2).cwiseAbs().maxCoeff());
      tr.derivative = std::max(tr.derivative, ((d.xd - prev.xd) * kHz - (d.xdd + prev.xdd) / 2).cwiseAbs().maxCoeff());
    }
    if (line) {
      const Vec3<double> r = d.x.head<3>() - line[0], u = (line[1] - line[0]).normalized();
      tr.off_line = std::max(tr.off_line, (r - u * r.dot(u)).norm());
    }
    tr.finished += ev.finished, tr.stopped += ev.stopped;
    if (ev.done_id != 0) tr.done.push_back(ev.done_id);
    prev = d, w_prev = w;
    tr.last = d;
    ++tr.ticks;
    if (until_event && (ev.finished || ev.stopped)) break;
  }
  return tr;
}

const CartesianLimits<double> kLim = CartesianLimits<double>::defaults();

inline void expect_within_limits(const Trace& tr, double slack = 1e-9) {
  EXPECT_LE(tr.v, params::kMoveLinear[0] * (1 + slack));
  EXPECT_LE(tr.a, params::kMoveLinear[1] * (1 + slack));
  EXPECT_LE(tr.j, params::kMoveLinear[2] * (1 + 1e-6));  // a difference quotient of a piecewise-linear a
  EXPECT_LE(tr.w, params::kMoveAngular[0] * (1 + 1e-6));
  EXPECT_LE(tr.wd, params::kMoveAngular[1] * (1 + 1e-3));
  EXPECT_LE(tr.jump, 0.0);
  EXPECT_LE(tr.derivative, 0.25 * params::kMoveAngular[2] / kHz);
}

}  // namespace osc::test
