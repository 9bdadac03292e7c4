#pragma once
// A hot end's thermal record: the heater's measured temperature beside what drove it (the
// heater's PWM duty, the part-cooling fan's duty, the filament feed) and the temperature the
// firmware was asked to hold, sampled at common instants. A designed thermal experiment writes
// it, a firmware log reader (Klipper's klippy.log "Stats" lines) fills it, and the thermal
// identification (thermal_model.hpp) fits it as a whole.

#include <vector>

namespace tunekit::ident {

/// The samples of one heater, all vectors indexed alike. `fan_duty` and `feed_mm_s` may be empty,
/// meaning zero throughout (a log that does not state them); `target_c` may be empty, meaning
/// unknown. Every other vector has t_s's size.
struct ThermalRecord {
  std::vector<double> t_s;          ///< sample time, s, strictly increasing
  std::vector<double> temp_c;       ///< the heater's measured temperature, degC
  std::vector<double> heater_duty;  ///< heater PWM duty over the interval that starts at t_s, in [0, 1]
  std::vector<double> fan_duty;     ///< part-cooling fan duty in [0, 1]; empty: zero
  std::vector<double> feed_mm_s;    ///< filament feed into the hot end, mm/s; empty: zero
  std::vector<double> target_c;     ///< the firmware's target temperature, degC; empty: unknown
};

}  // namespace tunekit::ident
