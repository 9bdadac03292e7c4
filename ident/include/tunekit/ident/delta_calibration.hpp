#pragma once
// Least-squares delta calibration from probe heights (after Brown, "Delta Printer Project
// Report", La Trobe University, 2013). The factor sets are those of RepRapFirmware's G32
// auto-calibration, whose 6-factor set is also Klipper's DELTA_CALIBRATE set:
//   3: endstop adjustments e_A, e_B, e_C
//   4: + delta radius
//   6: + tower angle corrections of towers A and B (tower C is the reference)
//   7: + diagonal rod length (one shift common to the three rods)
//   8: 6 + bed tilt in X and Y
//   9: 7 + bed tilt in X and Y
// The homed height is not a factor: it moves with the mean of the endstop adjustments and
// the exports normalise it as each firmware does.
//
// Model: the firmware runs the nominal geometry; a probe at commanded (x, y) triggered at
// commanded height z. The carriages then stood a known distance below their endstops; under
// candidate geometry g the nozzle was at height h(g) = forward(g, homed(g) - travel), and the
// fit makes h(g) = 0 (a flat bed) at every probe point. Lengths in mm, angles in degrees,
// tilts in percent (RepRapFirmware's M666 A/B).
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/ident/delta_kinematics.hpp"

namespace tunekit::ident {

/// Factor counts the fit accepts.
inline constexpr int kDeltaFactorChoices[] = {3, 4, 6, 7, 8, 9};

/// Names of the fitted parameters for `factors` (throws InputError for an unsupported count).
/// Names: endstop_a/b/c (mm), delta_radius (mm), angle_a/b (deg, absolute tower angle),
/// diagonal_rod (mm, mean of the three rods), tilt_x/tilt_y (%).
std::vector<std::string> delta_factor_names(int factors);

/// Flatness of a set of heights: rms about zero, standard deviation about the mean and
/// peak-to-peak, all mm.
struct DeltaFlatness {
  double rms_mm = 0;
  double std_mm = 0;
  double peak_to_peak_mm = 0;
};
DeltaFlatness delta_flatness(const std::vector<double>& heights_mm);

struct DeltaCalibration {
  fitting::FitResult fit;           ///< the factors with standard errors and 95 % intervals
  DeltaGeometry nominal;            ///< the geometry the firmware ran while probing
  DeltaGeometry fitted;             ///< nominal with the fitted factors applied
  std::vector<double> residual_mm;  ///< height left at each probe point under `fitted`
  DeltaFlatness before, after;      ///< probe heights as measured, and the residuals
};

/// Fits `factors` geometric errors to the probe heights. Throws InputError for too few or
/// unreachable points, FitError when the fit does not converge or a factor is not
/// identifiable from the points (e.g. all points on one circle for 7 factors).
DeltaCalibration fit_delta_calibration(const DeltaGeometry& nominal, const std::vector<DeltaProbe>& probes,
                                       int factors);

/// The geometry `nominal` with the factor values `values` (in delta_factor_names order).
DeltaGeometry delta_apply_factors(const DeltaGeometry& nominal, int factors, const std::vector<double>& values);

}  // namespace tunekit::ident
