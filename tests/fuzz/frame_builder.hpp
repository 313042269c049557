// Link frames built from fuzz input, for the targets that feed the PIL parser well-formed frames.
#pragma once

#include <cstdint>
#include <cstring>

#include "fuzz_util.hpp"
#include "osc/link/frames.hpp"

namespace fuzz {

inline void fill(Input& in, std::uint8_t& v) { v = in.u8(); }
inline void fill(Input& in, std::uint32_t& v) { v = in.u32(); }
inline void fill(Input& in, std::int32_t& v) { v = in.i32(); }
inline void fill(Input& in, float& v) {  // raw bits: NaNs and infinities included
  const std::uint32_t u = in.u32();
  std::memcpy(&v, &u, 4);
}
template <class T, int N>
void fill(Input& in, T (&a)[N]) {
  for (T& v : a) fill(in, v);
}
inline void fill(Input& in, pil::LinkCounters& c) { fill(in, c.count); }

/// Encodes a sensor or actuator frame whose every field comes from the input, in the order of the
/// frame's field list (osc/link/frames.hpp), into buf (kMaxFrame bytes); returns its length.
inline int build_frame(fuzz::Input& in, bool actuator, std::uint8_t* buf) {
#define OSC_FUZZ_FILL(type, name, extent, unit, doc) fill(in, f.name);
  if (!actuator) {
    pil::SensorFrame f;
    OSC_SENSOR_FIELDS(OSC_FUZZ_FILL)
    return pil::encode(f, buf);
  }
  pil::ActuatorFrame f;
  OSC_ACTUATOR_FIELDS(OSC_FUZZ_FILL)
#undef OSC_FUZZ_FILL
  return pil::encode(f, buf);
}

}  // namespace fuzz
