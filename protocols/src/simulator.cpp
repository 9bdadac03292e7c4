#include "tunekit/protocols/simulator.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/fitting/error.hpp"
#include "tunekit/ident/input_shaper.hpp"

#ifndef TUNEKIT_VERSION
#define TUNEKIT_VERSION "0.1.0"
#endif

namespace tunekit::protocols {
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

}  // namespace

std::string SimFault::describe() const {
  switch (kind) {
    case Kind::drop: return fmt::format("drop@{}", at_line);
    case Kind::garble: return fmt::format("garble@{}", at_line);
    case Kind::late_ok: return fmt::format("late-ok@{}:{:g}", at_line, delay_ms);
    case Kind::disconnect: return fmt::format("disconnect@{}", at_line);
    case Kind::error: return fmt::format("error@{}", at_line);
  }
  return "?";
}

SimConfig SimConfig::from_options(const std::vector<std::string>& options) {
  SimConfig c;
  for (const auto& opt : options) {
    const auto eq = opt.find('=');
    if (eq == std::string::npos) throw InputError(fmt::format("simulator option '{}' is not key=value", opt));
    const std::string k = opt.substr(0, eq), v = opt.substr(eq + 1);
    auto pos = [&](double d) {
      if (!(d > 0)) throw InputError(fmt::format("simulator option {} must be positive", k));
      return d;
    };
    if (k == "liquefier") {
      if (v != "fopdt" && v != "physics") throw InputError("simulator option liquefier must be fopdt or physics");
      c.liquefier = v;
    } else if (k == "K" || k == "K_N_per_mm_s") c.K_N_per_mm_s = parse_double(k, v);
    else if (k == "tau_s") c.tau_s = pos(parse_double(k, v));
    else if (k == "theta_s") c.theta_s = std::max(0.0, parse_double(k, v));
    else if (k == "k_MPa") c.k_MPa = pos(parse_double(k, v));
    else if (k == "n_index") c.n_index = pos(parse_double(k, v));
    else if (k == "compliance_mm3_MPa") c.compliance_mm3_MPa = pos(parse_double(k, v));
    else if (k == "filament_diameter_mm") c.filament_diameter_mm = pos(parse_double(k, v));
    else if (k == "force_offset_N") c.force_offset_N = parse_double(k, v);
    else if (k == "force_noise_N") c.force_noise_N = std::max(0.0, parse_double(k, v));
    else if (k == "load_cell_rate_hz") c.load_cell_rate_hz = pos(parse_double(k, v));
    else if (k == "accel_rate_hz") c.accel_rate_hz = pos(parse_double(k, v));
    else if (k == "accel_noise_mm_s2") c.accel_noise_mm_s2 = std::max(0.0, parse_double(k, v));
    else if (k == "cross_coupling") c.cross_coupling = parse_double(k, v);
    else if (k == "jerk_mm_s3") c.jerk_mm_s3 = pos(parse_double(k, v));
    else if (k == "seed") c.seed = static_cast<unsigned>(parse_double(k, v));
    else if (k == "firmware") {
      if (v != "marlin" && v != "klipper" && v != "rrf")
        throw InputError("simulator option firmware must be marlin, klipper or rrf");
      c.firmware = v;
    } else if (k == "steps_per_mm") c.steps_per_mm = pos(parse_double(k, v));
    else if (k == "max_extrude_only_distance_mm") c.max_extrude_only_distance_mm = pos(parse_double(k, v));
    else if (k == "max_extrude_only_accel_mm_s2") c.max_extrude_only_accel_mm_s2 = pos(parse_double(k, v));
    else if (k == "sensor_stream") {
      if (v != "0" && v != "1") throw InputError("simulator option sensor_stream must be 0 or 1");
      c.sensor_stream = v == "1";
    } else if (k == "rrf_http") {
      if (v != "0" && v != "1") throw InputError("simulator option rrf_http must be 0 or 1");
      c.rrf_http = v == "1";
    } else if (k == "ft_motion") {
      if (v != "none" && v != "off" && v != "on") throw InputError("simulator option ft_motion must be none, off or on");
      c.ft_motion = v;
    } else if (k == "minimum_cruise_ratio") {
      c.minimum_cruise_ratio = parse_double(k, v);
      if (c.minimum_cruise_ratio < 0 || c.minimum_cruise_ratio >= 1)
        throw InputError("simulator option minimum_cruise_ratio must be in [0, 1)");
    }
    else if (k.rfind("mode_", 0) == 0 && k.size() == 6) {
      std::vector<SimMode> modes;
      for (const auto& m : split(v, ',')) {
        const auto parts = split(m, ':');
        if (parts.size() < 2 || parts.size() > 3)
          throw InputError(fmt::format("simulator option {}: '{}' is not FREQ_HZ:ZETA[:WEIGHT]", k, m));
        SimMode sm{pos(parse_double(k, parts[0])), pos(parse_double(k, parts[1])), parts.size() == 3 ? parse_double(k, parts[2]) : 1.0};
        if (sm.zeta >= 1) throw InputError(fmt::format("simulator option {}: damping ratio must be below 1", k));
        modes.push_back(sm);
      }
      c.modes[k.substr(5)] = modes;
    } else if (k.rfind("shaper_", 0) == 0 && k.size() == 8 && (k[7] == 'x' || k[7] == 'y')) {
      const auto parts = split(v, ':');
      if (parts.size() < 2 || parts.size() > 3)
        throw InputError(fmt::format("simulator option {}: '{}' is not TYPE:FREQ_HZ[:DAMPING]", k, v));
      const double damping = parts.size() == 3 ? parse_double(k, parts[2]) : 0.1;
      const auto sh = ident::design_shaper(ident::parse_shaper_type(parts[0]), pos(parse_double(k, parts[1])), damping);
      std::vector<std::pair<double, double>> imp;
      for (std::size_t i = 0; i < sh.amplitudes.size(); ++i) imp.push_back({sh.amplitudes[i], sh.times_s[i]});
      c.shapers[k.substr(7)] = imp;
      c.shaper_names[k.substr(7)] = fmt::format("{}:{:g}:{:g}", parts[0], sh.freq_hz, damping);
    } else if (k == "fault") {
      const auto at = v.find('@');
      if (at == std::string::npos) throw InputError(fmt::format("simulator fault '{}' is not KIND@LINE", v));
      const std::string kind = v.substr(0, at);
      SimFault f;
      auto rest = v.substr(at + 1);
      if (kind == "late-ok") {
        const auto colon = rest.find(':');
        if (colon == std::string::npos) throw InputError("simulator fault late-ok needs @LINE:MILLISECONDS");
        f.delay_ms = pos(parse_double(k, rest.substr(colon + 1)));
        rest = rest.substr(0, colon);
        f.kind = SimFault::Kind::late_ok;
      } else if (kind == "drop") f.kind = SimFault::Kind::drop;
      else if (kind == "garble") f.kind = SimFault::Kind::garble;
      else if (kind == "disconnect") f.kind = SimFault::Kind::disconnect;
      else if (kind == "error") f.kind = SimFault::Kind::error;
      else throw InputError(fmt::format("unknown simulator fault '{}' (drop, garble, late-ok, disconnect, error)", kind));
      f.at_line = static_cast<long>(pos(parse_double(k, rest)));
      c.faults.push_back(f);
    } else {
      throw InputError(fmt::format("unknown simulator option '{}' (see docs/machine.md)", k));
    }
  }
  return c;
}

