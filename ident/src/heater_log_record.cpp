#include "tunekit/ident/heater_log_record.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::ident {

ThermalRecord thermal_record_from_heater_log(const formats::HeaterLog& log, const formats::HeaterRun& run) {
  if (run.begin >= run.end || run.end > log.t_s.size())
    throw InputError(
        fmt::format("the heater log has no samples {} to {} (it has {})", run.begin, run.end, log.t_s.size()));
  ThermalRecord r;
  const double t0 = log.t_s[run.begin];
  for (std::size_t i = run.begin; i < run.end; ++i) {
    r.t_s.push_back(log.t_s[i] - t0);
    r.temp_c.push_back(log.temp_c[i]);
    r.heater_duty.push_back(log.duty[i]);
    r.target_c.push_back(log.target_c[i]);
  }
  return r;
}

formats::HeaterRun heated_run(const formats::HeaterLog& log) {
  formats::HeaterRun best;
  for (const auto& run : formats::heater_runs(log)) {
    const auto first = log.target_c.begin() + static_cast<std::ptrdiff_t>(run.begin);
    const auto last = log.target_c.begin() + static_cast<std::ptrdiff_t>(run.end);
    const bool heated = std::any_of(first, last, [](double t) { return t > 0; });
    if (heated && run.end - run.begin > best.end - best.begin) best = run;
  }
  if (best.end == best.begin)
    throw InputError(
        fmt::format("the heater '{}' is never given a target in the log: there is no heat-up to fit", log.heater));
  return best;
}

}  // namespace tunekit::ident
