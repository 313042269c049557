// The main loop's side of an identify run on a board that estimates (issue 57; docs/adaptation.md, "The identify
// command"): the run's samples from the task's sampler summed into the estimate (osc/runtime/identify_run.hpp,
// IdentifyRun), and when the run's motion ends, its report to the client as one identify frame
// (osc/link/command_frames.hpp): the estimate when the motion was done, status `aborted` when it was aborted, and
// right after it an identify_offset frame (each drive's torque offset); a run asked with the command flag payload
// estimates the payload at the flange too and sends it in an identify_payload frame after those.
//
// A board calls after_tick() from its main loop, after every tick where it runs in lockstep (the virtual board,
// osc_sim, after CommandPort::after_tick_and_poll; the QEMU images, pil_firmware.cpp), or as often as its main loop
// runs (a timer-paced board). A run is followed from the call after the tick that accepted it, and the ticks the task
// recorded since the last call go through the run's filter (IdentifyRun::poll: up to params::kRunRingTicks behind;
// the samples of ticks overwritten before a call are counted lost). The run's accept and end are the sampler's
// counts (IdentifySampler::accept, note_end), not the tick's report, which holds only the latest tick's: a call
// that comes some ticks late misses neither. The estimate's sums are doubles, about 10 kB (the information matrix of
// 4 x 6 + 10 unknowns), and the solve at the end a few hundred thousand operations (soft-float on the QEMU images).
// The STM32F4 app calls it from its timer-paced main loop (boards/stm32f4/app.hpp), at least every 16 ticks.
//
// What the client does with the report: the friction goes into the parameters friction_vis, friction_cou and
// friction_sti, the armatures into armature_correction (oscctl identify --apply; they need the torque off), and a
// `param save` keeps them for the next power-on. Header-only, allocation-free.
#pragma once

#include <cstdint>

#include "osc/link/frames.hpp"
#include "osc/runtime/task.hpp"

namespace osc {

/// A run's report as its frame (f32). `friction` and `armature` hold the estimate only when the run is ok.
inline pil::IdentifyFrame identify_frame(std::uint32_t id, const IdentifyReport& r, std::uint32_t samples,
                                         std::uint32_t lost) {
  pil::IdentifyFrame f;
  f.id = id;
  f.status = static_cast<std::uint8_t>(r.status);
  f.samples = samples;
  f.lost = lost;
  f.condition = static_cast<float>(r.condition);
  f.prediction_error = static_cast<float>(r.worst_prediction_error);
  const bool ok = r.status == IdentifyStatus::kOk;
  for (int k = 0; k < 3 * kDof; ++k) {
    f.friction[k] = ok ? static_cast<float>(r.friction(k)) : 0.0f;
    f.friction_sd[k] = static_cast<float>(r.friction_sd(k));
    if (ok && r.friction_verdict[static_cast<std::size_t>(k)] == CoefficientVerdict::kIdentified)
      f.identified |= 1u << k;
  }
  for (int i = 0; i < kDof; ++i) {
    f.armature[i] = ok ? static_cast<float>(r.armature(i)) : 0.0f;
    f.armature_sd[i] = static_cast<float>(r.armature_sd(i));
  }
  return f;
}

/// A run's estimate of each drive's torque offset as its frame (f32): the offsets when the run is ok, their sigma
/// always.
inline pil::IdentifyOffsetFrame identify_offset_frame(std::uint32_t id, const IdentifyReport& r) {
  pil::IdentifyOffsetFrame f;
  f.id = id;
  f.status = static_cast<std::uint8_t>(r.status);
  const bool ok = r.status == IdentifyStatus::kOk;
  for (int i = 0; i < kDof; ++i) {
    f.offset[i] = ok ? static_cast<float>(r.offset(i)) : 0.0f;
    f.offset_sd[i] = static_cast<float>(r.offset_sd(i));
  }
  return f;
}

/// A run's payload estimate as its frame (f32): the body (mass, centre of mass, inertia about it) when the run is ok,
/// the estimated parameters' sigma and verdicts always.
inline pil::IdentifyPayloadFrame identify_payload_frame(std::uint32_t id, const IdentifyReport& r) {
  pil::IdentifyPayloadFrame f;
  f.id = id;
  f.status = static_cast<std::uint8_t>(r.status);
  if (r.status == IdentifyStatus::kOk) {
    const Payload b = PayloadParams<double>::of(r.payload).body();
    f.mass = static_cast<float>(b.mass);
    for (int k = 0; k < 3; ++k) f.com[k] = static_cast<float>(b.com[k]);
    for (int k = 0; k < 6; ++k) f.inertia[k] = static_cast<float>(b.inertia[k]);
  }
  for (int k = 0; k < 10; ++k) {
    f.pi_sd[k] = static_cast<float>(r.payload_sd(k));
    if (r.payload_verdict[static_cast<std::size_t>(k)] == CoefficientVerdict::kIdentified) f.identified |= 1u << k;
  }
  return f;
}

/// Follows the task's identify runs from the main loop and reports each one's end (the file comment).
template <class S>
class IdentifyPort {
 public:
  /// After every tick: a run accepted in it is started, the run's new ticks filtered and sampled, and in the tick its
  /// motion ends the identify frame written (`write(bytes, n)`, after the tick's answer frame).
  template <class Write>
  void after_tick(const ControlTask<S>& task, Write&& write) {
    const IdentifySampler<S>& s = task.identify;
    const std::uint32_t accepted = s.accepted;
    if (accepted != followed_) {  // a run accepted since the last call
      followed_ = accepted;
      run_.start(s.accepted_id, s.accepted_payload, task.model, task.without_payload(), &task.io);
      active_ = true;
    }
    if (!active_) return;
    run_.poll(s);
    if (s.ended != followed_) return;
    const bool done = s.ended_done;
    run_.poll(s);  // the ticks recorded before the end that the tick noted after the poll above
    active_ = false;
    IdentifyReport report;
    if (done)
      report = run_.finish();
    else
      report.status = IdentifyStatus::kAborted;
    ++reports_;
    last_ = report;
    std::uint8_t buf[pil::kMaxFrame];
    write(buf, pil::encode(identify_frame(run_.id(), report, run_.taken(), run_.lost()), buf));
    write(buf, pil::encode(identify_offset_frame(run_.id(), report), buf));
    if (run_.payload() != payload_mask::kNone) write(buf, pil::encode(identify_payload_frame(run_.id(), report), buf));
  }
  /// Whether a run is being followed.
  bool active() const { return active_; }
  /// The reports sent, and the last one.
  std::uint32_t reports() const { return reports_; }
  const IdentifyReport& last() const { return last_; }

 private:
  IdentifyRun<S> run_;
  IdentifyReport last_{};
  std::uint32_t followed_ = 0;  // the sampler's accepted count of the run followed last
  bool active_ = false;
  std::uint32_t reports_ = 0;
};

}  // namespace osc
