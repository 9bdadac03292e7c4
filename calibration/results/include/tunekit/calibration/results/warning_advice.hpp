#pragma once
// One line of "what to do" for each warning tunekit gives, shown under the warning in reports.

#include <string>

namespace tunekit::calibration {

/// The action a warning asks for: matched on the warning's wording; a general hint for a
/// warning without its own entry. Never empty.
std::string advice_for_warning(const std::string& warning);

}  // namespace tunekit::calibration
