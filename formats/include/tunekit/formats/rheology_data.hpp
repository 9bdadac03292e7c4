#pragma once
// Rheometer (or capillary) data from CSV into SI units for the viscosity fits, with the unit
// checks that catch the usual mix-ups. Columns, by name (case-insensitive), units in brackets
// or as a suffix (shear_rate_1_s, viscosity_Pa_s, temperature_C), or named in the options:
//   shear_rate (1/s)                        required, > 0
//   viscosity (Pa.s | mPa.s | cP | P | kPa.s)  or shear_stress (Pa | kPa | MPa), eta = tau / gamma
//                                           (P is the poise, 0.1 Pa.s, used by many compilations)
//   temperature (degC | C | K)              optional if a temperature is given separately
//   pressure (Pa | kPa | MPa | bar)         optional
//   weight                                  optional, > 0 (weights of ln-viscosity residuals)
// Refused with InputError (exit 2) and FILE:LINE: negative or zero shear rates, non-positive
// or non-finite viscosities, a temperature without a unit, kelvin values below 273.15 (they
// are degC), degC values above 600 (they are kelvin), a stated viscosity unit that contradicts
// the header, and viscosity and shear_stress columns that disagree (eta != tau / gamma: a unit
// is wrong).
// Let through with a warning (RheologyTable::warnings): viscosities above kHighViscosity or below
// kLowViscosity, and a shear stress (eta gamma) that falls by more than 10 % as the shear rate
// rises at one temperature (a melt's flow curve rises). Zero-shear viscosities above 1e6 Pa.s are real (high-Tg
// polymers near their processing window, high molecular weights), so magnitude alone cannot prove a unit mix-up.

#include <string>
#include <string_view>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/fitting/viscosity.hpp"

namespace tunekit::formats {

struct RheologyCsvOptions {
  /// Temperature of every point when the file has no temperature column (degC); NaN: none.
  double temperature_degC = fitting::kNaN;
  /// degC -> K offset: 273.15 (SI) or 273 (Holtrup's (2019) code).
  double kelvin_offset = fitting::kKelvinOffset;
  /// Unit of the viscosity column when its header states none (Pa.s, mPa.s, cP, P, kPa.s);
  /// empty: the header's unit, else Pa.s. A header unit that disagrees is an InputError.
  std::string viscosity_unit;
  /// Keep only the rows whose temperature lies in [min, max] degC (inclusive); NaN: no limit.
  double temperature_min_degC = fitting::kNaN;
  double temperature_max_degC = fitting::kNaN;
  /// Column names for files whose headers are not the usual ones (a rheometer's export, another
  /// language); empty: found by the names above. A named column must exist.
  std::string shear_rate_column, viscosity_column, stress_column, temperature_column, pressure_column;
  /// Units of the stress and temperature columns when their names carry none (or a wrong one):
  /// override the header.
  std::string stress_unit, temperature_unit;
};

/// Viscosities outside [kLowViscosity, kHighViscosity] Pa.s are unusual for a polymer melt at
/// processing temperature and draw a warning naming the row and the unit they were read in.
inline constexpr double kHighViscosity = 1e6;
inline constexpr double kLowViscosity = 1e-2;

struct RheologyTable {
  fitting::RheologyData data;
  std::vector<std::string> notes;     ///< conversions applied, e.g. "viscosity: mPa.s -> Pa.s"
  std::vector<std::string> warnings;  ///< "FILE:LINE: ..." plausibility warnings; the data were kept
};

RheologyTable parse_rheology_csv(std::string_view text, const std::string& path,
                                 const RheologyCsvOptions& options = {});

/// Multiplier from a viscosity unit to Pa.s; InputError for an unknown unit.
double viscosity_unit_factor(std::string_view unit);
/// Multiplier from a pressure/stress unit to Pa; InputError for an unknown unit.
double pressure_unit_factor(std::string_view unit);

}  // namespace tunekit::formats
