// The control tick over the simulated arm, osc::control_tick with sim::PlantHal, compiled once in the
// three scalars (control_tick_sim.cpp, in osc_sim) and linked by every file of the simulator and its
// tests that runs it: it is the simulator's largest instantiation (the whole control step, the
// monitors and the motion state machine), and compiling it again in each of them took a third to a
// half of their build time. Another scalar or HAL still instantiates it where it is used.
#pragma once

#include "osc/math/q.hpp"
#include "osc/runtime/control_task.hpp"
#include "plant_hal.hpp"

namespace osc {

extern template std::uint32_t control_tick<double, sim::PlantHal>(ControlTask<double>&, sim::PlantHal&);
extern template std::uint32_t control_tick<float, sim::PlantHal>(ControlTask<float>&, sim::PlantHal&);
extern template std::uint32_t control_tick<Fixed, sim::PlantHal>(ControlTask<Fixed>&, sim::PlantHal&);

}  // namespace osc
