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

/// The comparison of two estimates of one quantity.
struct Agreement {
  std::string id;  ///< the quantity's short name in the report ("tau", "theta"); empty: none given
  std::string quantity, unit;
  Estimate a, b;                   ///< the two estimates compared
  double difference = 0;           ///< |a - b|, in unit
  double combined_half_width = 0;  ///< h = sqrt(h_a^2 + h_b^2), in unit
  double margin_relative = 0;      ///< the equivalence margin as a fraction of the mean |value|
  double margin_value = 0;         ///< the same margin in unit
  std::string margin_basis;        ///< one sentence: why this margin
  std::string verdict;             ///< "equivalent", "undecided" or "differ"
  bool agree = true;               ///< false only for "differ"
  std::string statement;           ///< one sentence for the report ("... do NOT agree ..." only for "differ")
};

/// Compares two estimates by the rule above. Throws InputError for non-finite values or an
/// interval that does not contain its value.
Agreement compare_estimates(const std::string& quantity, const std::string& unit, const Estimate& a, const Estimate& b,
                            const fitting::Margin& margin);

/// An agreement as results JSON holds it: {id (when given), quantity, unit, estimates: [{method,
/// value, ci95}], difference, combined_half_width, margin: {relative, value, basis}, verdict,
/// agree, statement}.
nlohmann::json to_json(const Agreement& a);

}  // namespace tunekit::calibration
