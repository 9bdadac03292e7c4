#pragma once
// Delta calibration results as each firmware stores them.
//   Klipper: the SAVE_CONFIG block DELTA_CALIBRATE leaves for SAVE_CONFIG ([printer]
//     delta_radius; [stepper_a/b/c] angle, arm_length, position_endstop, "%.6f" as Klipper's
//     delta kinematics saves them; position_endstop = homed height + endstop adjustment).
//   Marlin: M665 (H delta height, L diagonal rod, R delta radius, X/Y/Z tower angle trims)
//     and M666 X/Y/Z endstop adjustments, then M500. Marlin's adjustment lowers a carriage
//     after homing (a larger one raises it), so M666 = min(e) - e_i (every one <= 0, as
//     Marlin's M666 requires) and H = homed height + min(e) + the probe's z offset (Marlin
//     homes the nozzle at delta_height - M851 Z when it has a bed probe).
//   RepRapFirmware: M665 L(per tower) R H B X Y Z and M666 X Y Z A B as its config-override.g
//     writes them (endstop adjustments normalised to mean 0, tilts in percent).
// Every writer refuses (InputError) a value that is not finite or that the firmware cannot
// hold (Klipper and Marlin have no bed tilt; Marlin has one rod length).
#include <string>

#include "tunekit/ident/delta_kinematics.hpp"

namespace tunekit::firmware {

std::string delta_klipper_save_config(const ident::DeltaGeometry& g);
/// `probe_z_offset_mm`: Marlin's M851 Z when the printer has a bed probe, else 0.
std::string delta_marlin_gcode(const ident::DeltaGeometry& g, double probe_z_offset_mm = 0.0);
/// `print_radius_mm`: RepRapFirmware's M665 B (printable bed radius), > 0.
std::string delta_rrf_gcode(const ident::DeltaGeometry& g, double print_radius_mm);

}  // namespace tunekit::firmware
