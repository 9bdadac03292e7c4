// The simulator's configuration and its serving: SimConfig's "key=value" options and truth, the
// thread-safe queries, and serving a Simulator on a transport or a pseudo-terminal. The plant is
// in sim_plant.cpp, the G-code command table in sim_gcode.cpp, fault injection in sim_faults.cpp.
#include "tunekit/sim/simulator.hpp"

#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <numbers>

#include <fmt/format.h>

#include "sim_constants.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/design/shaper_defs.hpp"

namespace tunekit::sim {
namespace {

double parse_double(const std::string& key, const std::string& v) {
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || end != v.c_str() + v.size() || !std::isfinite(d))
    throw InputError(fmt::format("simulator option {}: '{}' is not a number", key, v));
  return d;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::size_t b = 0;
  for (;;) {
    const auto e = s.find(sep, b);
    out.push_back(s.substr(b, e == std::string::npos ? std::string::npos : e - b));
    if (e == std::string::npos) break;
    b = e + 1;
  }
  return out;
}

/// "ft_shaper_x=<code>:<Hz>": ftMotionShaper_t code (0 none .. 8 MZV) and base frequency.
void parse_ft_shaper(SimConfig& c, const std::string& key, const std::string& v) {
  const auto parts = split(v, ':');
  const double code = parse_double(key, parts.front());
  if (parts.size() != 2 || code < 0 || code > sim::kFtmLastShaper || code != std::floor(code))
    throw InputError(
        fmt::format("simulator option {} must be <shaper 0-{}>:<Hz>, e.g. 1:41", key, sim::kFtmLastShaper));
  const int axis = key.back() == 'x' ? 0 : 1;
  c.ft_shaper[axis] = static_cast<int>(code);
  c.ft_freq_hz[axis] = parse_double(key, parts.back());
}

const char* liquefier_model_name(LiquefierModel m) { return m == LiquefierModel::fopdt ? "fopdt" : "physics"; }

// A positive value of option k; InputError otherwise.
double positive_option(const std::string& k, double d) {
  if (!(d > 0)) throw InputError(fmt::format("simulator option {} must be positive", k));
  return d;
}

// A value of option k that is zero or positive; InputError otherwise.
double non_negative_option(const std::string& k, double d) {
  if (!(d >= 0)) throw InputError(fmt::format("simulator option {} must be zero or positive", k));
  return d;
}

// mode_AXIS=FREQ_HZ:ZETA[:WEIGHT],...: the axis' modes.
std::vector<SimMode> parse_modes(const std::string& k, const std::string& v) {
  auto pos = [&](double d) { return positive_option(k, d); };
  std::vector<SimMode> modes;
  for (const auto& m : split(v, ',')) {
    const auto parts = split(m, ':');
    if (parts.size() < 2 || parts.size() > 3)
      throw InputError(fmt::format("simulator option {}: '{}' is not FREQ_HZ:ZETA[:WEIGHT]", k, m));
    SimMode sm{pos(parse_double(k, parts[0])), pos(parse_double(k, parts[1])),
               parts.size() == 3 ? parse_double(k, parts[2]) : sim::kDefaultModeWeight};
    if (sm.zeta >= 1) throw InputError(fmt::format("simulator option {}: damping ratio must be below 1", k));
    modes.push_back(sm);
  }
  return modes;
}

// shaper_AXIS=TYPE:FREQ_HZ[:DAMPING]: the firmware's input shaper on the axis, as impulses.
void parse_shaper_option(SimConfig& c, const std::string& k, const std::string& v) {
  auto pos = [&](double d) { return positive_option(k, d); };
  const auto parts = split(v, ':');
  if (parts.size() < 2 || parts.size() > 3)
    throw InputError(fmt::format("simulator option {}: '{}' is not TYPE:FREQ_HZ[:DAMPING]", k, v));
  const double damping = parts.size() == 3 ? parse_double(k, parts[2]) : sim::kDefaultShaperDamping;
  const auto sh = design::design_shaper(design::parse_shaper_type(parts[0]), pos(parse_double(k, parts[1])), damping);
  std::vector<std::pair<double, double>> imp;
  for (std::size_t i = 0; i < sh.amplitudes.size(); ++i) imp.push_back({sh.amplitudes[i], sh.times_s[i]});
  c.shapers[k.substr(7)] = imp;
  c.shaper_names[k.substr(7)] = fmt::format("{}:{:g}:{:g}", parts[0], sh.freq_hz, damping);
}

// fault=KIND@LINE[:MILLISECONDS]: a fault injected at a received line.
SimFault parse_fault(const std::string& k, const std::string& v) {
  auto pos = [&](double d) { return positive_option(k, d); };
  const auto at = v.find('@');
  if (at == std::string::npos) throw InputError(fmt::format("simulator fault '{}' is not KIND@LINE", v));
  const std::string kind = v.substr(0, at);
  SimFault f;
  auto rest = v.substr(at + 1);
  if (kind == "late-ok") {
    const auto colon = rest.find(':');
    if (colon == std::string::npos) throw InputError("simulator fault late-ok needs @LINE:MILLISECONDS");
    f.delay_ms = pos(parse_double(k, rest.substr(colon + 1)));
    // About 30 years: past any host's timeout (1e9 ms, 11.6 days, is a wait that never
    // ends in practice), and well within what the clock counts in nanoseconds (2^63 ns).
    constexpr double kMaxLateOk_ms = 1e12;
    if (f.delay_ms > kMaxLateOk_ms)
      throw InputError(fmt::format("simulator fault late-ok: {:g} ms is out of range (accepted: up to {:g} ms)",
                                   f.delay_ms, kMaxLateOk_ms));
    rest = rest.substr(0, colon);
    f.kind = SimFault::Kind::late_ok;
  } else if (kind == "drop") f.kind = SimFault::Kind::drop;
  else if (kind == "garble") f.kind = SimFault::Kind::garble;
  else if (kind == "disconnect") f.kind = SimFault::Kind::disconnect;
  else if (kind == "error") f.kind = SimFault::Kind::error;
  else throw InputError(fmt::format("unknown simulator fault '{}' (drop, garble, late-ok, disconnect, error)", kind));
  f.at_line = static_cast<long>(pos(parse_double(k, rest)));
  return f;
}

// The hot end's options (SimConfig::hot_end); false when `k` is not one of them.
bool thermal_option(ThermalPlantTruth& t, const std::string& k, const std::string& v) {
  auto& m = t.model;
  double* field = k == "heater_power_w"                      ? &m.heater_power_w
                  : k == "block_heat_capacity_j_per_k"       ? &m.block_heat_capacity_j_per_k
                  : k == "sensor_responsiveness_per_s"       ? &m.sensor_responsiveness_per_s
                  : k == "ambient_transfer_w_per_k"          ? &m.ambient_transfer_w_per_k
                  : k == "fan_transfer_w_per_k"              ? &m.fan_transfer_w_per_k
                  : k == "filament_heat_capacity_j_per_k_mm" ? &m.filament_heat_capacity_j_per_k_mm
                  : k == "fan_exponent"                      ? &t.fan_exponent
                  : k == "thermistor_noise_c"                ? &t.sensor_noise_c
                  : k == "adc_step_c"                        ? &t.adc_step_c
                                                             : nullptr;
  if (k == "ambient_c") {
    m.ambient_c = parse_double(k, v);
    return true;
  }
  if (!field) return false;
  const double d = parse_double(k, v);
  const bool may_be_zero = k == "filament_heat_capacity_j_per_k_mm" || k == "thermistor_noise_c" || k == "adc_step_c";
  if (may_be_zero ? d < 0 : !(d > 0))
    throw InputError(fmt::format("simulator option {} must be {}", k, may_be_zero ? "at least 0" : "positive"));
  *field = d;
  return true;
}

}  // namespace

