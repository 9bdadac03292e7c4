#pragma once
// Drift of one quantity of one machine against the machine's own baseline.
//
// The baseline is the mean of the machine's first `baseline_runs` runs. A later run has
// drifted when the 95 % interval of its change from the baseline lies wholly beyond the
// quantity's equivalence margin m (tunekit/fitting/margins.hpp):
// |x_i - x_b| - k sqrt(u_i^2 + u_b^2) > m |x_b|, with u the standard errors the fits report and
// k the coverage factor (1.96: the 95 % interval of the difference, JCGM 100:2008, "Guide to
// the expression of uncertainty in measurement", sections 5 and 6). A change that may be noise,
// or that is real but too small to change what a compensator does, is not drift. A quantity
// reported without a standard error counts as exact. A designed quantity (the shaper chosen,
// its frequency and acceleration, the advance) is not judged on its own: follow_designed()
// marks it drifted in the runs where a quantity it was designed from drifted.
// "Drifted since" is the first run of the unbroken stretch of drifted runs that ends at the
// latest run: the answer to "since when".

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tunekit/fitting/margins.hpp"
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
  double margin = 0;         ///< the equivalence margin m |x_b|, in the quantity's unit
  bool in_baseline = false;  ///< one of the baseline runs
  bool drifted = false;
};

struct DriftSeries {
  std::string name, unit;
  bool is_text = false;
  fitting::Margin margin;  ///< the quantity's equivalence margin (relative) and why
  double baseline = 0, baseline_stderr = 0;
  std::string baseline_text;
  std::vector<DriftPoint> points;
  /// Index into points of the first run of the drift that lasts to the latest run.
  std::optional<std::size_t> drifted_since;
  bool latest_drifted() const { return !points.empty() && points.back().drifted; }
  /// The latest run's change in percent when it is drift, 0 when it is not
  /// (what `--require 'drift.x.freq_hz>-5%'` compares).
  double significant_change_pct() const;
};

/// Analyses a series (oldest run first). InputError when `baseline_runs` is 0.
DriftSeries analyse_drift(const std::string& name, const std::vector<SeriesPoint>& series, const DriftOptions& options);

/// Marks each designed series' runs drifted where a series it was designed from (when present
/// in `all`) drifted in the same record, and sets its drifted_since to match.
void follow_designed(std::vector<DriftSeries>& all);

}  // namespace tunekit::history
