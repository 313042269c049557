// The on-board capture (issue 58; docs/protocol.md, "Capture"): the board's oscilloscope. Armed by a
// capture frame with up to pil::kCaptureChannels channels (each an element of a signal of
// OSC_CAPTURE_SIGNAL_LIST), it records one sample of every channel each `divider` ticks into a ring of
// the board's (pil::kCaptureValues floats, 16 KiB), the samples per channel that ring's share (depth =
// kCaptureValues / channels). Its trigger (a fault latched, a command accepted, a channel crossing a level, or a
// trigger frame) ends the pre-trigger: the capture keeps `pre` samples before the trigger's and records depth - pre - 1
// after it, then is done and is read out over the link, kCaptureChunk values a frame.
//
// The command port (osc/link/command_port.hpp) owns one: sample() after every tick, where the port's
// after_tick() runs (in the control interrupt on a board whose tick runs there), and handle() for each
// capture frame, where the port's receive() runs (the main loop; a timer-paced board masks the control
// interrupt around it). Idle or done, sample() is one comparison; armed, it costs the tick one value per
// channel (docs/benchmarks.md, table target_instructions). Header-only, allocation-free.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "osc/link/frames.hpp"
#include "osc/runtime/task.hpp"

namespace osc {

/// Element k of signal `signal` of the task after its tick, in f32 (0 for a signal outside the list).
template <class S>
float capture_value(const ControlTask<S>& t, std::uint8_t signal, int k) {
  switch (signal) {
#define OSC_CAPTURE_SIGNAL_CASE(Name, name, n, unit, doc, value) \
  case pil::kCaptureSignal##Name:                                \
    return static_cast<float>(value);
    OSC_CAPTURE_SIGNAL_LIST(OSC_CAPTURE_SIGNAL_CASE)
#undef OSC_CAPTURE_SIGNAL_CASE
    default:
      return 0.0f;
  }
}

/// An integer that orders as the float `v` does (the two zeros alike; a NaN beyond the infinity of its sign): the
/// level trigger compares in integers, so that the tick calls no soft-float routine on a core without an FPU.
inline std::int32_t capture_order(float v) {
  std::uint32_t u;
  std::memcpy(&u, &v, 4);
  const auto magnitude = static_cast<std::int32_t>(u & 0x7FFFFFFFu);
  return (u >> 31) != 0 ? -magnitude : magnitude;
}

/// The capture's set-up and state, and the frames' handling (the file comment). The ring is the board's
/// (attach(): an array the board keeps, static on the images, so that a port stays small enough to copy);
/// without one an arm is refused, no_buffer.
class SignalCapture {
 public:
  /// The ring: `values` floats at `ring` (pil::kCaptureValues on the boards), or none (nullptr).
  void attach(float* ring, int values) {
    ring_ = ring;
    values_ = ring ? values : 0;
    idle();
  }
  /// After every tick (the task's tick count has passed it): a sample when one is due, and the trigger.
  template <class S>
  void sample(const ControlTask<S>& t) {
    if (state_ != pil::kCaptureStateArmed && state_ != pil::kCaptureStateTriggered) return;
    const std::uint32_t tick = static_cast<std::uint32_t>(t.tick - 1);
    const std::uint32_t latched = t.sup.latched;
    if (trigger_ == pil::kCaptureTriggerFault && (latched & ~latched_) != 0) event_ = true;
    if (trigger_ == pil::kCaptureTriggerCommand && t.report.outcome == CommandOutcome::kAccepted) event_ = true;
    latched_ = latched;
    if (--countdown_ != 0) return;
    countdown_ = divider_;
    float* row = ring_ + head_ * channels_;
    for (int c = 0; c < channels_; ++c) row[c] = capture_value(t, signal_[c], element_[c]);
    const int slot = head_;
    head_ = head_ + 1 == depth_ ? 0 : head_ + 1;
    if (state_ == pil::kCaptureStateTriggered) {
      if (--after_ <= 0) state_ = pil::kCaptureStateDone;
      return;
    }
    if (filled_ < depth_) ++filled_;
    if (level_trigger_ && level_crossed(row[level_channel_])) event_ = true;
    if (!event_) return;
    trigger_tick_ = tick;
    trigger_slot_ = slot;
    held_pre_ = filled_ - 1 < pre_ ? filled_ - 1 : pre_;
    after_ = depth_ - pre_ - 1;
    state_ = after_ > 0 ? pil::kCaptureStateTriggered : pil::kCaptureStateDone;
  }

