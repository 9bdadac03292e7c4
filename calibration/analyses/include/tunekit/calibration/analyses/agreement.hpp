#pragma once
// Agreement of one quantity measured two ways (the liquefier time constant from the step
// response and from the frequency response; an axis mode from a sweep and from a ring-down).
// The 95 % interval of the difference is |a - b| +- h, h = sqrt(h_a^2 + h_b^2) combining the
// half-widths of the two 95 % intervals. The two "do NOT agree" only when that interval lies
// wholly beyond the quantity's equivalence margin m |mean| (tunekit/fitting/margins.hpp: a
// difference the compensator designed from it would feel); they are "equivalent" when it lies
// wholly within it, and "undecided" otherwise (the intervals are too wide to tell, which is
// not a disagreement).

#include <string>

#include <nlohmann/json.hpp>

#include "tunekit/fitting/margins.hpp"

namespace tunekit::calibration {

struct Estimate {
  std::string method;  ///< e.g. "step response"
  double value = 0;
  double ci95_lo = 0, ci95_hi = 0;  ///< 95 % interval, same unit as value
};

/// {quantity, unit, estimates: [{method, value, ci95}], difference, combined_half_width,
/// margin: {relative, value, basis}, verdict ("equivalent", "undecided" or "differ"), agree
/// (false only for "differ"), statement}. The statement is one sentence for the report ("... do
/// NOT agree ..." only for "differ"). Throws InputError for non-finite values or an interval
/// that does not contain its value.
nlohmann::json compare_estimates(const std::string& quantity, const std::string& unit, const Estimate& a,
                                 const Estimate& b, const fitting::Margin& margin);

}  // namespace tunekit::calibration
