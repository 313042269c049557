// A link frame as JSON, its keys the names of the frame's field list (OSC_SENSOR_FIELDS,
// OSC_ACTUATOR_FIELDS in osc/link/frames.hpp), in wire order: a field added to the list appears
// here by itself. Arrays stay arrays; the link counters are an object keyed by the error names.
#pragma once

#include <nlohmann/json.hpp>
#include <type_traits>

#include "osc/link/frames.hpp"

namespace sim {

namespace detail {
inline nlohmann::ordered_json field_json(const pil::LinkCounters& c) {
  nlohmann::ordered_json j;
  for (int k = 0; k < pil::kLinkErrorKinds; ++k) j[pil::kLinkErrorNames[k]] = c.count[k];
  return j;
}
template <class T>
nlohmann::ordered_json field_json(const T& v) {
  if constexpr (std::is_array_v<T>) {
    nlohmann::ordered_json a = nlohmann::ordered_json::array();
    for (const auto& x : v) a.push_back(x);
    return a;
  } else {
    return v;
  }
}
}  // namespace detail

template <class Frame>
nlohmann::ordered_json frame_json(const Frame& f) {
  nlohmann::ordered_json j;
  pil::for_each_field(f, [&j](const char* name, const auto& value) { j[name] = detail::field_json(value); });
  return j;
}

}  // namespace sim