double SimConfig::tau_at_feed(double feed_mm_s) const {
  if (tau_flow_exponent == 0) return tau_s;
  const double u = std::max(std::abs(feed_mm_s), sim::kTauFloorFeed_mm_s);
  return tau_s * std::pow(u / tau_ref_feed_mm_s, tau_flow_exponent);
}

double SimConfig::bed_stiffness_N_per_m() const {
  const auto it = modes.find(bed_axis);
  if (it == modes.end() || it->second.empty()) return 0;
  const double w = 2 * std::numbers::pi * it->second.front().freq_hz;
  return bed_moving_mass_kg * w * w;
}

std::map<std::string, std::vector<SimMode>> SimConfig::loaded_modes() const {
  auto out = modes;
  const auto it = out.find(bed_axis);
  if (it == out.end() || it->second.empty() || bed_load_kg == 0) return out;
  // f ~ 1/sqrt(m0 + m) at a fixed stiffness; zeta ~ 1/sqrt(m0 + m) at a fixed viscous damping.
  const double scale = std::sqrt(bed_moving_mass_kg / (bed_moving_mass_kg + bed_load_kg));
  it->second.front().freq_hz *= scale;
  it->second.front().zeta *= scale;
  return out;
}

const char* SimConfig::preset_name(SimPreset p) { return p == SimPreset::desktop ? "desktop" : "peek"; }

