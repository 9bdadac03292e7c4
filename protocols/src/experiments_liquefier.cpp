// The liquefier protocols: feed steps (liquefier-step), a flow sweep (liquefier-flow-sweep) and
// sine dwells or a chirp of the feed (liquefier-sine, liquefier-chirp), with the load cell recording.
#include "tunekit/protocols/experiments.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/protocols/chirp_plan.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/protocols/camera_prints.hpp"
#include "tunekit/protocols/coverage_planner.hpp"
#include "tunekit/protocols/flow_sweep_plan.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/machine/trajectory.hpp"

#include "experiment_gcode.hpp"
#include "machine_defaults.hpp"

namespace tunekit::protocols::experiment_gcode {

namespace {

// The longest staircase step of a chirp sized from a time constant, s: fewer, longer moves keep
// the delivered feed close to the recorded staircase on a firmware that stops after every
// extrude-only move (Klipper), while 50 ms still resolves the liquefier's slowest corners.
constexpr double kLongestChirpStep_s = kLongestStaircaseStep_s;

/// The chirp sized from expected_tau_s (chirp_plan.hpp): its band, duration and settle time, and
/// a staircase step as long as the chirp's end allows (ten per period, at most 50 ms) but never
/// shorter than the machine's (segment_s as filled in from its limits); what the caller set stays.
void size_chirp(const std::map<std::string, double>& overrides, Experiment& e) {
  auto& p = e.params;
  const double shortest = p.at("segment_s");
  const auto plan = plan_liquefier_chirp(p.at("expected_tau_s"), shortest);
  if (!overrides.count("segment_s")) {
    p["segment_s"] = std::max(shortest, std::min(kLongestChirpStep_s, 1.0 / (10 * plan.freq_max_hz)));
    if (p["segment_s"] > shortest)
      e.excitation["machine_defaults"]["segment_s"] = fmt::format(
          "as long as the chirp's end {:.3g} Hz allows (ten steps a period, at most {:g} s); the machine's shortest "
          "is {:.3g} s",
          plan.freq_max_hz, kLongestChirpStep_s, shortest);
  }
  for (const auto& [k, v] : {std::pair{"freq_min_hz", plan.freq_min_hz}, std::pair{"freq_max_hz", plan.freq_max_hz},
                             std::pair{"duration_s", plan.duration_s}, std::pair{"settle_s", plan.settle_s}})
    if (!overrides.count(k)) p[k] = v;
}

// The flow sweep: every level of plan_flow_sweep reached from below and from above (the range
// from the profile's hot end when not given), recorded by the load cell.
void build_flow_sweep(const ExperimentRequest& r, Experiment& e) {
  const std::string& protocol = r.protocol;
  const machine::MachineProfile& profile = r.profile;
  const firmware::Dialect& d = r.dialect;
  const ProtocolLimits& limits = r.limits;
  auto& p = e.params;
  auto& g = e.gcode;
  auto guard = [&] { guard_line_count(g, r.limits, r.protocol); };
  const double area = profile.filament_area_mm2();
  if (std::isnan(p["flow_max_mm3_s"])) {
    double limit = std::numeric_limits<double>::infinity();
    if (profile.extruder.max_flow_mm3_s > 0) limit = profile.extruder.max_flow_mm3_s;
    if (profile.extruder.max_velocity_mm_s > 0) limit = std::min(limit, profile.extruder.max_velocity_mm_s * area);
    if (!std::isfinite(limit))
      throw InputError(
          "liquefier-flow-sweep needs the hot end's range: give flow_max_mm3_s, or max_flow_mm3_s in the "
          "profile's [extruder]");
    p["flow_max_mm3_s"] = 0.9 * limit;
  }
  if (std::isnan(p["flow_min_mm3_s"])) p["flow_min_mm3_s"] = p["flow_max_mm3_s"] / 10;
  const auto plan =
      plan_flow_sweep(p.at("flow_min_mm3_s"), p.at("flow_max_mm3_s"), static_cast<int>(p.at("levels")),
                      static_cast<int>(p.at("cycles")), p.at("expected_tau_s"), p.at("hold_taus"), p.at("settle_s"));
  double lines = 10;
  for (double q : plan.sequence_mm3_s)
    lines += std::ceil(q / area * plan.hold_s / std::max(profile.extruder.max_extrude_only_distance_mm, 1e-3)) + 1;
  check_plan(protocol, lines, plan.duration_s(), limits);
  std::vector<std::string> restore;
  const FeedPlan fp = liquefier_prologue(g, restore, p, profile, d);
  record_feed_plan(e, fp);
  nlohmann::json levels = nlohmann::json::array();
  std::string level_text;
  for (double q : plan.measured_flows_mm3_s) {
    levels.push_back(q);
    level_text += (level_text.empty() ? "" : ", ") + num(q, 3);
  }
  e.excitation["measured_flows_mm3_s"] = levels;
  e.excitation["turning_flows_mm3_s"] = {plan.flow_min_mm3_s, plan.flow_max_mm3_s};
  e.excitation["hold_s"] = plan.hold_s;
  g.push_back(fmt::format("; flow levels {} mm^3/s (ratio {}), turning at {} and {} mm^3/s, {} s each", level_text,
                          num(plan.ratio, 3), num(plan.flow_min_mm3_s), num(plan.flow_max_mm3_s), num(plan.hold_s, 3)));
  g.push_back(";@record load_cell on");
  for (std::size_t i = 0; i < plan.sequence_mm3_s.size(); ++i) {
    feed_move(g, fp, plan.sequence_mm3_s[i] / area, i == 0 ? plan.settle_s : plan.hold_s);
    guard();
  }
  g.push_back(d.wait_for_moves());
  g.push_back(";@record load_cell off");
  epilogue(g, restore);
}

// Sine dwells (log-spaced frequencies, a number of periods each) or a linear chirp of the feed
// about its mean, recorded by the load cell.
void build_sine_or_chirp(const ExperimentRequest& r, Experiment& e) {
  const std::string& protocol = r.protocol;
  const machine::MachineProfile& profile = r.profile;
  const firmware::Dialect& d = r.dialect;
  const ProtocolLimits& limits = r.limits;
  const auto& overrides = r.overrides;
  auto& p = e.params;
  auto& g = e.gcode;
  auto guard = [&] { guard_line_count(g, r.limits, r.protocol); };
  const double mean = p.at("feed_mean_mm_s");
  const double amp = p.at("amplitude_mm_s");
  if (amp >= mean) throw InputError("amplitude_mm_s must be in [0, feed_mean_mm_s) so the feed stays positive");
  if (protocol == "liquefier-chirp" && p.at("expected_tau_s") != 0) size_chirp(overrides, e);
  const double seg = p.at("segment_s");
  const double f0 = p.at("freq_min_hz"), f1 = p.at("freq_max_hz");
  std::vector<std::string> restore;
  FeedPlan fp;
  if (protocol == "liquefier-sine") {
    const int n = static_cast<int>(p.at("freq_count"));
    const double periods = p.at("periods");
    auto freq = [&](int i) { return n == 1 ? f0 : f0 * std::pow(f1 / f0, static_cast<double>(i) / (n - 1)); };
    double lines = 0, seconds = 3;
    for (int i = 0; i < n; ++i) {
      const double f = freq(i), dt = std::min(seg, 1.0 / (20 * f));
      lines += std::ceil(periods / f / dt) + 1;
      seconds += periods / f;
    }
    check_plan(protocol, lines + 10, seconds, limits);
    fp = liquefier_prologue(g, restore, p, profile, d);
    record_feed_plan(e, fp);
    g.push_back(";@record load_cell on");
    feed_move(g, fp, mean, 2.0);  // steady state first
    for (int i = 0; i < n; ++i) {
      const double f = freq(i);
      const double dt = std::min(seg, 1.0 / (20 * f));
      const long steps = static_cast<long>(std::ceil(periods / f / dt));
      g.push_back(fmt::format("; dwell at {} Hz", num(f, 4)));
      for (long k = 0; k < steps; ++k) {
        feed_move(g, fp, mean + amp * std::sin(2 * std::numbers::pi * f * (static_cast<double>(k) + 0.5) * dt), dt);
        guard();
      }
    }
  } else {
    const double T = p.at("duration_s");
    check_plan(protocol, std::ceil(T / seg) + 10, T + p.at("settle_s") + 1, limits);
    fp = liquefier_prologue(g, restore, p, profile, d);
    record_feed_plan(e, fp);
    g.push_back(";@record load_cell on");
    feed_move(g, fp, mean, p.at("settle_s"));  // steady state first
    const long steps = static_cast<long>(std::ceil(T / seg));
    for (long k = 0; k < steps; ++k) {
      const double t = (static_cast<double>(k) + 0.5) * seg;
      const double phase = 2 * std::numbers::pi * (f0 * t + 0.5 * (f1 - f0) / T * t * t);
      feed_move(g, fp, mean + amp * std::sin(phase), seg);
      guard();
    }
  }
  feed_move(g, fp, mean, 1.0);
  g.push_back(d.wait_for_moves());
  g.push_back(";@record load_cell off");
  epilogue(g, restore);
}

}  // namespace

bool build_liquefier_experiment(const ExperimentRequest& r, Experiment& e) {
  const std::string& protocol = r.protocol;
  const machine::MachineProfile& profile = r.profile;
  const firmware::Dialect& d = r.dialect;
  const ProtocolLimits& limits = r.limits;
  auto& p = e.params;
  auto& g = e.gcode;
  if (protocol == "liquefier-step") {
    const double cycles_d = p.at("cycles");
    check_plan(protocol, 2 * cycles_d + 8, p.at("settle_s") + 2 * cycles_d * p.at("hold_s"), limits);
    const int cycles = static_cast<int>(cycles_d);
    std::vector<std::string> restore;
    const FeedPlan fp = liquefier_prologue(g, restore, p, profile, d);
    record_feed_plan(e, fp);
    g.push_back(";@record load_cell on");
    feed_move(g, fp, p["feed_low_mm_s"], p["settle_s"]);
    for (int c = 0; c < cycles; ++c) {
      feed_move(g, fp, p["feed_high_mm_s"], p["hold_s"]);
      feed_move(g, fp, p["feed_low_mm_s"], p["hold_s"]);
    }
    g.push_back(d.wait_for_moves());
    g.push_back(";@record load_cell off");
    epilogue(g, restore);
  } else if (protocol == "liquefier-flow-sweep") {
    build_flow_sweep(r, e);
  } else if (protocol == "liquefier-sine" || protocol == "liquefier-chirp") {
    build_sine_or_chirp(r, e);
  } else {
    return false;
  }
  return true;
}

}  // namespace tunekit::protocols::experiment_gcode