nlohmann::json SimConfig::truth() const {
  nlohmann::json j;
  const double area = std::numbers::pi / 4 * filament_diameter_mm * filament_diameter_mm;
  nlohmann::json liq{{"model", liquefier},
                     {"input", "feed (mm/s), commanded filament feed"},
                     {"output", "force (N), load cell"},
                     {"theta_s", theta_s},
                     {"force_offset_N", force_offset_N},
                     {"force_noise_N", force_noise_N},
                     {"load_cell_rate_hz", load_cell_rate_hz}};
  if (liquefier == "fopdt") {
    liq["K"] = K_N_per_mm_s;
    liq["K_unit"] = "N/(mm/s)";
    liq["tau_s"] = tau_s;
  } else {
    liq["k_MPa_s^n_per_mm3^n"] = k_MPa;
    liq["n_index"] = n_index;
    liq["compliance_mm3_MPa"] = compliance_mm3_MPa;
    liq["filament_area_mm2"] = area;
    liq["equations"] = "C dP/dt = A u(t - theta) - (P/k)^(1/n); F = P A";
    nlohmann::json table = nlohmann::json::array();
    for (double u : {0.5, 1.0, 2.0, 3.0, 4.0, 5.0}) {
      const double Q = area * u, P = k_MPa * std::pow(Q, n_index);
      table.push_back({{"feed_mm_s", u},
                       {"force_N", P * area + force_offset_N},
                       {"K_local", n_index * P * area / u},
                       {"tau_local_s", compliance_mm3_MPa * k_MPa * n_index * std::pow(Q, n_index - 1)}});
    }
    liq["operating_points"] = table;
  }
  j["liquefier"] = liq;
  nlohmann::json axes = nlohmann::json::object();
  for (const auto& [axis, modes] : this->modes) {
    nlohmann::json ms = nlohmann::json::array();
    for (const auto& m : modes) ms.push_back({{"freq_hz", m.freq_hz}, {"zeta", m.zeta}, {"weight", m.weight}});
    axes[axis] = {{"modes", ms}};
  }
  j["axes"] = axes;
  j["accelerometer"] = {{"rate_hz", accel_rate_hz}, {"noise_mm_s2", accel_noise_mm_s2}, {"cross_coupling", cross_coupling}};
  j["jerk_mm_s3"] = jerk_mm_s3;
  j["firmware"] = firmware;
  if (firmware == "marlin") j["ft_motion"] = ft_motion;
  if (firmware == "rrf") j["rrf_http"] = rrf_http;
  j["planner"] = {{"steps_per_mm", steps_per_mm},
                  {"max_extrude_only_distance_mm", max_extrude_only_distance_mm},
                  {"max_extrude_only_accel_mm_s2", max_extrude_only_accel_mm_s2},
                  {"minimum_cruise_ratio", minimum_cruise_ratio}};
  for (const auto& [axis, name] : shaper_names) j["input_shaper"][axis] = name;
  j["seed"] = seed;
  nlohmann::json faults = nlohmann::json::array();
  for (const auto& f : this->faults) faults.push_back(f.describe());
  j["faults"] = faults;
  j["time"] = "machine time: advances with executed motion only, computed faster than real time";
  return j;
}

