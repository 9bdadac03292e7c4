#include "tunekit/calibration/results/display_number.hpp"

#include <cmath>

#include <fmt/format.h>

namespace tunekit::calibration {

std::string display_number(double v) {
  if (!std::isfinite(v)) return "n/a";
  return fmt::format("{:.4g}", v);
}

std::string display_interval(double lo, double hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) return fmt::format("[{}, {}]", display_number(lo), display_number(hi));
  // 8 significant digits tell apart bounds 1e-7 apart relative to their size: an interval narrower
  // than that is a measurement's rounding, not information, and prints as equal bounds.
  constexpr int kMaxDigits = 8;
  int digits = 4;
  while (digits < kMaxDigits && lo != hi && fmt::format("{:.{}g}", lo, digits) == fmt::format("{:.{}g}", hi, digits))
    ++digits;
  return fmt::format("[{:.{}g}, {:.{}g}]", lo, digits, hi, digits);
}

}  // namespace tunekit::calibration
