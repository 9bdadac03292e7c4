#pragma once
// What the firmware-configuration importers share (profile_from_klipper.cpp,
// profile_from_marlin.cpp, profile_from_rrf.cpp): where a value was read, the plausible range of
// each kind of quantity, setting a profile value together with its source, tunekit's defaults
// for what no firmware configuration holds, and the final check of an imported profile.

#include <cstddef>
#include <string>

#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/machine/profile_import.hpp"

namespace tunekit::machine::detail {

/// Where a value was read: the file (as the user named it, or an include's path relative to the
/// including file's folder), its 1-based line (0: the file as a whole) and the line as written.
struct Site {
  std::string file;
  std::size_t line = 0;
  std::string text;
  /// "FILE:LINE" (or "FILE") for error messages.
  std::string where() const;
  /// "FILE:LINE TEXT" for MachineProfile::sources.
  std::string cite() const;
};

/// The plausible range of one kind of quantity: values outside it (1e308 mm/s^2, a negative
/// speed) are refused as errors in the file rather than passed on as limits.
struct Range {
  double lo;
  double hi;
  bool lo_open;  ///< lo itself is excluded (a limit must be positive)
  const char* what;
  const char* unit;
};
inline constexpr Range kPosition{-1e9, 1e9, false, "position", "mm"};  // belt printers: 2e7 (CR-30)
inline constexpr Range kLength{0, 1e5, true, "length", "mm"};
inline constexpr Range kDiameter{0, 100, true, "diameter", "mm"};
inline constexpr Range kVelocity{0, 1e5, true, "speed", "mm/s"};
inline constexpr Range kAccel{0, 1e7, true, "acceleration", "mm/s^2"};
inline constexpr Range kTemperature{0, 1000, true, "temperature", "degC"};
inline constexpr Range kStepsPerMm{0, 1e7, true, "steps per mm", "steps/mm"};
inline constexpr Range kCount{0, 1e7, true, "count", ""};
inline constexpr Range kFraction{0, 1, false, "fraction", ""};
inline constexpr Range kSeconds{0, 100, false, "time", "s"};
inline constexpr Range kFrequency{0, 1e4, false, "frequency", "Hz"};

/// Checks `v` against `range`; InputError located at `site` naming `name` when it is NaN,
/// infinite or outside.
double checked(double v, const Range& range, const Site& site, const std::string& name);
/// A plain decimal number as written ("3000", "-0.5", "1e3"; core::parse_decimal), checked
/// against `range`; InputError at `site` for anything else ("nan", "inf", "0x10", "fast").
double parse_number(const std::string& text, const Range& range, const Site& site, const std::string& name);

/// A value with where it came from (a site's cite(), a firmware default with its formula).
struct Sourced {
  double value = 0;
  std::string source;
};

/// Sets the axis' travel and limits with their sources.
void set_axis(MachineProfile& p, const std::string& name, const Sourced& lo, const Sourced& hi, const Sourced& v,
              const Sourced& a);

/// `text` for a message: at most 60 characters ("..." marks a cut), so an error stays one short line.
std::string shown(const std::string& text);

/// Sets `field` to `v` and notes `source` under `key` in p.sources.
void set_value(MachineProfile& p, const std::string& key, double& field, double v, std::string source);
/// The shortest text that reads back as `v` ("798.1" is written with 4 significant digits where
/// a derived value is cited; this gives "3000", "0.4", "798.0984...").
std::string number_text(double v);

/// The values no firmware configuration holds, set with their reasons when not already set: the
/// hot end's flow limit (the smaller of tunekit's conservative 8 mm^3/s and what the extruder's
/// feed limit allows), the print's line width, layer height and speed (from the nozzle), and
/// heaters_off_on_abort.
void apply_common_defaults(MachineProfile& p);
/// Declares the sensors `options.sensors` names (InputError for an unknown name).
void apply_sensor_options(MachineProfile& p, const ProfileImportOptions& options);
/// The last check of an imported profile: x, y and z axes with max > min, every limit finite and
/// positive (InputError naming the key and its source otherwise).
void check_imported(const MachineProfile& p);

}  // namespace tunekit::machine::detail
