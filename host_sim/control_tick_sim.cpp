// The control tick over the simulated arm in the three scalars (control_tick_sim.hpp).
#include "control_tick_sim.hpp"

namespace osc {

template std::uint32_t control_tick<double, sim::PlantHal>(ControlTask<double>&, sim::PlantHal&);
template std::uint32_t control_tick<float, sim::PlantHal>(ControlTask<float>&, sim::PlantHal&);
template std::uint32_t control_tick<Fixed, sim::PlantHal>(ControlTask<Fixed>&, sim::PlantHal&);

}  // namespace osc