  /// A capture frame (the task's latched faults are the fault trigger's start): its answer.
  template <class S>
  pil::CaptureDataFrame handle(const ControlTask<S>& t, const pil::CaptureFrame& f) {
    pil::CaptureStatus s = pil::kCaptureStatusOk;
    switch (f.op) {
      case pil::kCaptureOpArm:
        s = arm(f, t.sup.latched);
        break;
      case pil::kCaptureOpTrigger:
        if (state_ == pil::kCaptureStateArmed)
          event_ = true;
        else
          s = pil::kCaptureStatusNotArmed;
        break;
      case pil::kCaptureOpAbort:
        idle();
        break;
      case pil::kCaptureOpStatus:
        break;
      case pil::kCaptureOpRead:
        s = state_ != pil::kCaptureStateDone ? pil::kCaptureStatusNotDone : pil::kCaptureStatusOk;
        break;
      default:
        s = pil::kCaptureStatusBadOp;
    }
    pil::CaptureDataFrame a = answer(f);
    a.status = s;
    if (f.op == pil::kCaptureOpRead && s == pil::kCaptureStatusOk) a.status = read(f.offset, a);
    return a;
  }

  /// Where the capture is (pil::CaptureState).
  std::uint8_t state() const { return state_; }
  /// The samples per channel a done capture holds.
  int held() const { return held_pre_ + 1 + (depth_ - pre_ - 1); }

 private:
  /// An arm frame checked and started (the ring's old contents dropped).
  pil::CaptureStatus arm(const pil::CaptureFrame& f, std::uint32_t latched) {
    if (values_ < pil::kCaptureChannels) return refuse(pil::kCaptureStatusNoBuffer);
    if (f.channels < 1 || f.channels > pil::kCaptureChannels) return refuse(pil::kCaptureStatusBadChannel);
    for (int c = 0; c < f.channels; ++c)
      if (f.signal[c] >= pil::kCaptureSignalCount || f.element[c] >= pil::kCaptureSignals[f.signal[c]].elements)
        return refuse(pil::kCaptureStatusBadChannel);
    const bool level = f.trigger == pil::kCaptureTriggerRising || f.trigger == pil::kCaptureTriggerFalling;
    if (f.trigger >= pil::kCaptureTriggerCount || (level && (f.level_channel >= f.channels || !std::isfinite(f.level))))
      return refuse(pil::kCaptureStatusBadTrigger);
    const int depth = values_ / f.channels;
    if (f.divider == 0 || f.pre >= static_cast<std::uint32_t>(depth)) return refuse(pil::kCaptureStatusBadSpan);
    channels_ = f.channels;
    for (int c = 0; c < pil::kCaptureChannels; ++c) {
      signal_[c] = c < channels_ ? f.signal[c] : std::uint8_t{0};
      element_[c] = c < channels_ ? f.element[c] : std::uint8_t{0};
    }
    trigger_ = f.trigger;
    level_trigger_ = level;
    level_channel_ = level ? f.level_channel : std::uint8_t{0};
    level_ = capture_order(f.level);
    pre_ = static_cast<int>(f.pre);
    divider_ = f.divider;
    depth_ = depth;
    head_ = filled_ = held_pre_ = 0;
    countdown_ = 1;  // the first sample after the next tick
    event_ = have_last_ = false;
    latched_ = latched;
    state_ = pil::kCaptureStateArmed;
    return pil::kCaptureStatusOk;
  }
  pil::CaptureStatus refuse(pil::CaptureStatus s) {
    idle();
    return s;
  }
  /// No capture, no set-up (an idle answer shows none).
  void idle() {
    state_ = pil::kCaptureStateIdle;
    channels_ = 0;
    for (int c = 0; c < pil::kCaptureChannels; ++c) signal_[c] = element_[c] = 0;
    trigger_ = pil::kCaptureTriggerManual;
    level_trigger_ = false;
    level_channel_ = 0;
    level_ = 0;
    pre_ = 0;
    divider_ = 1;
  }

