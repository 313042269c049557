// Desired trajectory (68): +-50 mm on each axis about the start position p0, period 5 s,
// envelope 1 - exp(-0.05 t^3) so that the desired velocity and acceleration start at zero.
// The orientation is held at its start value (phi_d = 0 relative to the start orientation).
#pragma once

#include "osc/kernels/model.hpp"
#include "osc/control/params.hpp"

namespace osc {

template <class S>
struct Desired {
  Vec6<S> x, xd, xdd;  // x_d, x_d dot, x_d double dot
};

/// Evaluates (68) and its analytic derivatives at time t (f = 1, see NOTES.md).
template <class S>
Desired<S> trajectory(const Vec3<S>& p0, S t) {
  const S A = lit<S>(params::kAmplitude), w = lit<S>(params::kOmega), c = lit<S>(params::kEnvelope);
  // Envelope s(t) and its derivatives.
  const S ex = math::exp(-c * t * t * t);
  const S s = S(1) - ex;
  const S sd = lit<S>(3) * c * t * t * ex;
  const S sdd = (lit<S>(6) * c * t - lit<S>(9) * c * c * t * t * t * t) * ex;
  const S sn = math::sin(w * t), cs = math::cos(w * t);
  // x: A sin(wt) s;  y, z: A cos(wt) s.
  const S px = A * sn * s, pxd = A * (w * cs * s + sn * sd), pxdd = A * (-w * w * sn * s + lit<S>(2) * w * cs * sd + sn * sdd);
  const S py = A * cs * s, pyd = A * (-w * sn * s + cs * sd), pydd = A * (-w * w * cs * s - lit<S>(2) * w * sn * sd + cs * sdd);
  Desired<S> d;
  d.x << p0(0) + px, p0(1) + py, p0(2) + py, S(0), S(0), S(0);
  d.xd << pxd, pyd, pyd, S(0), S(0), S(0);
  d.xdd << pxdd, pydd, pydd, S(0), S(0), S(0);
  return d;
}

}  // namespace osc
