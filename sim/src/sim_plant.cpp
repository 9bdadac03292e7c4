// The simulator's plant: the planner's motion (junction speeds, velocity profiles, dwells) and
// the physical models it drives each step (input shaping, the axes' resonant modes with the
// accelerometer, the liquefier with the load cell). The liquefier model is SimConfig::liquefier.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>

#include <fmt/format.h>

#include "sim_constants.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/sim/simulator.hpp"

namespace tunekit::sim {

namespace {

/// One sensor line of the simulator's stream: "<tag> <v1> <v2> ...\n", each value with its
/// decimals (the resolution the line's format documents, simulator.hpp).
void append_data_line(std::string& out, std::string_view tag, std::initializer_list<core::FixedField> fields) {
  out.append(tag);
  out.push_back(' ');
  core::append_fixed_fields(out, ' ', fields);
  out.push_back('\n');
}

}  // namespace

Simulator::Simulator(SimConfig config)
    : cfg_(std::move(config)), heater_(cfg_.hot_end, sim::kHeaterNoiseSeedFactor * cfg_.seed + 1), rng_(cfg_.seed) {
  firmware_ = cfg_.firmware == "klipper" ? FirmwareRules::klipper
              : cfg_.firmware == "rrf"   ? FirmwareRules::rrf
                                         : FirmwareRules::marlin;
  dt_ = 1.0 / (cfg_.accel_rate_hz * sim::kStepsPerAccelSample);
  accel_every_ = sim::kStepsPerAccelSample;
  ftm_active_ = cfg_.ft_motion == "on";
  for (int a = 0; a < 2; ++a) {
    ftm_shaper_[a] = cfg_.ft_shaper[a];
    ftm_freq_[a] = cfg_.ft_freq_hz[a];
  }
  // The modes as the load on the bed moves them (the weights stay those of cfg_.modes).
  for (const auto& [axis, modes] : cfg_.loaded_modes()) {
    mode_state_[axis].assign(modes.size(), {0.0, 0.0});
    for (const auto& md : modes) {
      mode_physics_[axis].emplace_back(md.freq_hz, md.zeta);
      mode_dt_step_[axis].push_back(mode_physics_[axis].back().step(dt_));
    }
  }
  // The dead time in whole steps and a fraction of one: the delayed feed is interpolated between
  // the two steps around it, so that the plant's dead time is theta_s, not theta_s rounded to the
  // step (up to half of 78 us off, which is about the width of a fitted dead time's interval).
  const double steps = std::max(0.0, cfg_.theta_s / dt_);
  delay_frac_ = steps - std::floor(steps);
  delay_.assign(static_cast<std::size_t>(std::floor(steps)) + 1, 0.0);
  mcr_ = cfg_.minimum_cruise_ratio;
  // The firmware's default acceleration limits (sim_constants.hpp names their sources).
  for (const auto& l : cfg_.acceleration_gcode()) interp_.apply(*machine::parse_gcode(l));
}

double Simulator::junction_speed(const machine::GcodeMove& a, const machine::GcodeMove& b) const {
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
  // Straight on: the lower of the two moves' speeds (Klipper toolhead.py calc_junction: the
  // minimum of both max_cruise_v2; Marlin planner.cpp: the previous and this block's nominal speed).
  if (dot > sim::kStraightJunctionCos) return std::min(a.feed_mm_s, b.feed_mm_s);
  if (rrf() && dot < -sim::kStraightJunctionCos) {
    // DDA.cpp MatchSpeeds: the speed change across the junction, |d_a - d_b| v = 2 v for a
    // reversal, may not exceed the axis' M566 jerk.
    const double jerk = std::abs(ua[0]) >= std::abs(ua[1]) ? jerk_x_mm_s_ : jerk_y_mm_s_;
    return std::min({jerk / 2, a.feed_mm_s, b.feed_mm_s});
  }
  return 0;
}

std::array<double, 3> Simulator::step_modes(const std::array<double, 4>& acc0, const std::array<double, 3>& accm,
                                            const std::array<double, 3>& acc1, const std::vector<PathPiece>* path,
                                            const std::array<double, 4>* unit) {
  const double h = dt_;
  std::array<double, 3> meas{acc1[0], acc1[1], acc1[2]};
  for (std::size_t ax = 0; ax < 3; ++ax) {
    const auto it = cfg_.modes.find(machine::kAxisNames[ax]);
    if (it == cfg_.modes.end()) continue;
    const std::string& name = it->first;
    auto& states = mode_state_[name];
    const auto& physics = mode_physics_[name];
    const bool exact = path != nullptr && unit != nullptr && cfg_.shapers.find(name) == cfg_.shapers.end();
    double rel = 0;
    for (std::size_t m = 0; m < it->second.size(); ++m) {
      ident::ModeState x{states[m][0], states[m][1]};
      if (exact) {
        const double u = (*unit)[ax];
        for (const auto& p : *path)
          x = p.h_s == h ? ident::BaseExcitedMode::apply(mode_dt_step_[name][m], x, u * p.accel_mm_s2, u * p.jerk_mm_s3)
                         : physics[m].advance(x, p.h_s, u * p.accel_mm_s2, u * p.jerk_mm_s3);
      } else {
        auto f = [&](double z, double zd, double a) { return physics[m].relative_accel({z, zd}, a); };
        const double z = x.z_mm, zd = x.v_mm_s;
        const double k1z = zd, k1v = f(z, zd, acc0[ax]);
        const double k2z = zd + h / 2 * k1v, k2v = f(z + h / 2 * k1z, zd + h / 2 * k1v, accm[ax]);
        const double k3z = zd + h / 2 * k2v, k3v = f(z + h / 2 * k2z, zd + h / 2 * k2v, accm[ax]);
        const double k4z = zd + h * k3v, k4v = f(z + h * k3z, zd + h * k3v, acc1[ax]);
        x = {z + h / 6 * (k1z + 2 * k2z + 2 * k3z + k4z), zd + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)};
      }
      states[m] = {x.z_mm, x.v_mm_s};
      rel += it->second[m].weight * physics[m].relative_accel(x, acc1[ax]);
    }
    meas[ax] = acc1[ax] + rel;
  }
  return meas;
}

