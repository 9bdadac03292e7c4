#pragma once
// Drift of one quantity of one machine against the machine's own baseline.
//
// The baseline is the mean of the machine's first `baseline_runs` runs. A later run has
// drifted when its change from the baseline is larger than the combined uncertainty of the
// two: |x_i - x_b| > k sqrt(u_i^2 + u_b^2), with u the standard errors the fits report and
// k the coverage factor (1.96: the 95 % interval of the difference, JCGM 100:2008, "Guide to
// the expression of uncertainty in measurement", sections 5 and 6). A change within that interval is
// noise, not drift. A quantity reported without a standard error counts as exact, and a
// word-valued one (the shaper type) has drifted when it differs from the baseline's.
// "Drifted since" is the first run of the unbroken stretch of drifted runs that ends at the
// latest run: the answer to "since when".

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tunekit/history/store.hpp"

namespace tunekit::history {

struct DriftOptions {
  std::size_t baseline_runs = 1;  ///< the first N runs form the baseline
  double coverage_k = 1.96;       ///< k of the interval a change must leave to count as drift
};

struct DriftPoint {
  SeriesPoint point;
  double change = 0;         ///< value - baseline, in the quantity's unit
  double change_pct = 0;     ///< 100 (value - baseline) / |baseline|; NaN when the baseline is 0
  double threshold = 0;      ///< k sqrt(u_i^2 + u_b^2), in the quantity's unit
  bool in_baseline = false;  ///< one of the baseline runs
  bool drifted = false;
};

struct DriftSeries {
  std::string name, unit;
  bool is_text = false;
  double baseline = 0, baseline_stderr = 0;
  std::string baseline_text;
  std::vector<DriftPoint> points;
  /// Index into points of the first run of the drift that lasts to the latest run.
  std::optional<std::size_t> drifted_since;
  bool latest_drifted() const { return !points.empty() && points.back().drifted; }
  /// The latest run's change in percent when it is drift, 0 when it is within the uncertainty
  /// (what `--require 'drift.x.freq_hz>-5%'` compares).
  double significant_change_pct() const;
};

/// Analyses a series (oldest run first). InputError when `baseline_runs` is 0.
DriftSeries analyse_drift(const std::string& name, const std::vector<SeriesPoint>& series, const DriftOptions& options);

}  // namespace tunekit::history
