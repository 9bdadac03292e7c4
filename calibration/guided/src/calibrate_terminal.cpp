// tunekit calibrate, what the technician reads after the progress: the identified quantities with
// their 95 % intervals, the configuration's settings (current, proposed, change), the diff, and
// what to do next (the same lines `tunekit export` prints: preview or written with its backup,
// then what the firmware needs to use the new values).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ostream>

#include <fmt/format.h>

#include "calibrate_stages.hpp"
#include "tunekit/calibration/results/json_access.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/results/calibration_record.hpp"

namespace tunekit::calibration {
namespace {

// One line of the identified quantities: label, value with unit, interval or basis.
struct QuantityLine {
  std::string label, value, interval;
};

std::string with_unit(double v, const std::string& unit) {
  return unit.empty() || unit == "1" ? display_number(v) : display_number(v) + " " + unit;
}

std::string interval_text(const SummaryRow& row) {
  if (row.ci_path.empty()) return row.basis;
  if (!row.estimate.has_interval()) return "n/a";
  return display_interval(row.estimate.ci95_lo, row.estimate.ci95_hi);
}

std::vector<QuantityLine> quantity_lines(const CalibrationRecord& record) {
  std::vector<QuantityLine> lines;
  for (const auto& row : record.summary)
    if (row.estimate.has_value())
      lines.push_back({row.label, with_unit(row.estimate.value, row.unit), interval_text(row)});
  return lines;
}

// The relative change of a numeric setting ("+12 %"), else empty (a new line, a word).
std::string change_text(const std::string& before, const std::string& after) {
  char* end_a = nullptr;
  char* end_b = nullptr;
  const double a = std::strtod(before.c_str(), &end_a), b = std::strtod(after.c_str(), &end_b);
  if (before.empty() || *end_a != '\0' || *end_b != '\0' || !std::isfinite(a) || !std::isfinite(b)) {
    return before.empty() ? "new" : "changed";
  }
  if (a == 0) return b == 0 ? "unchanged" : "from 0";
  return fmt::format("{:+.0f} %", 100 * (b - a) / std::abs(a));
}

void print_quantities(const std::vector<QuantityLine>& lines, std::ostream& os) {
  std::size_t w0 = std::string("quantity").size(), w1 = std::string("value").size();
  for (const auto& l : lines) {
    w0 = std::max(w0, l.label.size());
    w1 = std::max(w1, l.value.size());
  }
  os << fmt::format("{:<{}}  {:<{}}  {}\n", "quantity", w0, "value", w1, "95 % interval");
  for (const auto& l : lines) os << fmt::format("{:<{}}  {:<{}}  {}\n", l.label, w0, l.value, w1, l.interval);
}

void print_settings(const ExportOutcome& ex, std::ostream& os) {
  const auto& changes = ex.change.changes;
  if (changes.empty()) return;
  std::size_t w0 = std::string("setting").size(), w1 = std::string("current").size(),
              w2 = std::string("proposed").size();
  for (const auto& c : changes) {
    w0 = std::max(w0, c.key.size());
    w1 = std::max(w1, c.old_value.empty() ? std::size_t{1} : c.old_value.size());
    w2 = std::max(w2, c.new_value.size());
  }
  os << fmt::format("\nconfiguration {}:\n", ex.options.config);
  os << fmt::format("{:<{}}  {:<{}}  {:<{}}  {}\n", "setting", w0, "current", w1, "proposed", w2, "change");
  for (const auto& c : changes)
    os << fmt::format("{:<{}}  {:<{}}  {:<{}}  {}\n", c.key, w0, c.old_value.empty() ? "-" : c.old_value, w1,
                      c.new_value, w2, change_text(c.old_value, c.new_value));
}

}  // namespace

void print_calibrate_terminal(const CalibrationRecord& record, const CompensatorDesign& design,
                              const std::string& report, std::ostream& os) {
  const ExportOutcome& ex = design.exported;
  os << "\n";
  print_quantities(quantity_lines(record), os);
  print_settings(ex, os);
  const std::string& diff = ex.change.diff;
  if (!diff.empty()) os << "\n" << diff << (diff.back() == '\n' ? "" : "\n");
  os << "\nnext:\n";
  os << "  " << configuration_status(ex) << "\n";
  if (ex.change.changed())
    for (const auto& n : ex.change.notes) os << "  " << n << "\n";
  os << fmt::format("report: {}\n", report);
}

}  // namespace tunekit::calibration
