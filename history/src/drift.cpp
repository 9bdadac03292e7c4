#include "tunekit/history/drift.hpp"

#include <algorithm>
#include <cmath>

#include "tunekit/core/error.hpp"

namespace tunekit::history {
namespace {

// The first run of the unbroken stretch of drifted runs that ends at the latest run.
void set_drifted_since(DriftSeries& d) {
  d.drifted_since.reset();
  if (!d.latest_drifted()) return;
  std::size_t k = d.points.size() - 1;
  while (k > 0 && d.points[k - 1].drifted) --k;
  d.drifted_since = k;
}

}  // namespace

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
  d.margin = fitting::equivalence_margin(name);
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
      p.drifted = !d.margin.designed && !p.in_baseline && series[i].text != d.baseline_text;
    } else {
      p.change = series[i].value - d.baseline;
      p.change_pct = d.baseline != 0 ? 100 * p.change / std::fabs(d.baseline) : std::nan("");
      const double u = std::isfinite(series[i].stderr_value) ? series[i].stderr_value : 0;
      p.threshold = o.coverage_k * std::sqrt(u * u + d.baseline_stderr * d.baseline_stderr);
      p.margin = d.margin.relative * std::fabs(d.baseline);
      p.drifted = !d.margin.designed && !p.in_baseline && std::isfinite(p.change) &&
                  fitting::beyond_margin(p.change, p.threshold, p.margin) > 0;
    }
    d.points.push_back(p);
  }
  set_drifted_since(d);
  return d;
}

void follow_designed(std::vector<DriftSeries>& all) {
  for (auto& d : all) {
    if (!d.margin.designed) continue;
    for (auto& p : d.points) {
      p.drifted = false;
      for (const auto& src : all) {
        if (src.margin.designed || std::find(d.margin.designed_from.begin(), d.margin.designed_from.end(), src.name) ==
                                       d.margin.designed_from.end())
          continue;
        for (const auto& q : src.points)
          if (q.point.record_id == p.point.record_id && q.drifted) p.drifted = true;
      }
    }
    set_drifted_since(d);
  }
}

}  // namespace tunekit::history
