// The tick's monitors (docs/safety.md): small types, each with `check(...) -> fault bits` and the
// state it keeps between ticks, run by control_tick() (osc/runtime/control_task.hpp) in two
// stages: the encoder checks before the control step, the step's checks after it. This header
// includes them all; each part's header holds:
//
//   osc/runtime/encoder_monitors.hpp
//     before the step  EncoderRangeMonitor   every reading within the joint limits plus a margin
//                      EncoderJumpMonitor    no change beyond the joint's speed limit since the last sample
//     after the step   StuckEncoderMonitor   an encoder that stands still while its joint is driven
//                                            (EncoderActivity: each encoder's changes; qualify())
//   osc/runtime/residual_monitor.hpp
//     after the step   ResidualMonitor       the torque the model does not explain, and the travel check
//                                            (residual_constants.hpp, residual_thresholds.hpp and
//                                            residual_travel.hpp: its constants, thresholds, travel check)
//   osc/runtime/drive_monitor.hpp
//     after the step   DriveMonitor          each amplifier's current against its DAC code, the test dither,
//                                            the amplifiers' fault lines (a HAL with current readback)
//   osc/runtime/step_monitors.hpp
//     after the step   TrackingMonitor       the tracking error e (36) within params::kTrackingLimit*
//                      ThetaBandMonitor      the friction estimates within their band
//                      SaturationMonitor     a DAC clipped for params::kSaturationTicks ticks in a row
//                      PositionCrossCheck    each joint's potentiometer against its encoders (a HAL with pots)
// The thresholds are params:: constants (osc/control/params.hpp), converted to the scalar at compile time.
#pragma once

#include "osc/runtime/drive_monitor.hpp"
#include "osc/runtime/encoder_monitors.hpp"
#include "osc/runtime/residual_monitor.hpp"
#include "osc/runtime/step_monitors.hpp"
