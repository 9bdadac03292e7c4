#pragma once
// Delta calibration results as each firmware stores them.
//   Klipper: the SAVE_CONFIG block DELTA_CALIBRATE leaves for SAVE_CONFIG ([printer]
//     delta_radius; [stepper_a/b/c] angle, arm_length, position_endstop, "%.6f" as Klipper's
//     delta kinematics saves them; position_endstop = homed height + endstop adjustment).
//   Marlin: M665 (H delta height, L diagonal rod, R delta radius, X/Y/Z tower angle trims)
//     and M666 X/Y/Z endstop adjustments, normalised so that every adjustment is <= 0 as
//     Marlin's M666 requires (the largest moves into H), then M500.
//   RepRapFirmware: M665 L(per tower) R H B X Y Z and M666 X Y Z A B as its config-override.g
//     writes them (endstop adjustments normalised to mean 0, tilts in percent).
// Every writer refuses (InputError) a value that is not finite or that the firmware cannot
// hold (Klipper and Marlin have no bed tilt; Marlin has one rod length).
#include <string>

#include "tunekit/ident/delta_kinematics.hpp"

namespace tunekit::protocols {

std::string delta_klipper_save_config(const ident::DeltaGeometry& g);
std::string delta_marlin_gcode(const ident::DeltaGeometry& g);
/// `print_radius_mm`: RepRapFirmware's M665 B (printable bed radius), > 0.
std::string delta_rrf_gcode(const ident::DeltaGeometry& g, double print_radius_mm);

}  // namespace tunekit::protocols
