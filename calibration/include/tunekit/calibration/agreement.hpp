#pragma once
// Agreement of one quantity measured two ways (the liquefier time constant from the step
// response and from the frequency response; an axis mode from a sweep and from a ring-down).
// Two estimates agree when their difference is within the combined 95 % uncertainty,
// |a - b| <= sqrt(h_a^2 + h_b^2), h being the half-width of each 95 % interval.

#include <string>

#include <nlohmann/json.hpp>

namespace tunekit::calibration {

struct Estimate {
  std::string method;  ///< e.g. "step response"
  double value = 0;
  double ci95_lo = 0, ci95_hi = 0;  ///< 95 % interval, same unit as value
};

/// {quantity, unit, estimates: [{method, value, ci95}], difference, combined_half_width, agree,
/// statement}. The statement is one sentence for the report ("... agree within their combined
/// 95 % uncertainty ..." or "... do NOT agree ..."). Throws InputError for non-finite values or
/// an interval that does not contain its value.
nlohmann::json compare_estimates(const std::string& quantity, const std::string& unit, const Estimate& a,
                                 const Estimate& b);

}  // namespace tunekit::calibration
