// The commanded feed track and its alignment with a load-cell record (feed_track.hpp).
#include "tunekit/ident/feed_track.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/interpolate.hpp"
#include "tunekit/formats/csv.hpp"

namespace tunekit::ident {

using formats::CsvOptions;
using formats::CsvTable;
using formats::read_csv;

namespace {

// The refinement's search: +-kSearchSamples sample intervals around the start, first on a grid
// of kGridPerSample points per interval, then by golden-section search in the best grid cell.
constexpr double kSearchSamples = 4;
constexpr double kLocalSearchSamples = 2;
constexpr int kGridPerSample = 40;
constexpr int kGoldenIterations = 40;

/// The cumulative integral at every breakpoint, for feed_track_integral.
class TrackIntegral {
 public:
  explicit TrackIntegral(const FeedTrack& k) : k_(k), cum_(k.t.size(), 0.0) {
    for (std::size_t i = 1; i < k.t.size(); ++i)
      cum_[i] = cum_[i - 1] + 0.5 * (k.u[i] + k.u[i - 1]) * (k.t[i] - k.t[i - 1]);
  }
  /// Held at its first value before the track and at its last after it.
  double at(double x) const {
    const auto& t = k_.t;
    if (x <= t.front()) return (x - t.front()) * k_.u.front();
    if (x >= t.back()) return cum_.back() + (x - t.back()) * k_.u.back();
    const std::size_t i = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), x) - t.begin()) - 1;
    const double h = t[i + 1] - t[i], d = x - t[i];
    const double slope = h > 0 ? (k_.u[i + 1] - k_.u[i]) / h : 0.0;
    return cum_[i] + k_.u[i] * d + 0.5 * slope * d * d;
  }
  double total() const { return cum_.back(); }

 private:
  const FeedTrack& k_;
  std::vector<double> cum_;
};

/// Sum of squared differences between the track's window means (shifted by s) and u.
double mismatch(const TrackIntegral& P, const std::vector<double>& edges, std::span<const double> u, double s) {
  double sse = 0, prev = P.at(edges[0] - s);
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double next = P.at(edges[k + 1] - s);
    const double d = (next - prev) / (edges[k + 1] - edges[k]) - u[k];
    sse += d * d;
    prev = next;
  }
  return sse;
}

/// The time at which the cumulative feed of the samples reaches `length`.
double record_time_at_length(const std::vector<double>& edges, std::span<const double> u, double length) {
  double c = 0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double w = u[k] * (edges[k + 1] - edges[k]);
    if (w > 0 && c + w >= length) return edges[k] + (length - c) / u[k];
    c += w;
  }
  return edges.back();
}