Simulator::Simulator(SimConfig config) : cfg_(std::move(config)), rng_(cfg_.seed) {
  dt_ = 1.0 / (cfg_.accel_rate_hz * 4);
  accel_every_ = 4;
  ftm_active_ = cfg_.ft_motion == "on";
  load_every_ = std::max(1, static_cast<int>(std::lround(1.0 / (cfg_.load_cell_rate_hz * dt_))));
  for (const auto& [axis, modes] : cfg_.modes) mode_state_[axis].assign(modes.size(), {0.0, 0.0});
  delay_.assign(std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(cfg_.theta_s / dt_))), 0.0);
  mcr_ = cfg_.minimum_cruise_ratio;
  // The firmware's defaults: Marlin Configuration.h DEFAULT_MAX_ACCELERATION {3000, 3000, 100,
  // 10000} and DEFAULT_RETRACT_ACCELERATION 3000; RepRapFirmware's M201 of a typical config.g.
  if (marlin()) {
    for (const char* l : {"M201 X3000 Y3000 Z100 E10000", "M204 R3000"}) interp_.apply(*parse_gcode(l));
  } else if (rrf()) {
    interp_.apply(*parse_gcode("M201 X3000 Y3000 Z100 E3000"));
  }
}

double Simulator::junction_speed(const GcodeMove& a, const GcodeMove& b) const {
  if (a.extruder_only() != b.extruder_only()) return 0;
  // Klipper: a junction with a move that is not kinematic (extrude-only) is a full stop.
  if (klipper() && a.extruder_only()) return 0;
  const auto ua = a.unit(), ub = b.unit();
  double dot = 0;
  if (a.extruder_only()) {
    dot = ua[3] * ub[3];
  } else {
    double na = 0, nb = 0;
    for (std::size_t k = 0; k < 3; ++k) {
      dot += ua[k] * ub[k];
      na += ua[k] * ua[k];
      nb += ub[k] * ub[k];
    }
    dot /= std::sqrt(na * nb);
  }
  if (dot > 0.999) return a.feed_mm_s;
  if (rrf() && dot < -0.999) {
    // DDA.cpp MatchSpeeds: the speed change across the junction, |d_a - d_b| v = 2 v for a
    // reversal, may not exceed the axis' M566 jerk.
    const double jerk = std::abs(ua[0]) >= std::abs(ua[1]) ? jerk_x_mm_s_ : jerk_y_mm_s_;
    return std::min({jerk / 2, a.feed_mm_s, b.feed_mm_s});
  }
  return 0;
}

std::vector<std::string> Simulator::received() const {
  std::lock_guard<std::mutex> lock(mu_);
  return received_;
}

void Simulator::set_streaming(const std::string& sensor, bool on) {
  if (sensor == "accelerometer") stream_accel_ = on;
  else if (sensor == "load_cell") stream_load_ = on;
}

void Simulator::out_flush(const Emit& emit) {
  if (!out_.empty()) emit(out_);
  out_.clear();
}

