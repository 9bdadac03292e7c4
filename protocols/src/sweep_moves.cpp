// The axis sweep's motion as Klipper's resonance test plans it (see sweep_moves.hpp).
#include "sweep_moves.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/firmware/firmware_limits.hpp"

namespace tunekit::protocols::experiment_gcode {
namespace {

// Klipper runs the pulses while f <= freq_end + 1e-6 (VibrationPulseTestGenerator.gen_test).
constexpr double kFreqEndSlack_hz = 1e-6;
// A commanded acceleration below this is none: the piece is a cruise (Klipper: 1e-6, run_test;
// the moves write accelerations with three decimals).
constexpr double kZeroAccel_mm_s2 = 1e-3;
// A speed below this is rest (Klipper: 1e-6, run_test).
constexpr double kRest_mm_s = 1e-6;
// A slowest point of the motion (the speed falls, then rises, without stopping) is held by a
// cruise this long at that speed: its F caps both junctions (a planner joins two moves in the
// same direction at the lower of their speeds), as Klipper's limit_next_junction_speed does
// inside TEST_RESONANCES. At least kMinCruise_mm long, so that it survives the 1e-5 mm of the
// written positions; below kStopBelow_mm_s the planner is brought to rest there instead.
constexpr double kCruise_s = 2e-5;
constexpr double kMinCruise_mm = 5e-5;
constexpr double kStopBelow_mm_s = 1.0;
constexpr double kSpeedTolerance = 1e-9;
// A move shorter than the written positions' resolution (1e-5 mm) is left out: a firmware skips
// a move of no length, and the motion it stood for (a reversal at a few hundredths of a mm/s, a
// sliver of a piece) is below a step.
constexpr double kMinMove_mm = 1e-5;

/// One constant-acceleration piece of motion with its signed speeds at both ends (mm/s).
struct Piece {
  double accel = 0, v0 = 0, v1 = 0, dur = 0;
  double dir() const { return v0 + v1 >= 0 ? 1.0 : -1.0; }
  double peak() const { return std::max(std::abs(v0), std::abs(v1)); }
};

/// The pieces of motion of `segments` from rest; a piece whose speed changes sign is split at
/// the stop, as run_test splits it ("first goes to a complete stop, then changes direction").
std::vector<Piece> pieces_of(const std::vector<SweepSegment>& segments) {
  std::vector<Piece> out;
  double t = 0, v = 0;
  for (const auto& s : segments) {
    const double dur = s.t_end_s - t;
    t = s.t_end_s;
    if (dur <= 0) continue;
    const double a = std::abs(s.accel_mm_s2) < kZeroAccel_mm_s2 ? 0.0 : s.accel_mm_s2;
    double v1 = v + a * dur;
    if (std::abs(v1) < kRest_mm_s) v1 = 0;
    if (v * v1 < 0) {
      const double t_stop = -v / a;
      out.push_back({a, v, 0, t_stop});
      out.push_back({a, 0, v1, dur - t_stop});
    } else {
      out.push_back({a, v, v1, dur});
    }
    v = v1;
  }
  return out;
}

/// Two pieces run as one move: the same direction and acceleration, and no slowest point
/// between them (the speed does not fall and then rise).
bool joinable(const Piece& a, const Piece& b) {
  if (a.accel == 0 || std::abs(a.accel) != std::abs(b.accel) || a.dir() != b.dir()) return false;
  if (std::abs(a.v1) < kRest_mm_s) return false;
  const bool a_falls = std::abs(a.v1)<std::abs(a.v0), b_rises = std::abs(b.v1)> std::abs(b.v0);
  return !(a_falls && b_rises);
}

SweepMove move_of(const Piece& p) {
  SweepMove m;
  m.dist_mm = 0.5 * (p.v0 + p.v1) * p.dur;
  m.accel_mm_s2 = std::abs(p.accel);
  m.feed_mm_s = p.peak();
  m.v_start = std::abs(p.v0);
  m.v_end = std::abs(p.v1);
  m.duration_s = p.dur;
  if (p.accel == 0 && p.v0 == 0) m.dwell_s = p.dur;  // no acceleration at rest: a rest (run_test)
  return m;
}

/// The moves of the pieces, joined where a planner runs them as one move.
std::vector<SweepMove> joined_moves(const std::vector<Piece>& pieces) {
  std::vector<SweepMove> out;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    SweepMove m = move_of(pieces[i]);
    while (i + 1 < pieces.size() && joinable(pieces[i], pieces[i + 1])) {
      const SweepMove n = move_of(pieces[++i]);
      m.dist_mm += n.dist_mm;
      m.feed_mm_s = std::max(m.feed_mm_s, n.feed_mm_s);
      m.v_end = n.v_end;
      m.duration_s += n.duration_s;
    }
    if (std::abs(m.dist_mm) >= kMinMove_mm || m.dwell_s > 0) out.push_back(m);
  }
  return out;
}

/// The slowest points between moves in the same direction held (see kCruise_s).
std::vector<SweepMove> hold_slowest_points(const std::vector<SweepMove>& moves) {
  std::vector<SweepMove> out;
  for (std::size_t i = 0; i < moves.size(); ++i) {
    out.push_back(moves[i]);
    if (i + 1 == moves.size()) break;
    const SweepMove& next = moves[i + 1];
    const double v = moves[i].v_end;
    if (moves[i].dwell_s > 0 || next.dwell_s > 0) continue;  // a rest stops the planner anyway
    const bool same_dir = (moves[i].dist_mm > 0) == (next.dist_mm > 0);
    const bool slowest = moves[i].feed_mm_s > v + kSpeedTolerance && next.feed_mm_s > v + kSpeedTolerance;
    if (!same_dir || !slowest) continue;
    if (v < kStopBelow_mm_s) {
      out.back().stop_after = true;
      continue;
    }
    const double len = std::max(v * kCruise_s, kMinCruise_mm);
    out.push_back({std::copysign(len, moves[i].dist_mm), 0, v, v, v, false, 0, len / v});
  }
  return out;
}

}  // namespace