SimConfig SimConfig::with_preset(SimPreset p) {
  SimConfig c;
  c.preset = p;
  if (p == SimPreset::peek) {
    c.tau_s = 0.45;
    c.theta_s = 0.04;
    c.tau_flow_exponent = 0;
    c.modes = {{"x", {{48, 0.08, 1}}}, {"y", {{37, 0.1, 1}}}};
  }
  return c;
}

SimConfig SimConfig::from_options(const std::vector<std::string>& options) {
  // The preset first: the other options change it, whatever their order.
  SimConfig c;
  for (const auto& opt : options) {
    if (opt.rfind("preset=", 0) != 0) continue;
    const std::string v = opt.substr(7);
    if (v != "desktop" && v != "peek") throw InputError("simulator option preset must be desktop or peek");
    c = with_preset(v == "desktop" ? SimPreset::desktop : SimPreset::peek);
  }
  for (const auto& opt : options) {
    const auto eq = opt.find('=');
    if (eq == std::string::npos) throw InputError(fmt::format("simulator option '{}' is not key=value", opt));
    const std::string k = opt.substr(0, eq), v = opt.substr(eq + 1);
    if (k == "preset" || k == "hot_end" || thermal_option(c.hot_end, k, v)) continue;
    auto pos = [&](double d) { return positive_option(k, d); };
    auto clock_error = [&](double d) {
      if (!(std::abs(d) < 0.1))
        throw InputError(fmt::format("simulator option {} must be a fraction between -0.1 and 0.1", k));
      return d;
    };
    if (k == "liquefier") {
      if (v != "fopdt" && v != "physics") throw InputError("simulator option liquefier must be fopdt or physics");
      c.liquefier = v == "fopdt" ? LiquefierModel::fopdt : LiquefierModel::physics;
    } else if (k == "K" || k == "K_N_per_mm_s") c.K_N_per_mm_s = parse_double(k, v);
    else if (k == "tau_s") c.tau_s = pos(parse_double(k, v));
    else if (k == "tau_ref_feed_mm_s") c.tau_ref_feed_mm_s = pos(parse_double(k, v));
    else if (k == "tau_flow_exponent") c.tau_flow_exponent = parse_double(k, v);
    else if (k == "theta_s") c.theta_s = std::max(0.0, parse_double(k, v));
    else if (k == "k_MPa") c.k_MPa = pos(parse_double(k, v));
    else if (k == "n_index") c.n_index = pos(parse_double(k, v));
    else if (k == "compliance_mm3_MPa") c.compliance_mm3_MPa = pos(parse_double(k, v));
    else if (k == "filament_diameter_mm") c.filament_diameter_mm = pos(parse_double(k, v));
    else if (k == "force_offset_N") c.force_offset_N = parse_double(k, v);
    else if (k == "force_noise_N") c.force_noise_N = std::max(0.0, parse_double(k, v));
    else if (k == "load_cell_rate_hz") c.load_cell_rate_hz = pos(parse_double(k, v));
    else if (k == "load_cell_clock_error") c.load_cell_clock_error = clock_error(parse_double(k, v));
    else if (k == "accel_rate_hz") c.accel_rate_hz = pos(parse_double(k, v));
    else if (k == "accel_noise_mm_s2") c.accel_noise_mm_s2 = std::max(0.0, parse_double(k, v));
    else if (k == "cross_coupling") c.cross_coupling = parse_double(k, v);
    else if (k == "jerk_mm_s3") c.jerk_mm_s3 = pos(parse_double(k, v));
    else if (k == "bed_moving_mass_kg") c.bed_moving_mass_kg = pos(parse_double(k, v));
    else if (k == "bed_load_kg") c.bed_load_kg = non_negative_option(k, parse_double(k, v));
    else if (k == "bed_axis") {
      if (v != "x" && v != "y") throw InputError("simulator option bed_axis must be x or y");
      c.bed_axis = v;
    } else if (k == "seed") c.seed = static_cast<unsigned>(parse_double(k, v));
    else if (k == "firmware") {
      if (v != "marlin" && v != "klipper" && v != "rrf")
        throw InputError("simulator option firmware must be marlin, klipper or rrf");
      c.firmware = v;
    } else if (k == "steps_per_mm") c.steps_per_mm = pos(parse_double(k, v));
    else if (k == "max_extrude_only_distance_mm") c.max_extrude_only_distance_mm = pos(parse_double(k, v));
    else if (k == "max_extrude_only_accel_mm_s2") c.max_extrude_only_accel_mm_s2 = pos(parse_double(k, v));
    else if (k == "max_accel_xy_mm_s2") c.max_accel_xy_mm_s2 = pos(parse_double(k, v));
    else if (k == "retract_accel_mm_s2") c.retract_accel_mm_s2 = pos(parse_double(k, v));
    else if (k == "max_accel_e_mm_s2") c.max_accel_e_mm_s2 = pos(parse_double(k, v));
    else if (k == "sensor_stream") {
      if (v != "0" && v != "1") throw InputError("simulator option sensor_stream must be 0 or 1");
      c.sensor_stream = v == "1";
    } else if (k == "autoreport_temp") {
      if (v != "0" && v != "1") throw InputError("simulator option autoreport_temp must be 0 or 1");
      c.autoreport_temp = v == "1";
    } else if (k == "rrf_http") {
      if (v != "0" && v != "1") throw InputError("simulator option rrf_http must be 0 or 1");
      c.rrf_http = v == "1";
    } else if (k == "rrf_password") {
      c.rrf_password = v;
    } else if (k == "rrf_http_sessions") {
      const double n = parse_double(k, v);
      if (n < 0 || n != std::floor(n))
        throw InputError("simulator option rrf_http_sessions must be a whole number >= 0");
      c.rrf_http_sessions = static_cast<int>(n);
    } else if (k == "ft_motion") {
      if (v != "none" && v != "off" && v != "on")
        throw InputError("simulator option ft_motion must be none, off or on");
      c.ft_motion = v;
    } else if (k == "m493_form") {
      if (v != "mode" && v != "axis_slash" && v != "axis_named" && v != "axis_list" && v != "axis_list_v2")
        throw InputError("simulator option m493_form must be mode, axis_slash, axis_named, axis_list or axis_list_v2");
      c.m493_form = v;
    } else if (k == "ft_shaper_x" || k == "ft_shaper_y") {
      parse_ft_shaper(c, k, v);
    } else if (k == "minimum_cruise_ratio") {
      c.minimum_cruise_ratio = parse_double(k, v);
      if (c.minimum_cruise_ratio < 0 || c.minimum_cruise_ratio >= 1)
        throw InputError("simulator option minimum_cruise_ratio must be in [0, 1)");
    } else if (k.rfind("mode_", 0) == 0 && k.size() == 6) {
      c.modes[k.substr(5)] = parse_modes(k, v);
    } else if (k.rfind("shaper_", 0) == 0 && k.size() == 8 && (k[7] == 'x' || k[7] == 'y')) {
      parse_shaper_option(c, k, v);
    } else if (k == "fault") {
      c.faults.push_back(parse_fault(k, v));
    } else {
      throw InputError(fmt::format("unknown simulator option '{}' (see docs/machine.md)", k));
    }
  }
  return with_hot_end_drawn(c, options);
}