void Simulator::step(const std::array<double, 4>& pos, const std::array<double, 4>& vel,
                     const std::array<double, 4>& acc0_in, const std::array<double, 3>& accm_in,
                     const std::array<double, 3>& acc1_in, const Emit& emit) {
  const double h = dt_;
  std::array<double, 4> acc0 = acc0_in;
  std::array<double, 3> accm = accm_in, acc1 = acc1_in;
  if (!cfg_.shapers.empty()) {
    // Input shaping: the commanded x/y acceleration is the sum of delayed, scaled copies.
    std::size_t need = 1;
    for (const auto& [axis, imp] : cfg_.shapers)
      for (const auto& [a, t] : imp) need = std::max(need, static_cast<std::size_t>(std::lround(t / h)) + 1);
    for (std::size_t ax = 0; ax < 2; ++ax) {
      auto& hist = shape_hist_[ax];
      if (hist.size() < need) hist.assign(need, {0.0, 0.0, 0.0});
      hist[shape_pos_ % hist.size()] = {acc0_in[ax], accm_in[ax], acc1_in[ax]};
      const auto it = cfg_.shapers.find(kAxisNames[ax]);
      if (it == cfg_.shapers.end()) continue;
      double s0 = 0, sm = 0, s1 = 0;
      for (const auto& [a, t] : it->second) {
        const std::size_t lag = static_cast<std::size_t>(std::lround(t / h));
        const auto& e = hist[(shape_pos_ + hist.size() - lag % hist.size()) % hist.size()];
        s0 += a * e[0];
        sm += a * e[1];
        s1 += a * e[2];
      }
      acc0[ax] = s0;
      accm[ax] = sm;
      acc1[ax] = s1;
    }
    ++shape_pos_;
  }
  std::array<double, 3> meas{acc1[0], acc1[1], acc1[2]};
  for (std::size_t ax = 0; ax < 3; ++ax) {
    const auto it = cfg_.modes.find(kAxisNames[ax]);
    if (it == cfg_.modes.end()) continue;
    auto& states = mode_state_[kAxisNames[ax]];
    double rel = 0;
    for (std::size_t m = 0; m < it->second.size(); ++m) {
      const auto& md = it->second[m];
      const double w = 2 * std::numbers::pi * md.freq_hz, c = 2 * md.zeta * w, k = w * w;
      auto f = [&](double z, double zd, double a) { return -c * zd - k * z - a; };
      double z = states[m][0], zd = states[m][1];
      const double k1z = zd, k1v = f(z, zd, acc0[ax]);
      const double k2z = zd + h / 2 * k1v, k2v = f(z + h / 2 * k1z, zd + h / 2 * k1v, accm[ax]);
      const double k3z = zd + h / 2 * k2v, k3v = f(z + h / 2 * k2z, zd + h / 2 * k2v, accm[ax]);
      const double k4z = zd + h * k3v, k4v = f(z + h * k3z, zd + h * k3v, acc1[ax]);
      z += h / 6 * (k1z + 2 * k2z + 2 * k3z + k4z);
      zd += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      states[m] = {z, zd};
      rel += md.weight * f(z, zd, acc1[ax]);
    }
    meas[ax] = acc1[ax] + rel;
  }
  // Liquefier: input is the commanded filament feed, delayed by the dead time.
  const double u = vel[3];
  const double ud = delay_[delay_pos_];
  delay_[delay_pos_] = u;
  delay_pos_ = (delay_pos_ + 1) % delay_.size();
  const double area = std::numbers::pi / 4 * cfg_.filament_diameter_mm * cfg_.filament_diameter_mm;
  double force;
  if (cfg_.liquefier == "fopdt") {
    const double target = cfg_.K_N_per_mm_s * ud;
    liq_ = target + (liq_ - target) * std::exp(-h / cfg_.tau_s);
    force = liq_;
  } else {
    const double q_out = std::pow(std::max(liq_, 0.0) / cfg_.k_MPa, 1.0 / cfg_.n_index);
    liq_ += h * (area * ud - q_out) / cfg_.compliance_mm3_MPa;
    force = liq_ * area;
  }
  if (deposit_sink) {
    const double flow = cfg_.liquefier == "fopdt" ? (cfg_.K_N_per_mm_s != 0 ? std::max(0.0, liq_ / cfg_.K_N_per_mm_s) * area : 0.0)
                                                   : std::pow(std::max(liq_, 0.0) / cfg_.k_MPa, 1.0 / cfg_.n_index);
    deposit_sink(t_ + h, pos, std::hypot(vel[0], vel[1]), flow);
  }
  t_ += h;
  ++step_;
  if (stream_accel_ && step_ % accel_every_ == 0) {
    const double ax = meas[0] + cfg_.cross_coupling * meas[1] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    const double ay = meas[1] + cfg_.cross_coupling * meas[0] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    const double az = 9810.0 + meas[2] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    if (accel_sink) accel_sink(t_, ax, ay, az);
    else fmt::format_to(std::back_inserter(out_), "echo:TKA {:.6f} {:.2f} {:.2f} {:.2f} {:.2f} {:.2f}\n", t_, ax, ay, az, acc1[0], acc1[1]);
    ++accel_sent_;
  }
  if (capture_left_ > 0 && step_ % accel_every_ == 0) {
    // An M956 run: sample number, then X, Y, Z in g (Accelerometers.cpp writes 3 decimals at
    // 10-bit resolution); the trailer "Rate %u, overflows %u" once the samples are taken.
    const double g = 9806.65;
    const double ax = meas[0] + cfg_.cross_coupling * meas[1] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    const double ay = meas[1] + cfg_.cross_coupling * meas[0] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    const double az = 9810.0 + meas[2] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    fmt::format_to(std::back_inserter(capture_text_), "{},{:.3f},{:.3f},{:.3f}\n", capture_index_++, ax / g, ay / g, az / g);
    if (--capture_left_ == 0) {
      capture_text_ += fmt::format("Rate {}, overflows 0\n", std::lround(cfg_.accel_rate_hz));
      std::lock_guard<std::mutex> lock(mu_);
      files_[capture_name_] = capture_text_;
    }
  }
  if (stream_load_ && step_ % load_every_ == 0) {
    const double f = cfg_.force_offset_N + force + cfg_.force_noise_N * normal_(rng_);
    if (load_cell_sink) load_cell_sink(t_, f);
    else fmt::format_to(std::back_inserter(out_), "echo:TKL {:.6f} {:.5f} {:.5f}\n", t_, u, f);
    ++load_sent_;
  }
  if (out_.size() > 32768) out_flush(emit);
}

