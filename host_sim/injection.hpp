// Fault injection into the simulated hardware (encoders, DACs, amplifiers, timer, E-stop input) and
// contacts of the simulated arm with its surroundings: one injection of a named kind, on one joint or
// all, from a given time. The firmware sees it only through its HAL, exactly as it would see the real
// fault or contact; puma_experiment --inject KIND[:ARGS]@SECONDS.
#pragma once

#include <cstdint>
#include <string>

namespace sim {

/// What follows an injection's kind before its @SECONDS.
enum class InjectionForm : std::uint8_t {
  kNone,   ///< nothing
  kJoint,  ///< an optional :JOINT (default: every joint)
  kForce,  ///< :DIR:NEWTONS[:SECONDS]: a force on the tip, a step or a pulse of that length
  kWall,   ///< :DIR:MM[:N_PER_M]: a wall MM millimetres from the tip along DIR, of that stiffness
};

// X(Name, "name", form, qemu, what the hardware does from the injection time on). qemu: it acts on
// what a PIL run shares with the in-process one (the plant, the encoders, the amplifiers, their current
// monitors and fault lines: the sensor frame carries them), so --qemu takes it; overrun and estop act
// on the host-built task's clock and E-stop input.
#define SIM_INJECTION_LIST(X)                                                                                      \
  X(EncoderStuck, "encoder-stuck", kJoint, true, "the encoder reading freezes at its value at the injection time") \
  X(EncoderJump, "encoder-jump", kJoint, true,                                                                     \
    "the reading jumps by ten times the largest plausible step and stays offset")                                  \
  X(EncoderGarbage, "encoder-garbage", kJoint, true, "the reading is INT32_MAX (far outside the joint range)")     \
  X(EncoderNoise, "encoder-noise", kJoint, true,                                                                   \
    "a 50 ms burst of uniform noise of +-1 plausible step on the reading")                                         \
  X(DacStuck, "dac-stuck", kJoint, true, "the amplifier holds the DAC code it had at the injection time")          \
  X(DacZero, "dac-zero", kJoint, true, "the amplifier receives DAC code 0 whatever the controller writes")         \
  X(DacFull, "dac-full", kJoint, true, "the amplifier receives the positive full-scale DAC code")                  \
  X(AmpOff, "amp-off", kJoint, true, "the amplifier produces zero torque whatever code it receives")               \
  X(AmpFault, "amp-fault", kJoint, true, "the amplifier trips: zero torque, and its fault line reports it")        \
  X(CurrentStuck, "current-stuck", kJoint, true,                                                                   \
    "the current monitor's reading freezes at its value at the injection time")                                    \
  X(CurrentZero, "current-zero", kJoint, true, "the current monitor reads zero current whatever flows")            \
  X(CurrentGain, "current-gain", kJoint, true, "the current monitor reads half the current (its gain halved)")     \
  X(Overrun, "overrun", kNone, false, "the control tick at the injection time takes three periods")                \
  X(Estop, "estop", kNone, false, "the emergency-stop input becomes active and stays active")                      \
  X(Collision, "collision", kForce, true,                                                                          \
    "a force of NEWTONS along DIR on the tip (the wrist centre), for SECONDS or for good")                         \
  X(Wall, "wall", kWall, true,                                                                                     \
    "a stiff wall normal to DIR, MM millimetres from the tip along DIR, pushes back when the tip enters it")

enum class InjectionKind : std::uint8_t {
#define SIM_INJECTION_ENUM(Name, name, form, qemu, doc) k##Name,
  SIM_INJECTION_LIST(SIM_INJECTION_ENUM)
#undef SIM_INJECTION_ENUM
};

struct InjectionInfo {
  const char* name;
  InjectionForm form;
  bool qemu;  ///< puma_experiment --qemu takes it
  const char* doc;
};
inline constexpr InjectionInfo kInjections[] = {
#define SIM_INJECTION_INFO(Name, name, form, qemu, doc) {name, InjectionForm::form, qemu, doc},
    SIM_INJECTION_LIST(SIM_INJECTION_INFO)
#undef SIM_INJECTION_INFO
};
inline constexpr int kInjectionKindCount = static_cast<int>(sizeof(kInjections) / sizeof(kInjections[0]));

inline const InjectionInfo& info(InjectionKind k) { return kInjections[static_cast<int>(k)]; }

/// What a form takes after the kind: "[:JOINT]", ":DIR:NEWTONS[:SECONDS]", ...
const char* syntax(InjectionForm f);

/// The directions of a contact, in the base frame; index d is axis d / 2, negative when d is odd.
inline constexpr const char* kDirections[] = {"+x", "-x", "+y", "-y", "+z", "-z"};

/// One injection. joint: 0-based, or -1 for every joint (per-joint kinds) / not applicable.
struct Injection {
  bool enabled = false;
  InjectionKind kind = InjectionKind::kEncoderStuck;
  int joint = -1;
  double at = 0;         ///< [s] of simulated time
  int direction = -1;    ///< collision, wall: an index of kDirections
  double magnitude = 0;  ///< collision: the force [N]; wall: its distance from the tip [mm]
  double duration = -1;  ///< collision: a pulse's length [s]; negative: a step (for good)
  double stiffness = 0;  ///< wall [N/m]; 0: the plant's default (Contact::kWallStiffness)
  bool hits(int j) const { return joint < 0 || joint == j; }
  bool contact() const { return kind == InjectionKind::kCollision || kind == InjectionKind::kWall; }
};

/// Parses KIND[:ARGS]@SECONDS (JOINT 1 to 6; DIR one of kDirections; NEWTONS, SECONDS of a pulse and
/// N_PER_M finite and > 0, MM finite and >= 0; the time finite and >= 0); on failure fills err.
bool parse_injection(const std::string& text, Injection& out, std::string& err);

/// "encoder-stuck:3@12.5", "collision:+z:50:0.2@1.5" (the form parse_injection reads, each number in
/// its shortest form that reads back to the same value).
std::string to_string(const Injection& inj);

/// --inject's help (puma_experiment, osc_sim), its kinds from SIM_INJECTION_LIST.
std::string inject_help();

}  // namespace sim
