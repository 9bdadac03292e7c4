// tunekit export's command line: its options bound to ExportOptions, the help text, and the
// parsing of option values (the command itself is export_command.cpp).
#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/commands/export_command.hpp"
#include "tunekit/calibration/presentation/plots.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/design/flow_advance.hpp"
#include "tunekit/design/pressure_advance.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/firmware/gcode_advance.hpp"
#include "tunekit/firmware/orca_profile.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::calibration {

firmware::ShaperSetting parse_shaper_arg(const std::string& arg, const std::string& axis) {
  // TYPE:FREQ[:ZETA]
  std::vector<std::string> parts;
  std::stringstream ss(arg);
  std::string p;
  while (std::getline(ss, p, ':')) parts.push_back(p);
  if (parts.size() < 2 || parts.size() > 3 || parts[0].empty())
    throw InputError(fmt::format("--shaper-{} takes TYPE:FREQ[:ZETA] (for example mzv:45.2:0.1), not '{}'", axis, arg));
  firmware::ShaperSetting s;
  s.type = parts[0];
  try {
    // Plain decimals only (stod would read "0x10" as 16, and "inf" or "nan").
    for (std::size_t i = 1; i < parts.size(); ++i)
      if (!core::is_decimal_number(parts[i])) throw std::invalid_argument("not decimal");
    std::size_t used = 0;
    s.freq_hz = std::stod(parts[1], &used);
    if (used != parts[1].size()) throw std::invalid_argument("trailing");
    if (parts.size() == 3) {
      s.damping = std::stod(parts[2], &used);
      if (used != parts[2].size()) throw std::invalid_argument("trailing");
    }
  } catch (const std::out_of_range&) {  // a number, but beyond a double (5e-324, 1e999)
    throw InputError(fmt::format(
        "--shaper-{}: '{}' has a frequency or damping implausibly small or large (outside the accepted range)", axis,
        arg));
  } catch (const std::logic_error&) {
    throw InputError(fmt::format("--shaper-{}: '{}' has a frequency or damping that is not a number", axis, arg));
  }
  return s;
}

}  // namespace tunekit::calibration