std::vector<SweepSegment> vibration_pulses(const SweepDesign& d) {
  std::vector<SweepSegment> out;
  double t = 0, f = d.freq_start_hz, sign = 1;
  while (f <= d.freq_end_hz + kFreqEndSlack_hz) {
    const double quarter = 0.25 / f;
    // accel_per_hz f up to the axis' limit, then held there (the fit against the commanded motion
    // does not need the amplitude to grow with f).
    double a = std::min(d.accel_per_hz * f, d.pulse_accel_cap());
    // A half period at +-a from rest to rest covers a quarter^2.
    if (a * quarter * quarter < 1.5 * d.min_half_mm) a = 1.5 * d.min_half_mm / (quarter * quarter);
    if (a > d.pulse_accel_cap())
      throw InputError(fmt::format(
          "axis-sweep at {:.1f} Hz on Marlin: a half period must move at least {} steps (MIN_STEPS_PER_SEGMENT, "
          "Configuration_adv.h) = {:.4g} mm, which needs {:.0f} mm/s^2, above the {:.0f} mm/s^2 the axis limit "
          "leaves the pulses; lower freq_end_hz or raise [firmware_state] steps_per_mm",
          f, firmware::limits::kMarlinMinStepsPerSegment, d.min_half_mm, a, d.pulse_accel_cap()));
    t += quarter;
    out.push_back({t, sign * a, f});
    t += quarter;
    out.push_back({t, -sign * a, f});
    f += 2 * quarter * d.hz_per_sec;
    sign = -sign;
  }
  return out;
}

std::vector<SweepSegment> add_sweeping(const std::vector<SweepSegment>& pulses, const SweepDesign& d) {
  if (!d.sweeping()) return pulses;
  const double period = d.sweeping_period_s, s_accel = d.sweeping_accel_mm_s2;
  // The first switch comes early (period sqrt(2)/8) so that the motion swings about its start.
  double next_switch = period * std::sqrt(2.0) / 8, gap = period * (std::sqrt(2.0) / 8 + 0.25), sign = 1;
  std::vector<SweepSegment> out;
  for (const auto& p : pulses) {
    while (next_switch <= p.t_end_s) {
      out.push_back({next_switch, p.accel_mm_s2 + sign * s_accel, p.freq_hz});
      sign = -sign;
      next_switch += gap;
      gap = period / 2;
    }
    out.push_back({p.t_end_s, p.accel_mm_s2 + sign * s_accel, p.freq_hz});
  }
  return out;
}

SweepDesign sweep_design_from_params(const std::map<std::string, double>& p, double max_accel_mm_s2) {
  SweepDesign d;
  d.freq_start_hz = p.at("freq_start_hz");
  d.freq_end_hz = p.at("freq_end_hz");
  d.hz_per_sec = p.at("hz_per_sec");
  d.accel_per_hz = p.at("accel_per_hz");
  d.sweeping_accel_mm_s2 = p.at("sweeping_accel");
  d.sweeping_period_s = p.at("sweeping_period");
  d.max_accel_mm_s2 = max_accel_mm_s2;
  return d;
}

std::vector<SweepMove> sweep_moves(const std::vector<SweepSegment>& segments, double stop_accel_mm_s2) {
  std::vector<SweepMove> moves = hold_slowest_points(joined_moves(pieces_of(segments)));
  if (!moves.empty() && moves.back().v_end > kRest_mm_s) {
    // Ends moving: to rest at stop_accel, on in the direction of motion (run_test).
    const double v = moves.back().v_end;
    moves.push_back({std::copysign(v * v / (2 * stop_accel_mm_s2), moves.back().dist_mm), stop_accel_mm_s2, v, v, 0,
                     false, 0, v / stop_accel_mm_s2});
  }
  return moves;
}

double sweeping_excursion_mm(const SweepDesign& d) {
  return d.sweeping() ? d.sweeping_accel_mm_s2 * d.sweeping_period_s * d.sweeping_period_s / 32 : 0.0;
}

}  // namespace tunekit::protocols::experiment_gcode
