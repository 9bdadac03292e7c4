#include "tunekit/calibration/analyses/agreement.hpp"

#include <cmath>

#include <fmt/format.h>

#include "tunekit/calibration/presentation/report.hpp"  // display_number()
#include "tunekit/core/error.hpp"

namespace tunekit::calibration {

nlohmann::json compare_estimates(const std::string& quantity, const std::string& unit, const Estimate& a,
                                 const Estimate& b, const fitting::Margin& margin) {
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
  nlohmann::json ests = nlohmann::json::array();
  for (const auto* e : {&a, &b})
    ests.push_back({{"method", e->method}, {"value", e->value}, {"ci95", {e->ci95_lo, e->ci95_hi}}});
  return {{"quantity", quantity},
          {"unit", unit},
          {"estimates", ests},
          {"difference", diff},
          {"combined_half_width", combined},
          {"margin", {{"relative", margin.relative}, {"value", m}, {"basis", margin.basis}}},
          {"verdict", verdict},
          {"agree", where <= 0},
          {"statement", statement}};
}

}  // namespace tunekit::calibration