SimConfig SimConfig::with_hot_end_drawn(SimConfig c, const std::vector<std::string>& options) {
  // "hot_end=drawn": the plant drawn from the seed, then the single values given beside it.
  bool drawn = false;
  for (const auto& opt : options)
    if (opt.rfind("hot_end=", 0) == 0) {
      if (opt != "hot_end=drawn") throw InputError("simulator option hot_end must be drawn");
      drawn = true;
    }
  if (!drawn) return c;
  c.hot_end = draw_thermal_plant(c.seed);
  for (const auto& opt : options)
    if (const auto eq = opt.find('='); eq != std::string::npos)
      thermal_option(c.hot_end, opt.substr(0, eq), opt.substr(eq + 1));
  return c;
}

std::vector<std::string> SimConfig::machine_options(const machine::MachineProfile& p) {
  std::vector<std::string> o;
  if (p.firmware == "klipper" || p.firmware == "kalico") o.push_back("firmware=klipper");
  else if (p.firmware == "marlin" || p.firmware == "prusa") o.push_back("firmware=marlin");
  else if (p.firmware == "rrf") o.push_back("firmware=rrf");
  auto add = [&o](const char* key, double v) {
    if (std::isfinite(v) && v > 0) o.push_back(fmt::format("{}={}", key, v));
  };
  add("steps_per_mm", std::min(p.state.steps_per_mm_x, p.state.steps_per_mm_y));
  add("max_extrude_only_accel_mm_s2", p.extruder.max_accel_mm_s2);
  add("max_extrude_only_distance_mm", p.extruder.max_extrude_only_distance_mm);
  add("max_accel_xy_mm_s2", p.state.max_accel_xy_mm_s2);
  add("retract_accel_mm_s2", p.state.retract_accel_mm_s2);
  add("max_accel_e_mm_s2", p.state.max_accel_e_mm_s2);
  add("accel_rate_hz", p.sensors.accelerometer_rate_hz);
  add("filament_diameter_mm", p.extruder.filament_diameter_mm);
  if (p.state.minimum_cruise_ratio >= 0 && p.state.minimum_cruise_ratio < 1)
    o.push_back(fmt::format("minimum_cruise_ratio={}", p.state.minimum_cruise_ratio));
  return o;
}

