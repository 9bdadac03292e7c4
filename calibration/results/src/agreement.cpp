#include "tunekit/calibration/results/agreement.hpp"

#include <cmath>

#include <fmt/format.h>

#include "tunekit/calibration/results/display_number.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::calibration {

Agreement compare_estimates(const std::string& quantity, const std::string& unit, const Estimate& a, const Estimate& b,
                            const fitting::Margin& margin) {
  for (const auto* e : {&a, &b}) {
    if (!std::isfinite(e->value) || !std::isfinite(e->ci95_lo) || !std::isfinite(e->ci95_hi))
      throw InputError(fmt::format("{} from the {}: value or interval is not a finite number", quantity, e->method));
    if (!(e->ci95_lo <= e->value && e->value <= e->ci95_hi))
      throw InputError(fmt::format("{} from the {}: the interval [{:g}, {:g}] does not contain the value {:g}",
                                   quantity, e->method, e->ci95_lo, e->ci95_hi, e->value));
  }
  const double ha = 0.5 * (a.ci95_hi - a.ci95_lo), hb = 0.5 * (b.ci95_hi - b.ci95_lo);
  const double combined = std::hypot(ha, hb);
  const double diff = std::abs(a.value - b.value);
  const double m = margin.relative * 0.5 * (std::abs(a.value) + std::abs(b.value));
  const int where = fitting::beyond_margin(diff, combined, m);
  const char* verdict = where > 0 ? "differ" : where < 0 ? "equivalent" : "undecided";
  auto est = [&](const Estimate& e) {
    return fmt::format("{} {} {} {}", e.method, display_number(e.value), display_interval(e.ci95_lo, e.ci95_hi), unit);
  };
  const std::string gap = fmt::format("difference {} ± {} {} (95 %), margin {} {} ({:g} %)", display_number(diff),
                                      display_number(combined), unit, display_number(m), unit, 100 * margin.relative);
  const std::string statement =
      where > 0 ? fmt::format(
                      "{}: {} and {} do NOT agree: the difference lies beyond the margin a compensator "
                      "would feel ({})",
                      quantity, est(a), est(b), gap)
      : where < 0
          ? fmt::format("{}: {} and {} agree: the difference lies within the margin a compensator would feel ({})",
                        quantity, est(a), est(b), gap)
          : fmt::format(
                "{}: {} and {} are not shown to differ by more than the margin a compensator would feel, nor "
                "to lie within it ({})",
                quantity, est(a), est(b), gap);
  Agreement out;
  out.quantity = quantity;
  out.unit = unit;
  out.a = a;
  out.b = b;
  out.difference = diff;
  out.combined_half_width = combined;
  out.margin_relative = margin.relative;
  out.margin_value = m;
  out.margin_basis = margin.basis;
  out.verdict = verdict;
  out.agree = where <= 0;
  out.statement = statement;
  return out;
}

nlohmann::json to_json(const Agreement& a) {
  nlohmann::json ests = nlohmann::json::array();
  for (const auto* e : {&a.a, &a.b})
    ests.push_back({{"method", e->method}, {"value", e->value}, {"ci95", {e->ci95_lo, e->ci95_hi}}});
  nlohmann::json j{{"quantity", a.quantity},
                   {"unit", a.unit},
                   {"estimates", ests},
                   {"difference", a.difference},
                   {"combined_half_width", a.combined_half_width},
                   {"margin", {{"relative", a.margin_relative}, {"value", a.margin_value}, {"basis", a.margin_basis}}},
                   {"verdict", a.verdict},
                   {"agree", a.agree},
                   {"statement", a.statement}};
  if (!a.id.empty()) j["id"] = a.id;
  return j;
}

}  // namespace tunekit::calibration
