// Fault injection into the simulated hardware (encoders, amplifiers, timer, E-stop input): one fault
// of a named kind, on one joint or all, from a given time. The firmware sees it only through its
// HAL, exactly as it would see the real fault; puma_experiment --inject KIND[:JOINT]@SECONDS.
#pragma once

#include <cstdint>
#include <string>

namespace sim {

// X(Name, "name", joint-specific, what the hardware does from the injection time on)
#define SIM_INJECTION_LIST(X)                                                                                        \
  X(EncoderStuck, "encoder-stuck", true, "the encoder reading freezes at its value at the injection time")           \
  X(EncoderJump, "encoder-jump", true, "the reading jumps by ten times the largest plausible step and stays offset") \
  X(EncoderGarbage, "encoder-garbage", true, "the reading is INT32_MAX (far outside the joint range)")               \
  X(EncoderNoise, "encoder-noise", true, "a 50 ms burst of uniform noise of +-1 plausible step on the reading")      \
  X(DacStuck, "dac-stuck", true, "the amplifier holds the DAC code it had at the injection time")                    \
  X(Overrun, "overrun", false, "the control tick at the injection time takes three periods")                         \
  X(Estop, "estop", false, "the emergency-stop input becomes active and stays active")

enum class InjectionKind : std::uint8_t {
#define SIM_INJECTION_ENUM(Name, name, per_joint, doc) k##Name,
  SIM_INJECTION_LIST(SIM_INJECTION_ENUM)
#undef SIM_INJECTION_ENUM
};

struct InjectionInfo {
  const char* name;
  bool per_joint;  ///< takes an optional :JOINT (default: every joint)
  const char* doc;
};
inline constexpr InjectionInfo kInjections[] = {
#define SIM_INJECTION_INFO(Name, name, per_joint, doc) {name, per_joint, doc},
    SIM_INJECTION_LIST(SIM_INJECTION_INFO)
#undef SIM_INJECTION_INFO
};
inline constexpr int kInjectionKindCount = static_cast<int>(sizeof(kInjections) / sizeof(kInjections[0]));

inline const InjectionInfo& info(InjectionKind k) { return kInjections[static_cast<int>(k)]; }

/// One injected fault. joint: 0-based, or -1 for every joint (per-joint kinds) / not applicable.
struct Injection {
  bool enabled = false;
  InjectionKind kind = InjectionKind::kEncoderStuck;
  int joint = -1;
  double at = 0;  ///< [s] of simulated time
  bool hits(int j) const { return joint < 0 || joint == j; }
};

/// Parses KIND[:JOINT]@SECONDS (joints 1 to 6, SECONDS >= 0 and finite); on failure fills err.
bool parse_injection(const std::string& text, Injection& out, std::string& err);

/// "encoder-stuck:3@12.5" (the form parse_injection reads).
std::string to_string(const Injection& inj);

}  // namespace sim
