// Link frames built from fuzz input, for the targets that feed the PIL parser well-formed frames.
#pragma once

#include <cstdint>
#include <cstring>

#include "fuzz_util.hpp"
#include "osc/link/frames.hpp"

namespace fuzz {

inline void fill(Input& in, std::uint8_t& v) { v = in.u8(); }
inline void fill(Input& in, std::int16_t& v) { v = static_cast<std::int16_t>(in.u16()); }
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

/// Encodes a frame of the given type whose every field comes from the input, in the order of the
/// frame's field list (osc/link/frames.hpp), into buf (kMaxFrame bytes); returns its length (0 for
/// a type outside OSC_FRAME_LIST).
inline int build_frame_of(fuzz::Input& in, pil::FrameType frame_type, std::uint8_t* buf) {
#define OSC_FUZZ_FILL(type, name, extent, unit, doc) fill(in, f.name);
#define OSC_FUZZ_BUILD(Name, code, name, from, when, FIELDS) \
  case pil::k##Name##Frame: {                                \
    pil::Name##Frame f;                                      \
    FIELDS(OSC_FUZZ_FILL)                                    \
    return pil::encode(f, buf);                              \
  }
  switch (frame_type) { OSC_FRAME_LIST(OSC_FUZZ_BUILD) }
#undef OSC_FUZZ_BUILD
#undef OSC_FUZZ_FILL
  return 0;
}

/// A sensor or an actuator frame (build_frame_of).
inline int build_frame(fuzz::Input& in, bool actuator, std::uint8_t* buf) {
  return build_frame_of(in, actuator ? pil::kActuatorFrame : pil::kSensorFrame, buf);
}

}  // namespace fuzz