std::vector<std::string> SimConfig::acceleration_gcode() const {
  auto or_default = [](double v, double d) { return v > 0 ? v : d; };
  if (firmware == "marlin")
    return {
        fmt::format("M201 X{0} Y{0} Z{1} E{2}", or_default(max_accel_xy_mm_s2, sim::kMarlinDefaultMaxAccelXY_mm_s2),
                    sim::kDefaultMaxAccelZ_mm_s2, or_default(max_accel_e_mm_s2, sim::kMarlinDefaultMaxAccelE_mm_s2)),
        fmt::format("M204 R{}", or_default(retract_accel_mm_s2, sim::kMarlinDefaultRetractAccel_mm_s2))};
  if (firmware == "rrf")
    return {fmt::format("M201 X{0} Y{0} Z{1} E{2}", or_default(max_accel_xy_mm_s2, sim::kRrfDefaultMaxAccelXY_mm_s2),
                        sim::kDefaultMaxAccelZ_mm_s2, or_default(max_accel_e_mm_s2, sim::kRrfDefaultMaxAccelE_mm_s2))};
  return {};
}

SimConfig SimConfig::for_machine(const machine::MachineProfile& profile, const std::vector<std::string>& options) {
  std::vector<std::string> all = machine_options(profile);
  all.insert(all.end(), options.begin(), options.end());
  return from_options(all);
}