/// The time at which the track's integral reaches `length` (bisection; the integral rises).
double track_time_at_length(const TrackIntegral& P, const FeedTrack& k, double length) {
  double lo = k.t.front(), hi = k.t.back();
  for (int i = 0; i < 100 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    (P.at(mid) < length ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

std::string feed_track_csv(const FeedTrack& track) {
  std::string out = "time (s),feed (mm/s)\n";
  for (std::size_t i = 0; i < track.t.size(); ++i) out += fmt::format("{:.9f},{:.6f}\n", track.t[i], track.u[i]);
  return out;
}

FeedTrack read_feed_track_csv(const std::string& path) {
  const MappedFileBytes bytes(path);
  return parse_feed_track_csv(bytes.view(), path);
}

FeedTrack parse_feed_track_csv(std::string_view text, const std::string& path) {
  CsvOptions o;
  o.time_must_increase = false;
  const CsvTable table = parse_csv(text, path, o);
  if (table.columns.size() < 2 || table.rows < 2)
    throw InputError("a feed track needs two columns (time, feed) and at least two rows", path);
  FeedTrack k{table.columns[0].values, table.columns[1].values};
  for (std::size_t i = 0; i < k.t.size(); ++i) {
    const std::size_t line = table.header_line + i + 1;
    if (i > 0 && k.t[i] < k.t[i - 1])
      throw InputError(fmt::format("the feed track's time decreases ({} s after {} s)", k.t[i], k.t[i - 1]),
                       source_location(path, line));
    if (k.u[i] < 0)
      throw InputError(fmt::format("the feed track's feed is negative ({})", k.u[i]), source_location(path, line));
  }
  return k;
}

std::vector<double> sample_window_edges(std::span<const double> t) {
  const std::size_t n = t.size();
  std::vector<double> e(n + 1);
  e[0] = t[0] - 0.5 * (t[1] - t[0]);
  for (std::size_t i = 1; i < n; ++i) e[i] = 0.5 * (t[i - 1] + t[i]);
  e[n] = t[n - 1] + 0.5 * (t[n - 1] - t[n - 2]);
  return e;
}

double feed_track_integral(const FeedTrack& track, double x) { return TrackIntegral(track).at(x); }

namespace {

/// The offset minimising the mismatch over samples [k0, k1): a grid of kGridPerSample points per
/// sample interval over s0 +- `reach` intervals, then golden-section search in the best cell.
double refine_offset(const TrackIntegral& P, const std::vector<double>& edges, std::span<const double> u,
                     std::size_t k0, std::size_t k1, double s0, double dt, double reach) {
  const std::vector<double> e(edges.begin() + static_cast<std::ptrdiff_t>(k0),
                              edges.begin() + static_cast<std::ptrdiff_t>(k1) + 1);
  const auto uu = u.subspan(k0, k1 - k0);
  auto f = [&](double s) { return mismatch(P, e, uu, s); };
  const double cell = dt / kGridPerSample;
  double best_s = s0, best = std::numeric_limits<double>::infinity();
  const int n_grid = static_cast<int>(2 * reach * kGridPerSample);
  for (int i = 0; i <= n_grid; ++i) {
    const double s = s0 - reach * dt + i * cell;
    const double v = f(s);
    if (v < best) best = v, best_s = s;
  }
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double a = best_s - cell, b = best_s + cell;
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = f(c), fd = f(d);
  for (int i = 0; i < kGoldenIterations; ++i) {
    if (fc < fd) b = d, d = c, fd = fc, c = b - g * (b - a), fc = f(c);
    else a = c, c = d, fc = fd, d = a + g * (b - a), fd = f(d);
  }
  const double s = fc < fd ? c : d;
  return std::min(fc, fd) < best ? s : best_s;
}

/// The offset at record time x: linear between the local offsets, held beyond; `global` without any.
double offset_at(const FeedTrackAlignment& a, double x) {
  const auto& t = a.local_t;
  if (t.empty()) return a.offset_s;
  return fitting::interp_linear(t, a.local_offset_s, x);
}

/// Whether the track (placed by offset s) changes its feed within record times [lo, hi].
bool feed_changes_within(const FeedTrack& k, double s, double lo, double hi) {
  const auto first = std::lower_bound(k.t.begin(), k.t.end(), lo - s);
  return first != k.t.end() && *first + s <= hi;
}

}  // namespace

FeedTrackAlignment align_feed_track(const FeedTrack& track, std::span<const double> t, std::span<const double> u) {
  if (t.size() < 3 || t.size() != u.size()) throw InputError("feed track: the record is too short to align it");
  if (track.t.size() < 2 || track.t.size() != track.u.size())
    throw InputError("feed track: it needs at least two breakpoints");
  const TrackIntegral P(track);
  const auto edges = sample_window_edges(t);
  double fed = 0;
  for (std::size_t k = 0; k < u.size(); ++k) fed += u[k] * (edges[k + 1] - edges[k]);
  if (!(fed > 0) || !(P.total() > 0)) throw InputError("feed track: the record or the track feeds nothing");
  // Start: the instants at which half of the smaller of the two lengths is fed.
  const double half = 0.5 * std::min(fed, P.total());
  const double s0 = record_time_at_length(edges, u, half) - track_time_at_length(P, track, half);
  const double dt = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  FeedTrackAlignment r;
  r.offset_s = refine_offset(P, edges, u, 0, u.size(), s0, dt, kSearchSamples);
  for (std::size_t k0 = 0; k0 < u.size(); k0 += kFeedTrackSegment) {
    const std::size_t k1 = std::min(u.size(), k0 + kFeedTrackSegment);
    if (!feed_changes_within(track, r.offset_s, edges[k0], edges[k1])) continue;
    r.local_t.push_back(0.5 * (edges[k0] + edges[k1]));
    r.local_offset_s.push_back(refine_offset(P, edges, u, k0, k1, r.offset_s, dt, kLocalSearchSamples));
  }
  r.aligned = track;
  for (double& x : r.aligned.t) x += offset_at(r, x + r.offset_s);
  // A time-varying offset could reorder two breakpoints closer than its change: keep them in order.
  for (std::size_t i = 1; i < r.aligned.t.size(); ++i) r.aligned.t[i] = std::max(r.aligned.t[i], r.aligned.t[i - 1]);
  const double sse = mismatch(TrackIntegral(r.aligned), edges, u, 0.0);
  r.rms_mismatch = std::sqrt(sse / static_cast<double>(u.size()));
  r.feed_scale = *std::max_element(u.begin(), u.end());
  r.matches = r.rms_mismatch <= kFeedTrackMismatch * r.feed_scale;
  return r;
}

}  // namespace tunekit::ident