void Simulator::step(const std::array<double, 4>& pos, const std::array<double, 4>& vel,
                     const std::array<double, 4>& acc0_in, const std::array<double, 3>& accm_in,
                     const std::array<double, 3>& acc1_in, const Emit& emit, const std::vector<PathPiece>* path,
                     const std::array<double, 4>* unit) {
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
      const auto it = cfg_.shapers.find(machine::kAxisNames[ax]);
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
  const std::array<double, 3> meas = step_modes(acc0, accm, acc1, path, unit);
  // Liquefier: input is the commanded filament feed, delayed by the dead time.
  const double u = vel[3];
  // delay_[delay_pos_] was written delay_.size() steps ago, the next one a step later.
  const std::size_t n = delay_.size();
  const double newer = n == 1 ? u : delay_[(delay_pos_ + 1) % n];
  const double ud = newer + delay_frac_ * (delay_[delay_pos_] - newer);
  delay_[delay_pos_] = u;
  delay_pos_ = (delay_pos_ + 1) % n;
  const double area = std::numbers::pi / 4 * cfg_.filament_diameter_mm * cfg_.filament_diameter_mm;
  double force;
  if (cfg_.liquefier == LiquefierModel::fopdt) {
    const double target = cfg_.K_N_per_mm_s * ud;
    // The time constant of the flow leaving the nozzle (the state, as a filament feed): a melt's
    // shear rate is set by what flows through the nozzle, not by the feed commanded this instant.
    // The exponential step with the time constant at the half step's state (second order in h:
    // with it taken at the step's start, a chirp's fast swings of the state put a deterministic
    // error of a few 1e-4 into the time constant, beside the fitted interval's 1e-3).
    auto tau_of = [&](double x) { return cfg_.tau_at_feed(cfg_.K_N_per_mm_s != 0 ? x / cfg_.K_N_per_mm_s : ud); };
    const double half = target + (liq_ - target) * std::exp(-0.5 * h / tau_of(liq_));
    liq_ = target + (liq_ - target) * std::exp(-h / tau_of(half));
    force = liq_;
  } else {
    // The explicit midpoint rule (second order, as the first-order plant's step).
    auto rate = [&](double p) {
      return (area * ud - std::pow(std::max(p, 0.0) / cfg_.k_MPa, 1.0 / cfg_.n_index)) / cfg_.compliance_mm3_MPa;
    };
    liq_ += h * rate(liq_ + 0.5 * h * rate(liq_));
    force = liq_ * area;
  }
  if (deposit_sink) {
    const double flow = cfg_.liquefier == LiquefierModel::fopdt
                            ? (cfg_.K_N_per_mm_s != 0 ? std::max(0.0, liq_ / cfg_.K_N_per_mm_s) * area : 0.0)
                            : std::pow(std::max(liq_, 0.0) / cfg_.k_MPa, 1.0 / cfg_.n_index);
    deposit_sink(t_ + h, pos, std::hypot(vel[0], vel[1]), flow);
  }
  t_ += h;
  ++step_;
  if (stream_accel_ && step_ % accel_every_ == 0) {
    const double ax = meas[0] + cfg_.cross_coupling * meas[1] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    const double ay = meas[1] + cfg_.cross_coupling * meas[0] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    const double az = sim::kAccelRestZ_mm_s2 + meas[2] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    if (accel_sink) {
      accel_sink(t_, ax, ay, az);
    } else {
      append_data_line(out_, "echo:TKA", {{t_, 7}, {ax, 2}, {ay, 2}, {az, 2}, {acc1[0], 2}, {acc1[1], 2}});
    }
    ++accel_sent_;
  }
  if (capture_left_ > 0 && step_ % accel_every_ == 0) {
    // An M956 run: sample number, then X, Y, Z in g (Accelerometers.cpp writes 3 decimals at
    // 10-bit resolution); the trailer "Rate %u, overflows %u" once the samples are taken.
    const double g = sim::kStandardGravity_mm_s2;
    const double ax = meas[0] + cfg_.cross_coupling * meas[1] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    const double ay = meas[1] + cfg_.cross_coupling * meas[0] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    const double az = sim::kAccelRestZ_mm_s2 + meas[2] + cfg_.accel_noise_mm_s2 * normal_(rng_);
    fmt::format_to(std::back_inserter(capture_text_), "{},{:.3f},{:.3f},{:.3f}\n", capture_index_++, ax / g, ay / g,
                   az / g);
    if (--capture_left_ == 0) {
      capture_text_ += fmt::format("Rate {}, overflows 0\n", std::lround(cfg_.accel_rate_hz));
      std::lock_guard<std::mutex> lock(mu_);
      files_[capture_name_] = capture_text_;
    }
  }
  const double fed_before = fed_total_mm_;
  fed_total_mm_ += u * h;
  run_heater(h, u * h);
  if (stream_load_) sample_load_cell(h, fed_before, cfg_.force_offset_N + force);
  load_force_before_ = cfg_.force_offset_N + force;
  if (out_.size() > sim::kOutputFlushBytes) out_flush(emit);
}