  /// A level trigger's test on the level channel's newest value (the first sample only records it).
  bool level_crossed(float value) {
    const std::int32_t v = capture_order(value), last = last_level_;
    const bool had = have_last_;
    last_level_ = v;
    have_last_ = true;
    if (!had) return false;
    return trigger_ == pil::kCaptureTriggerRising ? last < level_ && v >= level_ : last > level_ && v <= level_;
  }

  /// The answer's set-up and state.
  pil::CaptureDataFrame answer(const pil::CaptureFrame& f) const {
    pil::CaptureDataFrame a;
    a.id = f.id;
    a.op = f.op;
    a.state = state_;
    a.channels = static_cast<std::uint8_t>(channels_);
    for (int c = 0; c < pil::kCaptureChannels; ++c) a.signal[c] = signal_[c], a.element[c] = element_[c];
    a.trigger = trigger_;
    a.divider = divider_;
    const bool triggered = state_ == pil::kCaptureStateTriggered || state_ == pil::kCaptureStateDone;
    a.depth = state_ == pil::kCaptureStateDone ? static_cast<std::uint32_t>(held()) : 0u;
    a.pre = triggered ? static_cast<std::uint32_t>(held_pre_) : static_cast<std::uint32_t>(pre_);
    a.trigger_tick = triggered ? trigger_tick_ : 0u;
    a.first_tick = triggered ? trigger_tick_ - static_cast<std::uint32_t>(held_pre_) * divider_ : 0u;
    return a;
  }

  /// A done capture's values from `offset` (sample x channels + channel, the first held sample first).
  pil::CaptureStatus read(std::uint32_t offset, pil::CaptureDataFrame& a) const {
    const std::uint32_t total = static_cast<std::uint32_t>(held() * channels_);
    if (offset > total) return pil::kCaptureStatusBadOffset;
    constexpr auto kChunk = static_cast<std::uint32_t>(pil::kCaptureChunk);
    const std::uint32_t n = total - offset < kChunk ? total - offset : kChunk;
    const int first = (trigger_slot_ - held_pre_ + depth_) % depth_;
    for (std::uint32_t v = 0; v < n; ++v) {
      const int s = static_cast<int>((offset + v) / static_cast<std::uint32_t>(channels_));
      const int c = static_cast<int>((offset + v) % static_cast<std::uint32_t>(channels_));
      a.values[v] = ring_[((first + s) % depth_) * channels_ + c];
    }
    a.offset = offset;
    a.count = static_cast<std::uint8_t>(n);
    return pil::kCaptureStatusOk;
  }

  std::uint8_t state_ = pil::kCaptureStateIdle;
  int channels_ = 0;
  std::uint8_t signal_[pil::kCaptureChannels] = {};
  std::uint8_t element_[pil::kCaptureChannels] = {};
  std::uint8_t trigger_ = pil::kCaptureTriggerManual;
  bool level_trigger_ = false;  // rising or falling: each sample's level channel is compared
  std::uint8_t level_channel_ = 0;
  std::int32_t level_ = 0, last_level_ = 0;  // capture_order of the level and of the level channel's last value
  bool have_last_ = false;
  bool event_ = false;  // the trigger's event came: the next sample is the trigger's
  int pre_ = 0;
  std::uint8_t divider_ = 1;
  int countdown_ = 1;  // ticks to the next sample
  int depth_ = 1;      // the ring's samples per channel
  int head_ = 0;       // the ring's next slot
  int filled_ = 0;     // samples recorded before the trigger (at most depth_)
  int after_ = 0;      // samples still to record after the trigger
  int trigger_slot_ = 0, held_pre_ = 0;
  std::uint32_t trigger_tick_ = 0;
  std::uint32_t latched_ = 0;  // the latched faults at the last tick (the fault trigger's edge)
  float* ring_ = nullptr;
  int values_ = 0;
};

}  // namespace osc
