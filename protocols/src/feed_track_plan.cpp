// The commanded feed of a liquefier experiment as the firmware plans it (feed_track_plan.hpp).
#include "tunekit/protocols/feed_track_plan.hpp"

#include <algorithm>
#include <cmath>

#include "tunekit/machine/gcode.hpp"

namespace tunekit::protocols {
namespace {

struct FeedMove {
  double length_mm = 0, feed_mm_s = 0;
};

/// The extrude-only moves the load cell records (relative or absolute E; the interpreter knows).
std::vector<FeedMove> recorded_feed_moves(const std::vector<std::string>& gcode) {
  machine::GcodeInterpreter interp;
  std::vector<FeedMove> moves;
  bool recording = false;
  for (const auto& line : gcode) {
    if (line.starts_with(";@record load_cell")) recording = line.ends_with(" on");
    const auto w = machine::parse_gcode(line);
    if (!w) continue;
    const auto m = interp.apply(*w);
    if (recording && m && m->extruder_only() && m->end[3] > m->start[3])
      moves.push_back({m->length_mm(), m->feed_mm_s});
  }
  return moves;
}

/// Entry speeds (mm/s) at each junction: 0 at both ends, at stops, and where the ramps cannot
/// reach the junction's limit within the moves (a forward and a backward pass).
std::vector<double> junction_speeds(const std::vector<FeedMove>& m, double accel, bool stops) {
  const std::size_t n = m.size();
  std::vector<double> v(n + 1, 0.0);
  for (std::size_t i = 1; i < n; ++i) v[i] = stops ? 0.0 : std::min(m[i - 1].feed_mm_s, m[i].feed_mm_s);
  for (std::size_t i = 1; i < n; ++i)
    v[i] = std::min(v[i], std::sqrt(v[i - 1] * v[i - 1] + 2 * accel * m[i - 1].length_mm));
  for (std::size_t i = n - 1; i >= 1; --i)
    v[i] = std::min(v[i], std::sqrt(v[i + 1] * v[i + 1] + 2 * accel * m[i].length_mm));
  return v;
}

void add_point(ident::FeedTrack& k, double t, double u) {
  if (!k.t.empty() && k.t.back() == t && k.u.back() == u) return;
  k.t.push_back(t);
  k.u.push_back(u);
}

}  // namespace

ident::FeedTrack planned_feed_track(const Experiment& e) {
  const auto& x = e.excitation;
  if (!x.contains("extrude_only_accel_mm_s2") || !x.contains("extrude_only_moves_stop")) return {};
  const double a = x.at("extrude_only_accel_mm_s2").get<double>();
  const bool stops = x.at("extrude_only_moves_stop").get<bool>();
  const auto moves = recorded_feed_moves(e.gcode);
  if (moves.empty() || !(a > 0)) return {};
  const auto v = junction_speeds(moves, a, stops);
  ident::FeedTrack k;
  double t = 0;
  for (std::size_t i = 0; i < moves.size(); ++i) {
    const double L = moves[i].length_mm, v0 = v[i], v1 = v[i + 1];
    // The peak: the cruise speed, or lower where the move is too short to reach it.
    const double peak = std::min(moves[i].feed_mm_s, std::sqrt(a * L + 0.5 * (v0 * v0 + v1 * v1)));
    const double t_up = (peak - v0) / a, t_down = (peak - v1) / a;
    const double cruise =
        std::max(0.0, (L - (peak * peak - v0 * v0) / (2 * a) - (peak * peak - v1 * v1) / (2 * a)) / peak);
    add_point(k, t, v0);
    add_point(k, t + t_up, peak);
    add_point(k, t + t_up + cruise, peak);
    t += t_up + cruise + t_down;
    add_point(k, t, v1);
  }
  return k;
}

}  // namespace tunekit::protocols