nlohmann::json SimConfig::truth() const {
  nlohmann::json j;
  const double area = std::numbers::pi / 4 * filament_diameter_mm * filament_diameter_mm;
  nlohmann::json liq{{"model", liquefier_model_name(liquefier)}, {"input", "feed (mm/s), commanded filament feed"},
                     {"output", "force (N), load cell"},         {"theta_s", theta_s},
                     {"force_offset_N", force_offset_N},         {"force_noise_N", force_noise_N},
                     {"load_cell_rate_hz", load_cell_rate_hz},   {"load_cell_clock_error", load_cell_clock_error}};
  if (liquefier == LiquefierModel::fopdt) {
    liq["K"] = K_N_per_mm_s;
    liq["K_unit"] = "N/(mm/s)";
    liq["tau_s"] = tau_s;
    liq["tau_ref_feed_mm_s"] = tau_ref_feed_mm_s;
    liq["tau_flow_exponent"] = tau_flow_exponent;
    liq["tau_floor_feed_mm_s"] = sim::kTauFloorFeed_mm_s;  // tau(u) = tau(floor) below it
    liq["equations"] = "tau(u) = tau_s (u / tau_ref_feed_mm_s)^tau_flow_exponent";
    nlohmann::json table = nlohmann::json::array();
    for (double u : sim::kTruthOperatingFeeds_mm_s)
      table.push_back({{"feed_mm_s", u},
                       {"flow_mm3_s", area * u},
                       {"force_N", K_N_per_mm_s * u + force_offset_N},
                       {"K_local", K_N_per_mm_s},
                       {"tau_local_s", tau_at_feed(u)}});
    liq["operating_points"] = table;
  } else {
    liq["k_MPa_s^n_per_mm3^n"] = k_MPa;
    liq["n_index"] = n_index;
    liq["compliance_mm3_MPa"] = compliance_mm3_MPa;
    liq["filament_area_mm2"] = area;
    liq["equations"] = "C dP/dt = A u(t - theta) - (P/k)^(1/n); F = P A";
    nlohmann::json table = nlohmann::json::array();
    for (double u : sim::kTruthOperatingFeeds_mm_s) {
      const double Q = area * u, P = k_MPa * std::pow(Q, n_index);
      table.push_back({{"feed_mm_s", u},
                       {"force_N", P * area + force_offset_N},
                       {"K_local", n_index * P * area / u},
                       {"tau_local_s", compliance_mm3_MPa * k_MPa * n_index * std::pow(Q, n_index - 1)}});
    }
    liq["operating_points"] = table;
  }
  j["preset"] = preset_name(preset);
  j["liquefier"] = liq;
  nlohmann::json axes = nlohmann::json::object();
  for (const auto& [axis, modes] : loaded_modes()) {
    nlohmann::json ms = nlohmann::json::array();
    for (const auto& m : modes) ms.push_back({{"freq_hz", m.freq_hz}, {"zeta", m.zeta}, {"weight", m.weight}});
    axes[axis] = {{"modes", ms}};
  }
  if (axes.contains(bed_axis)) {
    const double k = bed_stiffness_N_per_m(), z0 = modes.at(bed_axis).front().zeta;
    axes[bed_axis]["bed"] = {{"moving_mass_kg", bed_moving_mass_kg},
                             {"stiffness_N_per_m", k},
                             {"damping_N_s_per_m", 2 * z0 * std::sqrt(k * bed_moving_mass_kg)},
                             {"load_kg", bed_load_kg},
                             {"equations", "f = sqrt(k / (m0 + m)) / (2 pi), zeta = c / (2 sqrt(k (m0 + m)))"}};
  }
  j["axes"] = axes;
  j["accelerometer"] = {
      {"rate_hz", accel_rate_hz}, {"noise_mm_s2", accel_noise_mm_s2}, {"cross_coupling", cross_coupling}};
  j["jerk_mm_s3"] = jerk_mm_s3;
  j["firmware"] = firmware;
  if (firmware == "marlin") {
    j["ft_motion"] = ft_motion;
    j["m493_form"] = m493_form;
    j["ft_shaper"] = {{"x", {{"code", ft_shaper[0]}, {"freq_hz", ft_freq_hz[0]}}},
                      {"y", {{"code", ft_shaper[1]}, {"freq_hz", ft_freq_hz[1]}}}};
  }
  if (firmware == "rrf") j["rrf_http"] = rrf_http;
  j["planner"] = {{"steps_per_mm", steps_per_mm},
                  {"max_extrude_only_distance_mm", max_extrude_only_distance_mm},
                  {"max_extrude_only_accel_mm_s2", max_extrude_only_accel_mm_s2},
                  {"minimum_cruise_ratio", minimum_cruise_ratio}};
  if (firmware != "klipper")
    for (const auto& line : acceleration_gcode()) j["planner"]["acceleration_gcode"].push_back(line);
  for (const auto& [axis, name] : shaper_names) j["input_shaper"][axis] = name;
  j["seed"] = seed;
  j["hot_end"] = hot_end.to_json();
  nlohmann::json faults = nlohmann::json::array();
  for (const auto& f : this->faults) faults.push_back(f.describe());
  j["faults"] = faults;
  j["time"] = "machine time: advances with executed motion only, computed faster than real time";
  return j;
}

