#pragma once
// Size bounds of the file-reading analyses: a data file longer than the bound is refused with
// one line naming the bound and the option that raises it, instead of running for minutes.

#include <cstddef>
#include <string>
#include <string_view>

namespace tunekit::calibration {

/// Refuses (InputError, exit 2) `bytes` before parsing when it holds more than
/// 2 * max_rows + 1000 lines: a file so long that it cannot hold max_rows data rows plus any
/// plausible header and comments. `option` is the command-line option that raises the bound.
void require_line_limit(std::string_view bytes, std::size_t max_rows, const std::string& option,
                        const std::string& path);

/// Refuses (InputError, exit 2) `rows` data rows when they exceed `max_rows`.
void require_row_limit(std::size_t rows, std::size_t max_rows, const std::string& option, const std::string& path);

}  // namespace tunekit::calibration
