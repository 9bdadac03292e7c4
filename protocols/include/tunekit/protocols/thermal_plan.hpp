#pragma once
// The designed thermal experiment of the hot end (protocol heater-identify): what the heater's
// target, the part-cooling fan and the filament feed do over at most five minutes of machine
// time, sized from the machine profile, and the part of it held out of the fit to be predicted.
//
// From rest (heater and fan off, the record starting at the ambient): a heat-up to the printing
// temperature at the firmware's full power and its controller's settling (P/C, A and the sensor's
// lag), a step down and back up (the cooling at zero duty: A/C; the sensor's lag at each
// reversal), a full-fan step (F), an extrusion step (H); then, held out of the fit, a second fan
// step and a second extrusion step, which the identified model predicts. The heater is off
// at the end. The target never exceeds the profile's hotend_max_c: a plan asking for more is
// refused before any G-code is generated (and the safety gate checks the G-code again).

#include <map>
#include <string>
#include <vector>

#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::protocols {

/// One piece of the plan: from `from_s` (s after the record starts) on, until the next piece.
struct ThermalPiece {
  double from_s = 0;
  double target_c = 0;   ///< heater target, degC (0: off)
  double fan_duty = 0;   ///< part-cooling fan, 0..1
  double feed_mm_s = 0;  ///< filament feed, mm/s
  std::string what;      ///< "rest", "heat-up", "step down", ...
  bool held_out = false;
};

struct ThermalPlan {
  std::vector<ThermalPiece> pieces;
  double duration_s = 0;       ///< the record's length (the heater is off from then), s
  double held_out_from_s = 0;  ///< the first held-out piece's start, s
  double hotend_c = 0;         ///< the printing temperature the plan holds
};

/// The plan from the protocol's parameters: hotend_c (degC), step_down_c (K), fan_duty (0..1),
/// feed_mm_s (NaN: the machine's default, machine_defaults). InputError when the printing
/// temperature exceeds the profile's hotend_max_c or leaves no room for the step down.
ThermalPlan plan_thermal_experiment(const std::map<std::string, double>& params,
                                    const machine::MachineProfile& profile);

/// The feed of the extrusion steps the profile allows by default, mm/s of filament: 4 mm^3/s
/// (a 0.4 mm nozzle's ordinary printing flow), at most a third of the profile's max_flow_mm3_s
/// and of the extruder's max_velocity_mm_s.
double default_thermal_feed_mm_s(const machine::MachineProfile& profile);

}  // namespace tunekit::protocols
