// Reading an axis test's commanded motion (commanded_motion.hpp).
#include "tunekit/ident/commanded_motion.hpp"

#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"

namespace tunekit::ident {

using formats::CsvOptions;
using formats::CsvTable;
using formats::parse_csv;

std::vector<AccelPiece> load_commanded_motion_csv(const std::string& path, std::string_view bytes, char axis) {
  if (axis != 'x' && axis != 'y')
    throw InputError(fmt::format("commanded motion is read for the x or y axis, not '{}'", axis), path);
  const std::string a = fmt::format("accel_{}", axis), j = fmt::format("jerk_{}", axis);
  CsvOptions co;
  co.columns = {"time", "duration", a, j};
  co.time_column = "time";
  co.time_must_increase = false;  // a piece may start where the one before starts, rounded
  const CsvTable table = parse_csv(bytes, path, co);
  const auto& t = table.column("time").values;
  const auto& d = table.column("duration").values;
  const auto& acc = table.column(a).values;
  const auto& jerk = table.column(j).values;
  std::vector<AccelPiece> out;
  out.reserve(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    const std::size_t row = i + 1 + table.header_line;
    if (!std::isfinite(t[i]) || !std::isfinite(d[i]) || !std::isfinite(acc[i]) || !std::isfinite(jerk[i]))
      throw InputError(fmt::format("line {}: a value that is not a finite number", row), path);
    if (d[i] < 0) throw InputError(fmt::format("line {}: negative duration {} s", row, d[i]), path);
    if (!out.empty() && t[i] < out.back().t0_s)
      throw InputError(
          fmt::format("line {}: the piece starts at {} s, before the one above ({} s)", row, t[i], out.back().t0_s),
          path);
    out.push_back({t[i], d[i], acc[i], jerk[i]});
  }
  if (out.empty()) throw InputError("no commanded motion in the file", path);
  return out;
}

std::string commanded_motion_beside(const std::string& raw_path) {
  namespace fs = std::filesystem;
  const fs::path p(raw_path);
  const std::string name = p.filename().string();
  const std::string prefix = "raw_data_";
  if (name.rfind(prefix, 0) != 0) return {};
  const fs::path beside = p.parent_path() / ("commanded_motion_" + name.substr(prefix.size()));
  std::error_code ec;
  return fs::is_regular_file(beside, ec) ? beside.string() : std::string{};
}

}  // namespace tunekit::ident
