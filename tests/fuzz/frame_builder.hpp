// Link frames built from fuzz input, for the targets that feed the PIL parser well-formed frames.
#pragma once

#include <cstdint>
#include <cstring>

#include "fuzz_util.hpp"
#include "osc/link/frames.hpp"

namespace fuzz {

/// Encodes a sensor or actuator frame whose every field comes from the input (floats as raw bits,
/// NaNs included) into buf (kMaxFrame bytes); returns its length.
inline int build_frame(fuzz::Input& in, bool actuator, std::uint8_t* buf) {
  if (!actuator) {
    pil::SensorFrame s;
    s.seq = in.u32();
    for (auto& c : s.counts) c = in.i32();
    s.inject = in.u8();
    return pil::encode(s, buf);
  }
  pil::ActuatorFrame a;
  a.seq = in.u32();
  for (auto& c : a.codes) c = in.i32();
  a.faults = in.u32();
  a.state = in.u8();
  a.step_cycles = in.u32();
  a.max_cycles = in.u32();
  a.mean_cycles = in.u32();
  a.tick_max_cycles = in.u32();
  a.stack_used = in.u32();
  auto f32 = [&] {
    const std::uint32_t u = in.u32();
    float v;
    std::memcpy(&v, &u, 4);
    return v;
  };
  for (float& v : a.theta_hat) v = f32();
  for (float& v : a.tau_f_hat) v = f32();
  return pil::encode(a, buf);
}

}  // namespace fuzz
