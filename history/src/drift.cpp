#include "tunekit/history/drift.hpp"

#include <cmath>

#include "tunekit/core/error.hpp"

namespace tunekit::history {

double DriftSeries::significant_change_pct() const {
  if (!latest_drifted() || is_text) return 0;
  const double pct = points.back().change_pct;
  return std::isfinite(pct) ? pct : 0;
}

DriftSeries analyse_drift(const std::string& name, const std::vector<SeriesPoint>& series, const DriftOptions& o) {
  if (o.baseline_runs == 0) throw InputError("the baseline needs at least one run");
  if (!(o.coverage_k > 0) || !std::isfinite(o.coverage_k))
    throw InputError("the coverage factor must be a positive number");
  DriftSeries d;
  d.name = name;
  if (series.empty()) return d;
  d.unit = series.front().unit;
  d.is_text = !series.front().text.empty();
  const std::size_t nb = std::min(o.baseline_runs, series.size());

  if (d.is_text) {
    d.baseline_text = series.front().text;
  } else {
    // Mean of the baseline runs that have a value; its standard error combines theirs.
    double sum = 0, var = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < nb; ++i) {
      if (!std::isfinite(series[i].value)) continue;
      sum += series[i].value;
      const double u = std::isfinite(series[i].stderr_value) ? series[i].stderr_value : 0;
      var += u * u;
      ++n;
    }
    d.baseline = n > 0 ? sum / static_cast<double>(n) : std::nan("");
    d.baseline_stderr = n > 0 ? std::sqrt(var) / static_cast<double>(n) : std::nan("");
  }

  for (std::size_t i = 0; i < series.size(); ++i) {
    DriftPoint p;
    p.point = series[i];
    p.in_baseline = i < nb;
    if (d.is_text) {
      p.change = p.change_pct = std::nan("");
      p.drifted = !p.in_baseline && series[i].text != d.baseline_text;
    } else {
      p.change = series[i].value - d.baseline;
      p.change_pct = d.baseline != 0 ? 100 * p.change / std::fabs(d.baseline) : std::nan("");
      const double u = std::isfinite(series[i].stderr_value) ? series[i].stderr_value : 0;
      p.threshold = o.coverage_k * std::sqrt(u * u + d.baseline_stderr * d.baseline_stderr);
      p.drifted = !p.in_baseline && std::isfinite(p.change) && std::fabs(p.change) > p.threshold;
    }
    d.points.push_back(p);
  }
  if (d.latest_drifted()) {
    std::size_t k = d.points.size() - 1;
    while (k > 0 && d.points[k - 1].drifted) --k;
    d.drifted_since = k;
  }
  return d;
}

}  // namespace tunekit::history
