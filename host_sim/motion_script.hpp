// Scripted motions (puma_experiment --motion FILE.yaml): a list of timed commands played in
// lockstep against the simulated arm, with what each command did. The controller is the firmware's
// control task in process (motion_sim.hpp) or a PIL image in QEMU over the link (pil_client.hpp,
// --qemu); the commands reach either as command frames (osc/link/command_port.hpp).
//
// The script (docs/motion.md, "Scripted motions"; examples/*.yaml):
//   start_pose: [q1, ..., q6]      optional, degrees; the robot's start pose by default
//   timeout: SECONDS               optional, 600: a run that has not ended by then is a timeout
//   settle: SECONDS                optional, 1: how long the run goes on after the last step
//   inject: "KIND[:ARGS]@SECONDS"  optional: a fault or a contact, as puma_experiment --inject takes
//                                  it (docs/safety.md), e.g. "wall:-z:5@2" to put a wall in the path
//                                  of a move; not together with --inject
//   steps:
//     - at: SECONDS | after: done | after: answered
//                                  when it is sent: at that time (and after the step before it); once
//                                  the step before it was answered and the arm is at rest (every motion
//                                  done); or once the step before it was answered (to queue behind a
//                                  move, to stop or re-target it on its way)
//       delay: SECONDS             optional: that much later than at: or after: says
//       cmd: enable | disable | move_to | paper | stop | clear | stream
//       # move_to only:
//       position: [x, y, z]        the wrist centre [m], base frame (an offset if relative)
//       rpy_deg: [r, p, y]         optional orientation, R = Rz(y) Ry(p) Rx(r) (a rotation if relative)
//       relative: true             optional
//       replace: true              optional: re-target the running motion instead of queueing
//       v: .., a: .., j: ..        optional linear limits [m/s, m/s^2, m/s^3], at most the maxima
//       # stream only (and relative:, v:, a:, j: as for move_to):
//       file: PATH.csv             the path: rows t, x, y, z[, roll, pitch, yaw] in s, m, degrees
//                                  (t from 0, increasing; a header row and # comments are skipped;
//                                  PATH relative to the script's directory); with relative: true,
//                                  offsets from the pose where the stream starts
//       rate_hz: 10 .. 1000        the setpoints' rate: the path sampled (linearly between its rows)
//                                  every 1 / rate_hz s; the last one, at the path's end, ends the stream
//       cut_s: SECONDS             optional: no setpoint after this time (a stale stream: its stop)
//       velocity: true             optional: each setpoint with the path's velocity there (the slope
//                                  between its rows; setpoint_velocity frames): no delay of one period
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "experiment.hpp"
#include "osc/runtime/motion_commands.hpp"

namespace sim {

struct MotionStepSpec {
  bool after_done = false;      ///< sent once the previous step was answered and the arm is at rest
  bool after_answered = false;  ///< sent once the previous step was answered
  double at = 0;                ///< else: sent at this time [s]
  double delay = 0;             ///< sent this much later [s]
  osc::MotionVerb verb = osc::MotionVerb::kNone;
  osc::MoveRequest<double> move;  ///< move_to; stream: relative, limits, period [ticks]
  std::string text;               ///< the step as written, for the JSON
  /// stream: the path's rows (t [s], position [m], roll, pitch, yaw [rad]), and whether it has the
  /// orientation; the time after which no setpoint is sent (negative: none).
  std::vector<std::array<double, 7>> path;
  bool path_rpy = false;
  double cut_s = -1;
  bool velocity = false;  ///< stream: setpoint_velocity frames, with the path's velocity
};

/// Reads a stream's path (CSV: t, x, y, z[, roll, pitch, yaw] in s, m, degrees; a header row and
/// lines starting with # skipped); false with a message naming the file and line.
bool read_stream_csv(const std::string& path, std::vector<std::array<double, 7>>& rows, bool& has_rpy,
                     std::string& err);

struct MotionScript {
  std::vector<MotionStepSpec> steps;
  std::optional<Vec6> start_pose;  ///< [rad]
  double timeout = 600, settle = 1;
  Injection injection;  ///< inject: (none unless given)
};

/// Parses a script (YAML text); false with one message naming the step and the key on error.
bool parse_motion_script(const std::string& text, const std::string& name, MotionScript& script, std::string& err);

/// What one command did.
struct CommandRecord {
  std::string cmd, step;
  std::uint32_t id = 0;
  double sent_s = -1, answered_s = -1, done_s = -1, aborted_s = -1;
  bool accepted = false;
  std::string refused, aborted;  ///< reason names (empty: none)
  std::uint32_t cause = 0;
  double max_error_mm = 0, max_error_deg = 0;  ///< tracking while the command's motion ran
  double v = 0, a = 0, j = 0, w = 0, wd = 0;   ///< the reference's own maxima while it ran
  bool running = false;                        ///< its motion is on (accepted, not yet ended)
  std::vector<double> theta_at_sent;           ///< in process: theta^ when it was sent (18; else empty)
};

struct MotionRun {
  std::vector<CommandRecord> commands;
  struct Transition {
    double t;
    std::string state;
  };
  std::vector<Transition> states;
  std::uint32_t faults = 0;  ///< every fault bit seen
  double fault_s = -1;
  std::string result;  ///< "ok", "faulted", "timeout", or "error" (the controller failed: error)
  std::string error;   ///< why the controller failed (it did not start, its link was lost)
  double duration_s = 0, max_error_mm = 0, max_error_deg = 0;
  std::string controller;         ///< "in-process", or "pil" (a PIL image or peer over the link)
  std::string pil_command;        ///< pil: the program that ran it (qemu-system-arm, a peer)
  LinkReport link;                ///< pil: the link's health
  double wall_s = 0;              ///< wall-clock time of the run [s]
  double peak_contact_force = 0;  ///< an injected contact's largest |F| (Plant::peak_contact_force) [N]
  double first_contact_s = -1;    ///< ... when it first pushed (Plant::first_contact_time) [s]; -1: never
  /// The residual monitor of a controller in process (has_residual): each joint's worst |r| / threshold
  /// and the travel check's worst share of its limit, and its first detection (fault bit, joint, time).
  bool has_residual = false;
  double residual_peak_ratio[6] = {}, residual_travel_ratio[6] = {};
  std::uint32_t residual_fault = 0;
  int residual_joint = -1;
  double residual_detected_s = -1;
};

/// Plays the script against the simulated arm (plant set-up and injection from cfg: the caller puts
/// the script's inject: there, run_experiment.cpp's run_motion): with cfg.pil_command, the
/// controller of that PIL image or peer over the link (docs/motion.md, "Scripted motions"),
/// otherwise the in-process controller in cfg.scalar. The same script gives the same run either
/// way when the controller computes the same (fixed point; the host's PIL peer in float).
MotionRun run_motion_script(const MotionScript& script, const ExperimentConfig& cfg);

/// The run as JSON text (commands[], states[], faults, result).
std::string motion_run_json(const MotionRun& run, const std::string& script_name, const ExperimentConfig& cfg);

}  // namespace sim