void Simulator::execute(const GcodeMove& m, double v_entry, double v_exit, const Emit& emit) {
  double accel = m.accel_mm_s2, v_max = m.feed_mm_s;
  const double L = m.length_mm();
  if (klipper()) {
    if (m.extruder_only()) accel = std::min(accel, cfg_.max_extrude_only_accel_mm_s2);
    else v_max = std::min(v_max, std::sqrt(0.5 * (v_entry * v_entry + v_exit * v_exit) + accel * L * (1 - mcr_)));
  } else if (marlin() && min_segment_time_s_ > 0 && L / v_max < min_segment_time_s_) {
    v_max = L / min_segment_time_s_;  // planner.cpp: a block shorter than min_segment_time is slowed
  }
  v_max = std::max(v_max, 1e-6);
  const Profile prof = Profile::move(L, v_entry, v_max, v_exit, accel, cfg_.jerk_mm_s3);
  const auto u = m.unit();
  const double t0 = t_;
  const double T = prof.duration_s();
  const int n = static_cast<int>(std::floor(T / dt_ + 1e-9));
  if (move_sink && n > 0) move_sink(t_, n * dt_, prof, m.start, u);
  for (int i = 0; i < n; ++i) {
    const double tau = i * dt_;
    const PathState s0 = prof.at(tau), sm = prof.at(tau + dt_ / 2), s1 = prof.at(tau + dt_);
    std::array<double, 4> pos{}, vel{}, acc0{};
    std::array<double, 3> accm{}, acc1{};
    for (std::size_t k = 0; k < 4; ++k) {
      pos[k] = m.start[k] + u[k] * s1.pos_mm;
      vel[k] = u[k] * s1.vel_mm_s;
      acc0[k] = u[k] * s0.accel_mm_s2;
      if (k < 3) {
        accm[k] = u[k] * sm.accel_mm_s2;
        acc1[k] = u[k] * s1.accel_mm_s2;
      }
    }
    step(pos, vel, acc0, accm, acc1, emit);
  }
  (void)t0;
  // The fraction of a step left over is dropped: moves start on the sample grid.
}

void Simulator::dwell(double seconds, const Emit& emit) {
  const int n = static_cast<int>(std::lround(seconds / dt_));
  const std::array<double, 4> zero4{};
  const std::array<double, 3> zero3{};
  for (int i = 0; i < n; ++i) step(zero4, zero4, zero4, zero3, zero3, emit);
}

void Simulator::flush(const Emit& emit) {
  if (pending_) {
    execute(*pending_, pending_entry_, 0, emit);
    pending_.reset();
    pending_entry_ = 0;
  }
  out_flush(emit);
}

std::optional<std::string> Simulator::file(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mu_);
  const auto it = files_.find(name);
  if (it == files_.end()) return std::nullopt;
  return it->second;
}

