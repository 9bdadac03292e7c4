#pragma once
// Numbers as the terminal, the report and the agreement statements show them.

#include <string>

namespace tunekit::calibration {

/// Formats a number for display with 4 significant digits ("0.4512", "1.25e+04").
std::string display_number(double v);

/// Formats a 95 % interval for display as "[lo, hi]": 4 significant digits like display_number,
/// more (up to 8) where 4 would print two different bounds as the same number ("[3.5, 3.5]" reads
/// as an interval of zero width; "[3.4995, 3.5004]" says what was measured).
std::string display_interval(double lo, double hi);

}  // namespace tunekit::calibration
