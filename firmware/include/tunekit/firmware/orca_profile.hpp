#pragma once
// OrcaSlicer filament profile: adaptive pressure advance written as OrcaSlicer stores it.
//
// OrcaSlicer (SoftFever/OrcaSlicer, AGPLv3) keeps per-filament options as JSON arrays of strings
// (one per extruder): src/libslic3r/PrintConfig.cpp defines
//   adaptive_pressure_advance        coBools   (["1"] enables it)
//   adaptive_pressure_advance_model  coStrings, default "0,0,0\n0,0,0": lines "PA,flow,acceleration"
//                                    (PA in s, volumetric flow in mm^3/s, acceleration in mm/s^2)
//   enable_pressure_advance, pressure_advance (the fallback value OrcaSlicer uses when the model
//                                    cannot be evaluated, AdaptivePAProcessor.cpp)
// src/libslic3r/GCode/AdaptivePAInterpolator.cpp parses the lines (comma separated, std::stod),
// groups them by acceleration, fits a PCHIP curve over flow per acceleration (so flows must be
// distinct within an acceleration) and rounds its result to 3 decimals. tunekit writes the lines
// sorted by flow then acceleration, PA with 3 decimals, flow with 2 and acceleration as an
// integer, as OrcaSlicer's own profiles do (e.g. resources/profiles/Phrozen/filament/).
//
// Merging into an existing profile edits the JSON text in place: only the values of the keys
// above change (missing keys are appended in the file's own indentation); every other byte of
// the file stays as it was.

#include <string>
#include <vector>

#include "tunekit/design/flow_advance.hpp"

namespace tunekit::firmware {

struct OrcaAdvanceProfile {
  std::vector<design::OrcaPoint> table;  ///< at least two points per acceleration
  double fallback_k_s = 0;               ///< pressure_advance (the single K at the design flow)
};

/// The adaptive_pressure_advance_model text ("PA,flow,acceleration" lines joined by "\n").
/// Throws InputError for non-finite or out-of-range values (firmware_limits.hpp) or flows that
/// coincide within an acceleration after rounding.
std::string orca_model_text(const std::vector<design::OrcaPoint>& table);

struct OrcaMergeResult {
  std::string text;
  std::vector<std::string> changed_keys;  ///< keys whose value was replaced
  std::vector<std::string> added_keys;    ///< keys appended to the object
};

/// Merges into the text of an OrcaSlicer filament profile (`path` names it in errors).
/// Throws InputError when the text is not a JSON object.
OrcaMergeResult merge_orca_filament_profile(const std::string& json_text, const OrcaAdvanceProfile& p,
                                            const std::string& path);

/// A new user filament profile holding the advance settings (4-space indentation, as OrcaSlicer
/// writes user presets). `inherits` may be empty.
std::string new_orca_filament_profile(const OrcaAdvanceProfile& p, const std::string& name,
                                      const std::string& inherits);

/// The raw text of each top-level member ("key": value) of a JSON object, in file order (used to
/// check that a merge left untouched members byte-identical). Throws InputError on bad JSON.
std::vector<std::pair<std::string, std::string>> json_top_level_members(const std::string& json_text,
                                                                        const std::string& path);

}  // namespace tunekit::firmware