// RepRapFirmware's M956 (src/Accelerometers/Accelerometers.cpp StartAccelerometer): P, S and A
// are required ("missing parameter"); X/Y/Z pick axes (all three when none is given; the
// simulated board records all three); F"name" names the file under 0:/sys/accelerometer/,
// otherwise <board>_<date>_<time>.csv; a run while one is collecting is refused.
void Simulator::m956(std::string_view body, const GcodeWords& /*words*/, const Emit& emit) {
  // The quoted file name is not parameters: parse the rest.
  std::string rest(body);
  if (const auto q = rest.find('"'); q != std::string::npos) {
    const auto q2 = rest.find('"', q + 1);
    rest.erase(q, q2 == std::string::npos ? std::string::npos : q2 - q + 1);
  }
  const auto parsed = parse_gcode(rest);
  const GcodeWords w = parsed ? *parsed : GcodeWords{};
  for (const char* k : {"P", "S", "A"})
    if (!w.has(k)) {
      emit(fmt::format("Error: M956: missing parameter '{}'\n", k));
      return;
    }
  if (capture_left_ > 0) {
    emit("Error: M956: Accelerometer is already collecting data\n");
    return;
  }
  std::string name = "0_2024-01-01_00.00.00.csv";
  if (const auto f = body.find("F\""); f != std::string_view::npos) {
    const auto end = body.find('"', f + 2);
    if (end != std::string_view::npos) name = std::string(body.substr(f + 2, end - f - 2));
  }
  capture_name_ = "0:/sys/accelerometer/" + name;
  capture_left_ = std::max(1L, std::lround(w.get("S", 0)));
  capture_index_ = 0;
  capture_text_ = "Sample,X,Y,Z\n";
  std::lock_guard<std::mutex> lock(mu_);
  files_[capture_name_] = capture_text_;
}

// Marlin's M493 (Marlin/src/gcode/feature/ft_motion/M493.cpp), on a build without
// HAS_DYNAMIC_FREQ: S on/off, X/Y shaper (0 NONE, 1 ZV, 2 ZVD, 3 ZVDD, 4 ZVDDD, 5 EI, 6 2HEI,
// 7 3HEI, 8 MZV), A/B base frequency (needs a shaper on the axis), I/J zeta, P linear advance
// on/off, K its gain; without parameters, or after a change that sets flag.report, it prints
// say_shaping(). A build without FT_MOTION answers as gcode.cpp does for any unknown command.
void Simulator::m493(const GcodeWords& w, const Emit& emit) {
  if (cfg_.ft_motion == "none") {
    emit("echo:Unknown command: \"M493\"\n");
    return;
  }
  bool report = w.args.empty();
  if (w.has("S")) {
    const bool on = w.get("S", 0) != 0;
    if (on != ftm_active_) report = true;
    ftm_active_ = on;
  }
  static const char* const kNames[] = {"", "ZV", "ZVD", "ZVDD", "ZVDDD", "EI", "2 Hump EI", "3 Hump EI", "MZV"};
  for (int a = 0; a < 2; ++a) {
    const std::string letter = a == 0 ? "X" : "Y";
    if (!w.has(letter)) continue;
    const int sh = static_cast<int>(w.get(letter, 0));
    if (sh < 0 || sh > 8) {
      emit(fmt::format("?Invalid [{}] shaper.\n", letter));
      return;
    }
    if (sh != ftm_shaper_[a]) report = true;
    ftm_shaper_[a] = sh;
  }
  if (w.has("P")) {
    ftm_la_ = w.get("P", 0) != 0;
    report = true;
    emit(ftm_la_ ? "Linear Advance enabled.\n" : "Linear Advance disabled.\n");
  }
  if (w.has("K")) {
    const double k = w.get("K", 0);
    if (k >= 0) {
      ftm_k_ = k;
      report = true;
    } else {
      emit("Linear Advance gain out of range.\n");
    }
  }
  for (int a = 0; a < 2; ++a) {
    const std::string f = a == 0 ? "A" : "B", z = a == 0 ? "I" : "J";
    if (w.has(f)) {
      if (ftm_shaper_[a] == 0) emit(fmt::format("Wrong mode for [{}] frequency.\n", f));
      else {
        ftm_freq_[a] = w.get(f, ftm_freq_[a]);
        report = true;
      }
    }
    if (w.has(z) && ftm_shaper_[a] != 0) ftm_zeta_[a] = w.get(z, ftm_zeta_[a]);
  }
  if (!report) return;
  std::string l = fmt::format("Fixed-Time Motion {}abled", ftm_active_ ? "en" : "dis");
  if (ftm_shaper_[0]) l += fmt::format(" with X axis {} shaping", kNames[ftm_shaper_[0]]);
  if (ftm_shaper_[1]) l += fmt::format(" and with Y axis {} shaping", kNames[ftm_shaper_[1]]);
  emit(l + ".\n");
  if (ftm_shaper_[0] || ftm_shaper_[1]) {
    emit(fmt::format("X static shaper frequency: {:.2f}Hz\n", ftm_freq_[0]));
    emit(fmt::format("Y static shaper frequency: {:.2f} Hz\n", ftm_freq_[1]));
  }
  emit(ftm_la_ ? fmt::format("Linear Advance enabled. Gain: {:.2f}\n", ftm_k_) : std::string("Linear Advance disabled\n"));
}