void Simulator::sample_load_cell(double h, double fed_before, double force_now) {
  const double t0 = t_ - h, period = load_cell_period();
  auto at = [&](double t, double before, double now) { return before + (now - before) * (t - t0) / h; };
  while (next_load_edge_t_ <= t_ || next_load_t_ <= t_) {
    if (next_load_edge_t_ <= next_load_t_) {  // a window ends: the sample waiting for it goes out
      emit_pending_load_sample(next_load_edge_t_, at(next_load_edge_t_, fed_before, fed_total_mm_));
      next_load_edge_t_ += period;
      continue;
    }
    const double f = at(next_load_t_, load_force_before_, force_now) + cfg_.force_noise_N * normal_(rng_);
    if (load_cell_sink) {
      load_cell_sink(next_load_t_, f);
      ++load_sent_;
    } else {
      load_pending_ = true;
      pending_t_ = next_load_t_;
      pending_force_ = f;
    }
    next_load_t_ += period;
  }
}

double Simulator::load_cell_period() const { return 1.0 / (cfg_.load_cell_rate_hz * (1 + cfg_.load_cell_clock_error)); }

void Simulator::start_load_cell() {
  const double period = load_cell_period();
  // The converter's clock ticks at whole periods from power-up (t = 0), whenever the stream starts.
  next_load_t_ = (std::floor(t_ / period) + 1) * period;
  // The first sample's window opens half a period before it (at the stream's start if later).
  next_load_edge_t_ = next_load_t_ - 0.5 * period;
  if (next_load_edge_t_ < t_) next_load_edge_t_ += period;
  window_start_t_ = t_;
  fed_at_window_start_ = fed_total_mm_;
}

