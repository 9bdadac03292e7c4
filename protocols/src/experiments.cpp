#include "tunekit/protocols/experiments.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/fitting/error.hpp"
#include "tunekit/protocols/coverage_planner.hpp"
#include "tunekit/protocols/gcode.hpp"
#include "tunekit/protocols/trajectory.hpp"

namespace tunekit::protocols {
namespace {

constexpr double kMachineDefault = std::numeric_limits<double>::quiet_NaN();
constexpr double kMachineJerk = 1e8;  // mm/s^3, for duration estimates only

std::vector<ProtocolSpec> make_specs() {
  const ProtocolParam hotend{"hotend_c", 210, "degC", "hot-end temperature set (and waited for) first; 0 leaves the heater alone"};
  std::vector<ProtocolSpec> s;
  s.push_back({"liquefier-step",
               "extrusion-rate steps (low, then high/low cycles) with the load cell recording the filament force",
               {{"feed_low_mm_s", 1.0, "mm/s", "filament feed before and between steps"},
                {"feed_high_mm_s", 3.0, "mm/s", "filament feed during a step"},
                {"settle_s", 3.0, "s", "time at the low feed before the first step"},
                {"hold_s", 3.0, "s", "time at each level (several tau)"},
                {"cycles", 2, "", "number of low -> high -> low cycles"},
                {"accel_mm_s2", 2000, "mm/s^2", "filament acceleration of the feed changes"},
                hotend},
               {"load_cell"},
               false});
  s.push_back({"liquefier-sine",
               "sine-dwell list: the feed oscillates around a mean at log-spaced frequencies, load cell recorded",
               {{"feed_mean_mm_s", 2.0, "mm/s", "mean filament feed"},
                {"amplitude_mm_s", 1.0, "mm/s", "feed oscillation amplitude"},
                {"freq_min_hz", 0.2, "Hz", "lowest frequency"},
                {"freq_max_hz", 2.0, "Hz", "highest frequency"},
                {"freq_count", 5, "", "number of frequencies (log-spaced)"},
                {"periods", 4, "", "periods per frequency"},
                {"segment_s", 0.02, "s", "duration of one constant-feed move of the staircase"},
                {"accel_mm_s2", 3000, "mm/s^2", "filament acceleration between segments"},
                hotend},
               {"load_cell"},
               false});
  s.push_back({"liquefier-chirp",
               "linear chirp of the feed from freq_min_hz to freq_max_hz, load cell recorded",
               {{"feed_mean_mm_s", 2.0, "mm/s", "mean filament feed"},
                {"amplitude_mm_s", 1.0, "mm/s", "feed oscillation amplitude"},
                {"freq_min_hz", 0.1, "Hz", "start frequency"},
                {"freq_max_hz", 3.0, "Hz", "end frequency"},
                {"duration_s", 20, "s", "chirp duration"},
                {"segment_s", 0.02, "s", "duration of one constant-feed move of the staircase"},
                {"accel_mm_s2", 3000, "mm/s^2", "filament acceleration between segments"},
                hotend},
               {"load_cell"},
               false});
  s.push_back({"ring-print",
               "seed 001's frequency test: a ring printed at constant speed with the extrusion modulated by "
               "(1 + amplitude sin(periods theta)); f = periods v / (2 pi R). Measure the width with 'tunekit linewidth'",
               {{"radius_mm", 30, "mm", "ring radius R (seed 001 appendix D: 30 mm)"},
                {"center_x_mm", kMachineDefault, "mm", "ring centre x (default: middle of the travel)"},
                {"center_y_mm", kMachineDefault, "mm", "ring centre y (default: middle of the travel)"},
                {"speed_mm_s", 20, "mm/s", "print speed v"},
                {"periods", 8, "", "sine periods N around the ring"},
                {"amplitude", 0.2, "", "relative extrusion modulation A"},
                {"segments", 360, "", "straight segments per ring"},
                {"z_mm", 0.2, "mm", "layer height / nozzle height of the ring"},
                {"accel_mm_s2", 1000, "mm/s^2", "print acceleration"},
                hotend},
               {},
               false});
  s.push_back({"axis-sweep",
               "resonance sweep like Klipper's TEST_RESONANCES: back-and-forth moves whose acceleration is "
               "accel_per_hz * f while f rises at hz_per_sec; the accelerometer is recorded",
               {{"freq_start_hz", 10, "Hz", "first frequency"},
                {"freq_end_hz", 100, "Hz", "last frequency"},
                {"hz_per_sec", 2, "Hz/s", "sweep rate"},
                {"accel_per_hz", 60, "mm/s^2/Hz", "acceleration amplitude per Hz"},
                {"center_mm", kMachineDefault, "mm", "position of the swept axis (default: middle of its travel)"},
                {"other_mm", kMachineDefault, "mm", "position of the other horizontal axis (default: middle)"},
                {"travel_speed_mm_s", 100, "mm/s", "speed of the move to the start position"},
                {"settle_s", 0.3, "s", "recorded rest before and after the sweep"}},
               {"accelerometer"},
               true});
  s.push_back({"axis-rectangle",
               "the overshoot test of Hemminger, Improvements and Characterization of Error, Speed, and Capabilities "
               "in Low-Cost Additive Manufacturing Systems, UCLA, 2022: an XY rectangle with pauses at the corners, "
               "repeated; each axis sees step motions; the accelerometer is recorded (analyze: tunekit overshoot)",
               {{"width_mm", 40, "mm", "rectangle size along x"},
                {"height_mm", 40, "mm", "rectangle size along y"},
                {"speed_mm_s", 100, "mm/s", "move speed"},
                {"accel_mm_s2", 3000, "mm/s^2", "move acceleration"},
                {"repeats", 5, "", "rectangles (the thesis: 5)"},
                {"pause_s", 0.3, "s", "pause at each corner"}},
               {"accelerometer"},
               false});
  s.push_back({"test-pattern",
               "test prints (pads for photos, line steps, rings) on one layer, ordered by the grid-based coverage "
               "planner after Li and Yao, Coverage Path Planning Application on FDM 3D Printer, USC, 2018 (fewer "
               "travels and retractions than a zigzag; zigzag=1 prints the zigzag for comparison)",
               {{"pads", 4, "", "filled squares for photos"},
                {"pad_mm", 20, "mm", "pad size"},
                {"line_steps", 5, "", "single lines of rising length"},
                {"line_mm", 30, "mm", "longest line"},
                {"rings", 2, "", "two-line-wide rings"},
                {"ring_radius_mm", 12, "mm", "ring radius"},
                {"speed_mm_s", 40, "mm/s", "print speed"},
                {"travel_speed_mm_s", 150, "mm/s", "travel speed"},
                {"accel_mm_s2", 1500, "mm/s^2", "acceleration"},
                {"z_mm", 0.2, "mm", "layer height / nozzle height"},
                {"zigzag", 0, "", "1: plain zigzag order instead of the coverage planner"},
                hotend},
               {},
               false});
  return s;
}

double mid(const MachineProfile& p, const std::string& axis) {
  const auto& a = p.axis(axis);
  return 0.5 * (a.min_mm + a.max_mm);
}

std::string num(double v, int decimals = 4) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

void feed_move(std::vector<std::string>& g, double feed_mm_s, double duration_s) {
  g.push_back(fmt::format("G1 E{} F{}", num(feed_mm_s * duration_s, 5), num(feed_mm_s * 60, 2)));
}

void liquefier_prologue(std::vector<std::string>& g, const std::map<std::string, double>& p, const Dialect& d) {
  g.push_back("M83 ; relative extrusion");
  if (p.at("hotend_c") > 0) g.push_back(d.set_hotend(p.at("hotend_c"), true));
  g.push_back(d.set_accel(p.at("accel_mm_s2")));
}

double estimate_duration(const std::vector<std::string>& gcode, double jerk) {
  GcodeInterpreter in;
  double t = 0;
  for (const auto& l : gcode) {
    const auto w = parse_gcode(l);
    if (!w) continue;
    const auto m = in.apply(*w);
    if (m) t += Profile::move(m->length_mm(), 0, m->feed_mm_s, 0, m->accel_mm_s2, jerk).duration_s();
    t += in.dwell_s();
  }
  return t;
}

}  // namespace

const std::vector<ProtocolSpec>& protocol_specs() {
  static const std::vector<ProtocolSpec> specs = make_specs();
  return specs;
}

const ProtocolSpec& protocol_spec(const std::string& name) {
  for (const auto& s : protocol_specs())
    if (s.name == name) return s;
  std::string known;
  for (const auto& s : protocol_specs()) known += (known.empty() ? "" : ", ") + s.name;
  throw InputError(fmt::format("unknown protocol '{}' (known: {})", name, known));
}

nlohmann::json Experiment::to_json() const {
  nlohmann::json j;
  j["protocol"] = protocol;
  if (!axis.empty()) j["axis"] = axis;
  j["params"] = params;
  j["sensors"] = sensors;
  j["gcode_lines"] = gcode.size();
  j["estimated_duration_s"] = estimated_duration_s;
  return j;
}

Experiment build_experiment(const std::string& protocol, const std::map<std::string, double>& overrides,
                            const std::string& axis_in, const MachineProfile& profile, const Dialect& d) {
  const auto& spec = protocol_spec(protocol);
  Experiment e;
  e.protocol = protocol;
  e.sensors = spec.sensors;
  for (const auto& prm : spec.params) e.params[prm.name] = prm.default_value;
  for (const auto& [k, v] : overrides) {
    if (!e.params.count(k)) {
      std::string known;
      for (const auto& prm : spec.params) known += (known.empty() ? "" : ", ") + prm.name;
      throw InputError(fmt::format("protocol {} has no parameter '{}' (parameters: {})", protocol, k, known));
    }
    if (!std::isfinite(v)) throw InputError(fmt::format("parameter {} must be a finite number", k));
    e.params[k] = v;
  }
  auto& p = e.params;
  auto positive = [&](const char* k) {
    if (!(p.at(k) > 0)) throw InputError(fmt::format("{} parameter {} must be positive, not {:g}", protocol, k, p.at(k)));
    return p.at(k);
  };
  auto& g = e.gcode;
  g.push_back(fmt::format("; tunekit {} on {}", protocol, profile.name));

  if (protocol == "liquefier-step") {
    positive("feed_low_mm_s");
    positive("feed_high_mm_s");
    positive("hold_s");
    positive("settle_s");
    positive("accel_mm_s2");
    const int cycles = static_cast<int>(std::lround(positive("cycles")));
    liquefier_prologue(g, p, d);
    g.push_back(";@record load_cell on");
    feed_move(g, p["feed_low_mm_s"], p["settle_s"]);
    for (int c = 0; c < cycles; ++c) {
      feed_move(g, p["feed_high_mm_s"], p["hold_s"]);
      feed_move(g, p["feed_low_mm_s"], p["hold_s"]);
    }
    g.push_back(d.wait_for_moves());
    g.push_back(";@record load_cell off");
  } else if (protocol == "liquefier-sine" || protocol == "liquefier-chirp") {
    const double mean = positive("feed_mean_mm_s");
    const double amp = p.at("amplitude_mm_s");
    if (amp < 0 || amp >= mean) throw InputError("amplitude_mm_s must be in [0, feed_mean_mm_s) so the feed stays positive");
    const double seg = positive("segment_s");
    positive("accel_mm_s2");
    liquefier_prologue(g, p, d);
    g.push_back(";@record load_cell on");
    feed_move(g, mean, 2.0);  // steady state first
    if (protocol == "liquefier-sine") {
      const double f0 = positive("freq_min_hz"), f1 = positive("freq_max_hz");
      const int n = std::max(1, static_cast<int>(std::lround(positive("freq_count"))));
      const double periods = positive("periods");
      for (int i = 0; i < n; ++i) {
        const double f = n == 1 ? f0 : f0 * std::pow(f1 / f0, static_cast<double>(i) / (n - 1));
        const double dt = std::min(seg, 1.0 / (20 * f));
        const int steps = static_cast<int>(std::ceil(periods / f / dt));
        g.push_back(fmt::format("; dwell at {} Hz", num(f, 4)));
        for (int k = 0; k < steps; ++k)
          feed_move(g, mean + amp * std::sin(2 * std::numbers::pi * f * (k + 0.5) * dt), dt);
      }
    } else {
      const double f0 = positive("freq_min_hz"), f1 = positive("freq_max_hz"), T = positive("duration_s");
      const int steps = static_cast<int>(std::ceil(T / seg));
      for (int k = 0; k < steps; ++k) {
        const double t = (k + 0.5) * seg;
        const double phase = 2 * std::numbers::pi * (f0 * t + 0.5 * (f1 - f0) / T * t * t);
        feed_move(g, mean + amp * std::sin(phase), seg);
      }
    }
    feed_move(g, mean, 1.0);
    g.push_back(d.wait_for_moves());
    g.push_back(";@record load_cell off");
  } else if (protocol == "ring-print") {
    const double R = positive("radius_mm"), v = positive("speed_mm_s"), A = p.at("amplitude");
    const int N = static_cast<int>(std::lround(positive("periods")));
    const int segs = std::max(12, static_cast<int>(std::lround(positive("segments"))));
    if (std::isnan(p["center_x_mm"])) p["center_x_mm"] = mid(profile, "x");
    if (std::isnan(p["center_y_mm"])) p["center_y_mm"] = mid(profile, "y");
    const double cx = p["center_x_mm"], cy = p["center_y_mm"];
    const double e_per_mm = profile.line_area_mm2() / profile.filament_area_mm2();
    g.push_back(fmt::format("; f = N v / (2 pi R) = {} Hz", num(N * v / (2 * std::numbers::pi * R), 4)));
    g.push_back("G28");
    g.push_back("G90");
    g.push_back("M83 ; relative extrusion");
    if (p.at("hotend_c") > 0) g.push_back(d.set_hotend(p.at("hotend_c"), true));
    g.push_back(d.set_accel(std::min(positive("accel_mm_s2"), profile.axis("z").max_accel_mm_s2)));
    g.push_back(fmt::format("G1 Z{} F{}", num(positive("z_mm")), num(std::min(10.0, profile.axis("z").max_velocity_mm_s) * 60, 1)));
    g.push_back(d.set_accel(positive("accel_mm_s2")));
    g.push_back(fmt::format("G1 X{} Y{} F{}", num(cx + R), num(cy), num(std::min(100.0, v * 3) * 60, 1)));
    const double seg_len = 2 * R * std::sin(std::numbers::pi / segs);
    for (int k = 1; k <= segs; ++k) {
      const double th = 2 * std::numbers::pi * k / segs, th_mid = 2 * std::numbers::pi * (k - 0.5) / segs;
      const double e = e_per_mm * seg_len * (1 + A * std::sin(N * th_mid));
      g.push_back(fmt::format("G1 X{} Y{} E{} F{}", num(cx + R * std::cos(th)), num(cy + R * std::sin(th)), num(e, 5),
                              num(v * 60, 1)));
    }
    g.push_back(d.wait_for_moves());
  } else if (protocol == "axis-sweep") {
    if (axis_in != "x" && axis_in != "y") throw InputError(fmt::format("axis-sweep needs --axis x or y, not '{}'", axis_in));
    e.axis = axis_in;
    const std::string other = axis_in == "x" ? "y" : "x";
    if (std::isnan(p["center_mm"])) p["center_mm"] = mid(profile, axis_in);
    if (std::isnan(p["other_mm"])) p["other_mm"] = mid(profile, other);
    const double f0 = positive("freq_start_hz"), f1 = positive("freq_end_hz"), rate = positive("hz_per_sec");
    const double aph = positive("accel_per_hz");
    if (f1 <= f0) throw InputError("freq_end_hz must exceed freq_start_hz");
    const std::string A = axis_in == "x" ? "X" : "Y", O = axis_in == "x" ? "Y" : "X";
    g.push_back("G28");
    g.push_back("G90");
    g.push_back(d.set_accel(std::min(3000.0, profile.axis(axis_in).max_accel_mm_s2)));
    g.push_back(fmt::format("G1 {}{} {}{} F{}", A, num(p["center_mm"]), O, num(p["other_mm"]),
                            num(positive("travel_speed_mm_s") * 60, 1)));
    g.push_back(d.wait_for_moves());
    g.push_back(";@record accelerometer on");
    g.push_back(fmt::format("G4 P{}", std::lround(p["settle_s"] * 1000)));
    double t = 0, f = f0, pos = p["center_mm"];
    int sign = 1;
    while (f < f1) {
      const double th = 1.0 / (2 * f), a = aph * f;
      const double vpk = a * th / 2, dist = vpk * th / 2;
      g.push_back(d.set_accel(a));
      pos += sign * dist;
      g.push_back(fmt::format("G1 {}{} F{}", A, num(pos), num(vpk * 60, 2)));
      sign = -sign;
      t += th;
      f = f0 + rate * t;
    }
    g.push_back(fmt::format("G4 P{}", std::lround(p["settle_s"] * 1000)));
    g.push_back(d.wait_for_moves());
    g.push_back(";@record accelerometer off");
  } else if (protocol == "axis-rectangle") {
    const double w = positive("width_mm"), h = positive("height_mm"), v = positive("speed_mm_s");
    const int reps = static_cast<int>(std::lround(positive("repeats")));
    const long pause_ms = std::lround(positive("pause_s") * 1000);
    const double x0 = mid(profile, "x") - w / 2, y0 = mid(profile, "y") - h / 2;
    g.push_back("G28");
    g.push_back("G90");
    g.push_back(d.set_accel(positive("accel_mm_s2")));
    g.push_back(fmt::format("G1 X{} Y{} F{}", num(x0), num(y0), num(v * 60, 1)));
    g.push_back(d.wait_for_moves());
    g.push_back(";@record accelerometer on");
    g.push_back(fmt::format("G4 P{}", pause_ms));
    for (int r = 0; r < reps; ++r) {
      for (const auto& corner : {std::pair{x0 + w, y0}, std::pair{x0 + w, y0 + h}, std::pair{x0, y0 + h}, std::pair{x0, y0}}) {
        g.push_back(fmt::format("G1 X{} Y{} F{}", num(corner.first), num(corner.second), num(v * 60, 1)));
        g.push_back(fmt::format("G4 P{}", pause_ms));
      }
    }
    g.push_back(d.wait_for_moves());
    g.push_back(";@record accelerometer off");
  } else if (protocol == "test-pattern") {
    TestPatternSet set;
    set.pads = static_cast<int>(std::lround(p.at("pads")));
    set.pad_mm = positive("pad_mm");
    set.line_steps = static_cast<int>(std::lround(p.at("line_steps")));
    set.line_mm = positive("line_mm");
    set.rings = static_cast<int>(std::lround(p.at("rings")));
    set.ring_radius_mm = positive("ring_radius_mm");
    CoverageMotion mo;
    mo.print_speed_mm_s = positive("speed_mm_s");
    mo.travel_speed_mm_s = positive("travel_speed_mm_s");
    mo.accel_mm_s2 = positive("accel_mm_s2");
    // The safety check counts a retraction's filament speed against the hot end's flow limit.
    double retract = mo.retract_speed_mm_s;
    if (profile.extruder.max_flow_mm3_s > 0) retract = std::min(retract, 0.9 * profile.extruder.max_flow_mm3_s / profile.filament_area_mm2());
    if (profile.extruder.max_velocity_mm_s > 0) retract = std::min(retract, 0.9 * profile.extruder.max_velocity_mm_s);
    mo.retract_speed_mm_s = retract;
    const auto plan = plan_test_patterns(set, profile, p.at("zigzag") != 0 ? "zigzag" : "pce", mo);
    const auto other = plan_test_patterns(set, profile, p.at("zigzag") != 0 ? "pce" : "zigzag", mo);
    for (const auto* pl : {&plan, &other})
      g.push_back(fmt::format("; {} order: print {} mm, travel {} mm, {} retractions, estimated {} s", pl->planner,
                              num(pl->stats.print_mm, 1), num(pl->stats.travel_mm, 1), pl->stats.retractions,
                              num(pl->stats.time_s, 1)));
    const double e_per_mm = profile.line_area_mm2() / profile.filament_area_mm2();
    g.push_back("G28");
    g.push_back("G90");
    g.push_back("M83 ; relative extrusion");
    if (p.at("hotend_c") > 0) g.push_back(d.set_hotend(p.at("hotend_c"), true));
    g.push_back(d.set_accel(std::min(mo.accel_mm_s2, profile.axis("z").max_accel_mm_s2)));
    g.push_back(fmt::format("G1 Z{} F{}", num(positive("z_mm")), num(std::min(10.0, profile.axis("z").max_velocity_mm_s) * 60, 1)));
    g.push_back(d.set_accel(mo.accel_mm_s2));
    const auto& first = plan.moves.front();
    g.push_back(fmt::format("G0 X{} Y{} F{}", num(first.x0), num(first.y0), num(mo.travel_speed_mm_s * 60, 1)));
    for (const auto& m : plan.moves) {
      if (m.extrude) {
        g.push_back(fmt::format("G1 X{} Y{} E{} F{}", num(m.x1), num(m.y1),
                                num(e_per_mm * std::hypot(m.x1 - m.x0, m.y1 - m.y0), 5), num(mo.print_speed_mm_s * 60, 1)));
      } else {
        g.push_back(fmt::format("G1 E-{} F{}", num(mo.retract_mm), num(mo.retract_speed_mm_s * 60, 1)));
        g.push_back(fmt::format("G0 X{} Y{} F{}", num(m.x1), num(m.y1), num(mo.travel_speed_mm_s * 60, 1)));
        g.push_back(fmt::format("G1 E{} F{}", num(mo.retract_mm), num(mo.retract_speed_mm_s * 60, 1)));
      }
    }
    g.push_back(d.wait_for_moves());
  }
  e.estimated_duration_s = estimate_duration(g, kMachineJerk);
  return e;
}

}  // namespace tunekit::protocols