bool Simulator::handle_line(std::string_view raw, const Emit& emit) {
  std::string line(raw);
  while (!line.empty() && (line.back() == '\r' || line.back() == '\n' || line.back() == ' ')) line.pop_back();
  if (line.empty()) return true;
  ++received_count_;
  {
    std::lock_guard<std::mutex> lock(mu_);
    received_.push_back(line);
  }
  double late_ms = 0;
  for (const auto& f : cfg_.faults) {
    if (f.at_line != received_count_) continue;
    switch (f.kind) {
      case SimFault::Kind::drop: return true;  // as if the line never arrived
      case SimFault::Kind::disconnect: out_flush(emit); return false;
      case SimFault::Kind::garble: {
        // Corrupt a character of the command (not the checksum): the checksum no longer matches.
        const auto star = line.rfind('*');
        const std::size_t at = star != std::string::npos && star > 1 ? star - 1 : line.size() - 1;
        line[at] = static_cast<char>(line[at] ^ 0x04);
        break;
      }
      case SimFault::Kind::late_ok: late_ms = f.delay_ms; break;
      case SimFault::Kind::error:
        out_flush(emit);
        emit("Error:Thermal Runaway, system stopped! Heater_ID: 0\nError:Printer halted. kill() called!\n");
        halted_ = true;
        return true;
    }
  }
  if (halted_) return true;  // a killed Marlin answers nothing more
  const NumberedLine nl = split_numbered(line);
  if (nl.checksum && !nl.checksum_ok) {
    out_flush(emit);
    emit(fmt::format("Error:checksum mismatch, Last Line: {}\nResend: {}\nok\n", last_n_, last_n_ + 1));
    return true;
  }
  auto words = parse_gcode(nl.body);
  if (nl.number) {
    if (words && words->command == "M110") {
      last_n_ = static_cast<long>(words->get("N", static_cast<double>(*nl.number)));
      emit("ok\n");
      return true;
    }
    if (*nl.number == last_n_) {  // a line sent again after a late ok: already done
      emit("ok\n");
      return true;
    }
    if (*nl.number != last_n_ + 1) {
      out_flush(emit);
      emit(fmt::format("Error:Line Number is not Last Line Number+1, Last Line: {}\nResend: {}\nok\n", last_n_, last_n_ + 1));
      return true;
    }
    last_n_ = *nl.number;
  }
  if (words) {
    const std::string& c = words->command;
    if (c == "G0" || c == "G1") {
      if (auto m = interp_.apply(*words)) {
        if (carry_start_) {
          m->start = *carry_start_;  // Marlin: the joined move's distance is added to this one
          carry_start_.reset();
        }
        if (klipper() && m->extruder_only() && m->length_mm() > cfg_.max_extrude_only_distance_mm) {
          out_flush(emit);
          emit(fmt::format("!! Extrude only move too long ({:.3f}mm vs {:.3f}mm)\n", m->length_mm(),
                           cfg_.max_extrude_only_distance_mm));
          emit("ok\n");
          return true;
        }
        double steps = 0;
        for (std::size_t k = 0; k < 3; ++k) steps = std::max(steps, std::abs(m->end[k] - m->start[k]) * cfg_.steps_per_mm);
        if (marlin() && !m->extruder_only() && std::lround(steps) < 6) {
          carry_start_ = m->start;  // Configuration_adv.h MIN_STEPS_PER_SEGMENT 6
        } else {
          if (pending_) {
            const double v_exit = junction_speed(*pending_, *m);
            execute(*pending_, pending_entry_, v_exit, emit);
            pending_entry_ = v_exit;
          }
          pending_ = *m;
        }
      }
    } else if (c == "G4") {
      flush(emit);
      interp_.apply(*words);
      dwell(interp_.dwell_s(), emit);
    } else if (c == "M400") {
      flush(emit);
    } else if (c == "G28") {
      flush(emit);
      GcodeWords home;
      home.command = "G92";
      home.args = {{"X", 0}, {"Y", 0}, {"Z", 0}};
      interp_.apply(home);
    } else if (c == "M205" && words->has("B")) {
      min_segment_time_s_ = words->get("B", 20000) * 1e-6;
    } else if (c == "M566") {
      if (words->has("X")) jerk_x_mm_s_ = std::max(0.1, words->get("X", 900) / 60.0);  // Configuration.h MinimumJerk
      if (words->has("Y")) jerk_y_mm_s_ = std::max(0.1, words->get("Y", 900) / 60.0);
    } else if (c == "SET_VELOCITY_LIMIT") {
      interp_.apply(*words);
      if (words->has("MINIMUM_CRUISE_RATIO")) mcr_ = words->get("MINIMUM_CRUISE_RATIO", mcr_);
    } else if (c == "M410" && rrf()) {
      out_flush(emit);
      emit("Error: M410: Command is not supported\n");
    } else if (c == "M410") {
      pending_.reset();  // quickstop: queued motion is dropped
      pending_entry_ = 0;
    } else if (c == "M112") {
      pending_.reset();
      halted_ = true;
      out_flush(emit);
      return true;
    } else if (c == "M4100") {
      flush(emit);
      if (words->has("A")) set_streaming("accelerometer", words->get("A", 0) != 0);
      if (words->has("L")) set_streaming("load_cell", words->get("L", 0) != 0);
    } else if (c == "M955" && rrf()) {
      out_flush(emit);
      // Accelerometers.cpp ConfigureAccelerometer without other parameters: the report.
      emit(fmt::format("Accelerometer 0 type LIS3DH with orientation 20 samples at {}Hz with 10-bit resolution, SPI "
                       "frequency 2000000\n",
                       std::lround(cfg_.accel_rate_hz)));
    } else if (c == "M956" && rrf()) {
      flush(emit);
      m956(nl.body, *words, emit);
    } else if (c == "M493" && !klipper() && !rrf()) {
      out_flush(emit);
      m493(*words, emit);
    } else if (c == "M115") {
      out_flush(emit);
      if (klipper())
        emit(fmt::format("FIRMWARE_NAME:Klipper FIRMWARE_VERSION:v0.13.0-tunekit-sim-{}\n", TUNEKIT_VERSION));
      else if (rrf())
        emit(fmt::format("FIRMWARE_NAME: RepRapFirmware for tunekit-sim FIRMWARE_VERSION: 3.5.1 ELECTRONICS: tunekit-sim "
                         "{} FIRMWARE_DATE: 2024-01-01\n",
                         TUNEKIT_VERSION));
      else
        emit(fmt::format("FIRMWARE_NAME:Marlin 2.1.2 (tunekit-sim {}) SOURCE_CODE_URL:https://github.com/MarlinFirmware/Marlin "
                         "PROTOCOL_VERSION:1.0 MACHINE_TYPE:tunekit-sim EXTRUDER_COUNT:1 "
                         "UUID:00000000-0000-0000-0000-000000000000\n"
                         "Cap:EEPROM:0\nCap:AUTOREPORT_TEMP:0\n",
                         TUNEKIT_VERSION));
      if (cfg_.sensor_stream) emit("Cap:TUNEKIT_SENSOR_STREAM:1\n");
    } else if (c == "M105") {
      out_flush(emit);
      const double te = interp_.hotend_c.value_or(0), tb = interp_.bed_c.value_or(0);
      emit(fmt::format("ok T:{:.1f} /{:.1f} B:{:.1f} /{:.1f} @:0 B@:0\n", te, te, tb, tb));
      return true;
    } else if (c == "M114") {
      flush(emit);
      const auto& p = interp_.position();
      emit(fmt::format("X:{:.3f} Y:{:.3f} Z:{:.3f} E:{:.3f} Count X:0 Y:0 Z:0\n", p[0], p[1], p[2], p[3]));
    } else if (c == "M109" || c == "M190") {
      flush(emit);
      interp_.apply(*words);
      const double te = interp_.hotend_c.value_or(0), tb = interp_.bed_c.value_or(0);
      emit(fmt::format(" T:{:.1f} /{:.1f} B:{:.1f} /{:.1f} @:0 B@:0\n", te, te, tb, tb));
    } else {
      interp_.apply(*words);
    }
  }
  out_flush(emit);
  if (late_ms > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(late_ms));
  emit("ok\n");
  return true;
}

void serve_simulator(Simulator& sim, Transport& t, const std::atomic<bool>& stop) {
  std::string buf;
  const Simulator::Emit emit = [&](std::string_view s) { t.write(s); };
  try {
    while (!stop.load()) {
      const std::string chunk = t.read_some(std::chrono::milliseconds(50));
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
          std::this_thread::sleep_for(std::chrono::milliseconds(300));  // let the host read what was sent
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

void SimPtyServer::wait() {
  if (thread_.joinable()) thread_.join();
}

void SimPtyServer::serve() {
  FdTransport master(master_, "simulator pseudo-terminal master");
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

}  // namespace tunekit::protocols