void Simulator::emit_pending_load_sample(double t, double fed_mm) {
  if (load_pending_) {
    const double span = t - window_start_t_;
    const double u_mean = span > 0 ? (fed_mm - fed_at_window_start_) / span : 0.0;
    append_data_line(out_, "echo:TKL", {{pending_t_, 6}, {u_mean, 5}, {pending_force_, 5}});
    load_pending_ = false;
    ++load_sent_;
  }
  window_start_t_ = t;
  fed_at_window_start_ = fed_mm;
}

namespace {

/// The commanded path acceleration over profile times [ta, tb] of one step, piece by piece. Before
/// the profile's start it holds the start's acceleration, after its end the end's (Profile::at
/// clamps the same way). `cursor` is the first piece that may still overlap, kept between steps.
void step_path(const std::vector<machine::Profile::Piece>& pieces, const machine::Profile& prof, double ta, double tb,
               std::size_t& cursor, std::vector<Simulator::PathPiece>& out) {
  out.clear();
  double t = ta;
  if (t < 0) {
    const double until = std::min(tb, 0.0);
    out.push_back({until - t, prof.at(0).accel_mm_s2, 0.0});
    t = until;
  }
  while (t < tb && cursor < pieces.size()) {
    const auto& p = pieces[cursor];
    const double end = p.t0_s + p.duration_s;
    if (end <= t) {
      ++cursor;
      continue;
    }
    const double to = std::min(tb, end);
    out.push_back({to - t, p.accel_mm_s2 + p.jerk_mm_s3 * (t - p.t0_s), p.jerk_mm_s3});
    t = to;
  }
  if (t < tb) out.push_back({tb - t, prof.at(prof.duration_s()).accel_mm_s2, 0.0});
  // One piece over the whole step: exactly dt, so that the mode's step of dt applies.
  if (out.size() == 1) out.front().h_s = tb - ta;
}

}  // namespace

/// Pieces shorter than the streamed times' resolution (1 ns) are left out of echo:TKM: their
/// acceleration acts for under a nanosecond, and their rounded start would not follow the one before.
constexpr double kShortestStreamedPiece_s = 1e-9;

void Simulator::stream_commanded_motion(double t_start, double t_end, double origin, const machine::Profile& prof,
                                        const std::array<double, 4>& u) {
  // What the steps of this move run: the profile from origin, clipped to [t_start, t_end]; before
  // the origin the profile's start holds (step_path).
  auto line = [&](double t0, double d, double a, double j) {
    if (!(d >= kShortestStreamedPiece_s)) return;
    append_data_line(out_, "echo:TKM", {{t0, 9}, {d, 9}, {u[0] * a, 4}, {u[1] * a, 4}, {u[0] * j, 1}, {u[1] * j, 1}});
  };
  if (origin > t_start) line(t_start, std::min(origin, t_end) - t_start, prof.at(0).accel_mm_s2, 0);
  for (const auto& p : prof.pieces()) {
    const double s0 = origin + p.t0_s, cs = std::max(s0, t_start), ce = std::min(s0 + p.duration_s, t_end);
    if (ce > cs) line(cs, ce - cs, p.accel_mm_s2 + p.jerk_mm_s3 * (cs - s0), p.jerk_mm_s3);
  }
  const double end = origin + prof.duration_s();
  if (end < t_end) line(end, t_end - end, prof.at(prof.duration_s()).accel_mm_s2, 0);
}

