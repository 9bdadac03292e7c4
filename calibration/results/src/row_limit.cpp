// Size bounds of the file-reading analyses: see row_limit.hpp.
#include "tunekit/calibration/results/row_limit.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::calibration {

void require_line_limit(std::string_view bytes, std::size_t max_rows, const std::string& option,
                        const std::string& path) {
  const auto lines = static_cast<std::size_t>(std::count(bytes.begin(), bytes.end(), '\n'));
  if (lines > 2 * max_rows + 1000)
    throw InputError(
        fmt::format("{} lines, far more than the limit of {} data rows (raise it with {} N)", lines, max_rows, option),
        path);
}

void require_row_limit(std::size_t rows, std::size_t max_rows, const std::string& option, const std::string& path) {
  if (rows > max_rows)
    throw InputError(
        fmt::format("{} data rows, more than the limit of {} (raise it with {} N)", rows, max_rows, option), path);
}

}  // namespace tunekit::calibration
