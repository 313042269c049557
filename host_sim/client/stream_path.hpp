// A stream's path sampled for its setpoints: the rows of a path (t [s], x, y, z [m], roll, pitch,
// yaw [rad], as sim::read_stream_csv reads them) at any time, linearly between rows, with the
// path's velocity there (the slope of the row's segment: the wrist centre's velocity, and the
// angular velocity w = E(rpy) rpy_dot in the base frame, as a setpoint_velocity frame carries them).
// The clients (osc_client's Client::stream, oscctl) and the motion scripts (puma_experiment
// --motion) sample their streams here. Header-only.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "osc/kernels/kinematics.hpp"

namespace osc::client {

/// One setpoint of a stream: the wrist centre [m] and roll, pitch, yaw [rad] (base frame; offsets
/// with a relative stream), and the path's velocity there (linear [m/s], then angular [rad/s]; zero
/// at the path's end).
struct StreamPoint {
  Vec3<double> position = Vec3<double>::Zero();
  Vec3<double> rpy = Vec3<double>::Zero();
  Vec6<double> velocity = Vec6<double>::Zero();
};

/// The path at time t (rows non-empty, t increasing from row to row; `end`: t at or beyond the last
/// row, which then gives the point, at rest). `i` carries the segment from call to call (start at 1)
/// for times that increase.
inline StreamPoint path_at(const std::vector<std::array<double, 7>>& rows, double t, std::size_t& i, bool& end) {
  end = t >= rows.back()[0] - 1e-9;
  while (i < rows.size() && rows[i][0] < t) ++i;
  StreamPoint p;
  std::array<double, 7> x = rows.back();
  if (!end) {
    const std::array<double, 7>& a = rows[i - 1];
    const std::array<double, 7>& b = rows[i];
    const double dt = b[0] - a[0], f = (t - a[0]) / dt;
    for (int c = 1; c < 7; ++c) x[c] = a[c] + f * (b[c] - a[c]);
    Vec3<double> rate;
    for (int c = 0; c < 3; ++c) p.velocity(c) = (b[1 + c] - a[1 + c]) / dt, rate(c) = (b[4 + c] - a[4 + c]) / dt;
    p.velocity.tail<3>() = phi_rate_to_angular<double>(Vec3<double>(x[4], x[5], x[6])) * rate;
  }
  p.position = Vec3<double>(x[1], x[2], x[3]);
  p.rpy = Vec3<double>(x[4], x[5], x[6]);
  return p;
}

/// The path sampled every 1 / rate_hz s from t = 0 (path_at); the last sample is the path's end.
inline std::vector<StreamPoint> resample_path(const std::vector<std::array<double, 7>>& rows, double rate_hz) {
  std::vector<StreamPoint> out;
  if (rows.empty() || !(rate_hz > 0)) return out;
  std::size_t i = 1;
  for (long n = 0;; ++n) {
    bool end = false;
    out.push_back(path_at(rows, static_cast<double>(n) / rate_hz, i, end));
    if (end) return out;
  }
}

}  // namespace osc::client