double Simulator::execute(const machine::GcodeMove& m, double v_entry, double v_exit, const Emit& emit) {
  double accel = m.accel_mm_s2, v_max = m.feed_mm_s;
  const double L = m.length_mm();
  if (klipper()) {
    if (m.extruder_only()) accel = std::min(accel, cfg_.max_extrude_only_accel_mm_s2);
    else v_max = std::min(v_max, std::sqrt(0.5 * (v_entry * v_entry + v_exit * v_exit) + accel * L * (1 - mcr_)));
  } else if (marlin() && min_segment_time_s_ > 0 && L / v_max < min_segment_time_s_) {
    v_max = L / min_segment_time_s_;  // planner.cpp: a block shorter than min_segment_time is slowed
  }
  v_max = std::max(v_max, sim::kMinPeakSpeed_mm_s);
  const machine::Profile prof = machine::Profile::move(L, v_entry, v_max, v_exit, accel, cfg_.jerk_mm_s3);
  const auto u = m.unit();
  // A move joined at speed to the one before starts step_carry_s_ before the sample grid's
  // current time (what that move left of its last step): its steps sample it that much later, so
  // that a chain of short moves (a resonance sweep) keeps its total time. After a move that ends
  // at rest, or extrudes (the printing and feeding protocols' timing on the grid, which their
  // tests were measured with), the fraction of a step left over is dropped.
  const double T = prof.duration_s(), shift = step_carry_s_;
  const int n = static_cast<int>(std::floor((T + shift) / dt_ + sim::kStepCountSlack));
  const double v_end = prof.at(T).vel_mm_s;
  const bool joined = v_end > 0 && m.end[3] == m.start[3];
  step_carry_s_ = joined ? std::max(0.0, T + shift - n * dt_) : 0.0;
  if (move_sink && n > 0) move_sink(t_, n * dt_, prof, m.start, u);
  if (stream_accel_ && !accel_sink && n > 0) stream_commanded_motion(t_, t_ + n * dt_, t_ + shift, prof, u);
  const std::vector<machine::Profile::Piece> pieces = prof.pieces();
  std::vector<PathPiece> path;
  std::size_t cursor = 0;
  for (int i = 0; i < n; ++i) {
    const double tau = i * dt_ - shift;
    step_path(pieces, prof, tau, tau + dt_, cursor, path);
    const machine::PathState s0 = prof.at(tau), sm = prof.at(tau + dt_ / 2), s1 = prof.at(tau + dt_);
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
    step(pos, vel, acc0, accm, acc1, emit, &path, &u);
  }
  return v_end;  // below v_exit when the move is too short to reach it
}

void Simulator::dwell(double seconds, const Emit& emit) {
  const int n = static_cast<int>(std::lround(seconds / dt_));
  const std::array<double, 4> zero4{};
  const std::array<double, 3> zero3{};
  const std::vector<PathPiece> rest{{dt_, 0.0, 0.0}};
  for (int i = 0; i < n; ++i) step(zero4, zero4, zero4, zero3, zero3, emit, &rest, &zero4);
}

void Simulator::run_heater(double h, double fed_mm) {
  heater_dt_ += h;
  heater_fed_ += fed_mm;
  if (heater_dt_ >= sim::kHeaterChunk_s) sync_heater();
}

void Simulator::sync_heater() {
  if (heater_dt_ > 0) heater_.advance(heater_dt_, heater_fed_);
  heater_dt_ = heater_fed_ = 0;
  const auto& r = heater_.record();
  // A sample is complete (its fan and feed means known) once the next tick is taken.
  for (; stream_heater_ && heater_sent_ + 1 < r.t_s.size(); ++heater_sent_) {
    const std::size_t i = heater_sent_;
    append_data_line(out_, "echo:TKH",
                     {{r.t_s[i], 3},
                      {r.temp_c[i], 2},
                      {r.target_c[i], 1},
                      {r.heater_duty[i], 4},
                      {r.fan_duty[i], 4},
                      {r.feed_mm_s[i], 4}});
  }
  auto_report();
}

void Simulator::flush(const Emit& emit) {
  if (pending_) {
    execute(*pending_, pending_entry_, 0, emit);
    pending_.reset();
    pending_entry_ = 0;
  }
  out_flush(emit);
}

}  // namespace tunekit::sim