std::vector<std::string> Simulator::received() const {
  std::lock_guard<std::mutex> lock(mu_);
  return received_;
}

void Simulator::set_streaming(const std::string& sensor, bool on) {
  if (sensor == "accelerometer") stream_accel_ = on;
  else if (sensor == "heater") {
    sync_heater();
    if (on && !stream_heater_) heater_sent_ = heater_.record().t_s.size();  // from the next tick on
    stream_heater_ = on;
  } else if (sensor == "load_cell") {
    if (on && !stream_load_) start_load_cell();
    if (!on && stream_load_) emit_pending_load_sample(t_, fed_total_mm_);  // its window ends here
    stream_load_ = on;
  }
}

void Simulator::out_flush(const Emit& emit) {
  if (!out_.empty()) emit(out_);
  out_.clear();
}

std::optional<std::string> Simulator::file(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mu_);
  const auto it = files_.find(name);
  if (it == files_.end()) return std::nullopt;
  return it->second;
}

void serve_simulator(Simulator& sim, machine::Transport& t, const std::atomic<bool>& stop) {
  std::string buf;
  const Simulator::Emit emit = [&](std::string_view s) { t.write(s); };
  sim.set_cancel(&stop);
  try {
    while (!stop.load()) {
      const std::string chunk = t.read_some(sim::kServeReadPoll);
      if (chunk.empty()) continue;
      buf += chunk;
      std::size_t b = 0;
      for (;;) {
        const auto e = buf.find_first_of("\r\n", b);
        if (e == std::string::npos) break;
        const std::string line = buf.substr(b, e - b);
        b = e + 1;
        if (line.empty()) continue;
        if (!sim.handle_line(line, emit)) {
          std::this_thread::sleep_for(sim::kDisconnectGrace);  // let the host read what was sent
          t.close();
          return;
        }
      }
      buf.erase(0, b);
    }
  } catch (const MachineError&) {
    // The host went away.
  }
}

SimPtyServer::SimPtyServer(SimConfig config, const std::function<void(Simulator&)>& setup)
    : sim_(std::make_unique<Simulator>(std::move(config))) {
  if (setup) setup(*sim_);
  if (sim_->config().rrf_http && sim_->config().firmware == "rrf") http_ = std::make_unique<SimHttpServer>(*sim_);
  master_ = ::posix_openpt(O_RDWR | O_NOCTTY);
  if (master_ < 0) throw MachineError("cannot create a pseudo-terminal (posix_openpt)");
  char name[256];
  if (::grantpt(master_) != 0 || ::unlockpt(master_) != 0 || ::ptsname_r(master_, name, sizeof name) != 0) {
    ::close(master_);
    throw MachineError("cannot set up the pseudo-terminal");
  }
  slave_path_ = name;
  ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
  ::fcntl(master_, F_SETFD, FD_CLOEXEC);
  // Keep a slave descriptor open so the master does not see a hang-up between clients, and
  // put the line in raw mode (no echo, no CR/LF translation) before anyone connects.
  slave_keepalive_ = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (slave_keepalive_ >= 0) {
    termios tio{};
    if (::tcgetattr(slave_keepalive_, &tio) == 0) {
      ::cfmakeraw(&tio);
      ::tcsetattr(slave_keepalive_, TCSANOW, &tio);
    }
  }
  thread_ = std::thread([this] { serve(); });
}

SimPtyServer::~SimPtyServer() {
  stop();
  wait();
  if (slave_keepalive_ >= 0) ::close(slave_keepalive_);
}

void SimPtyServer::stop() { stop_ = true; }

std::string SimPtyServer::http_url() const { return http_ ? http_->url() : std::string(); }
std::vector<std::string> SimPtyServer::http_targets() const {
  return http_ ? http_->targets() : std::vector<std::string>();
}

void SimPtyServer::wait() {
  if (thread_.joinable()) thread_.join();
}

void SimPtyServer::serve() {
  machine::FdTransport master(master_, "simulator pseudo-terminal master");
  serve_simulator(*sim_, master, stop_);
  if (!stop_.load()) {
    disconnected_ = true;
    if (slave_keepalive_ >= 0) {
      ::close(slave_keepalive_);
      slave_keepalive_ = -1;
    }
  }
  master.close();
  master_ = -1;
}

}  // namespace tunekit::sim
