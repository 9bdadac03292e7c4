#include "run_sessions.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>

#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/heater_log.hpp"
#include "tunekit/ident/rrf_accelerometer.hpp"
#include "tunekit/machine/klipper_api.hpp"
#include "tunekit/machine/klipper_sensors.hpp"
#include "tunekit/machine/klipper_settings.hpp"
#include "tunekit/machine/rrf_http.hpp"
#include "tunekit/protocols/safety.hpp"

namespace tunekit::protocols::detail {

/// Parses whitespace-separated numbers after a prefix; returns how many were read.
int parse_numbers(std::string_view s, double* out, int max) {
  const char* p = s.data();
  const char* const end = s.data() + s.size();
  int n = 0;
  while (n < max) {
    while (p < end && (*p == ' ' || *p == '\t')) ++p;
    if (p < end && *p == '+') ++p;
    const auto [next, ec] = std::from_chars(p, end, out[n]);
    if (ec != std::errc() || next == p) break;
    ++n;
    p = next;
  }
  return n;
}

bool Recorder::marlin_report(std::string_view l) {
  if (l.find("T:") == std::string_view::npos || l.find("@:") == std::string_view::npos) return false;
  formats::HeaterLog one;
  try {
    one = formats::read_marlin_temperature_reports(l, 1.0);
  } catch (const InputError&) {
    return false;  // no hot end with its power: not a report of use (journaled as received)
  }
  const double t = report_clock_();
  ThermalInput in;
  for (const auto& i : thermal_inputs_)
    if (i.from_s <= t) in = i;
  const double v[6] = {t, one.temp_c.front(), one.target_c.front(), one.duty.front(), in.fan_duty, in.feed_mm_s};
  thermal(v);
  return true;
}

namespace {

constexpr std::chrono::milliseconds kHttpTimeout{5000};
// Marlin's temperature auto-report interval the heater is recorded at, s (M155 S1).
constexpr int kReportInterval_s = 1;
// Lines kept unanswered on Klipper's G-code pseudo-terminal. Klipper stops reading at 20
// pending commands (klippy/gcode.py); 8 keeps the link busy without filling its queue, and an
// interrupted run has at most 8 lines queued beyond the one that was answering.
constexpr std::size_t kKlipperReadAhead = 8;

class GcodeSession : public Session {
 public:
  GcodeSession(std::unique_ptr<machine::Transport> t, machine::Journal& j, Recorder& rec,
               const machine::LinkOptions& lo, const std::atomic<bool>* abort, SendGuard& guard, std::string http,
               std::optional<std::string> http_password)
      : t_(std::move(t)),
        link_(*t_, &j, lo),
        j_(j),
        rec_(rec),
        http_(std::move(http)),
        http_password_(std::move(http_password)) {
    link_.guard = &guard;
    link_.on_line = [&rec](std::string_view l) { return rec.line(l); };
    link_.on_batch = [&j] { j.flush(); };
    link_.abort_flag = abort;
  }
  firmware::FirmwareInfo identify() override {
    link_.reset_line_numbers();
    firmware::FirmwareInfo f = firmware::parse_m115(link_.send("M115"));
    // Marlin's M115 names no FT_MOTION capability: ask M493 (a bare M493 only reports; a build
    // without FT_MOTION answers "Unknown command"). With fixed-time motion active the classic
    // shaper and smooth linear advance are bypassed, so settings go to M493.
    // The 2025 report form ("(X=ZV ; Y=MZV)") does not tell which letters set a shaper: builds
    // that take C<shaper> answer M493 V with "FTM V2" (M493.cpp), earlier ones nothing.
    if (f.firmware == firmware::Firmware::marlin) {
      auto answer = link_.send("M493");
      if (firmware::parse_m493_report(answer).form == firmware::M493Form::axis_list) {
        const auto v = link_.send("M493 V");
        answer.insert(answer.end(), v.begin(), v.end());
      }
      f.m493 = firmware::parse_m493_report(answer);
      f.ft_motion = f.m493.present;
      f.ft_motion_active = f.m493.active;
    }
    return f;
  }
  void send(const std::string& line) override { link_.send(line); }
  void send_lines(const std::vector<std::string>& lines, const std::atomic<bool>& /*abort: the link's flag*/) override {
    // Klipper reads ahead and answers each line in order (its API session sends scripts of 50
    // lines); Marlin's and RepRapFirmware's small receive buffers and line-number resends want
    // one line in flight.
    link_.send_pipelined(lines, firmware.firmware == firmware::Firmware::klipper ? kKlipperReadAhead : 1);
  }
  void record(const std::string& sensor, bool on, double window_s) override {
    if (!firmware.sensor_stream() && rrf_file_accelerometer(sensor)) {
      if (on) start_m956(window_s);
      else fetch_m956();
      return;
    }
    if (!firmware.sensor_stream() && marlin_auto_report(sensor)) {
      if (on) start_auto_report();
      else stop_auto_report();
      return;
    }
    // tunekit-sim streams with M4100 whichever firmware it follows.
    const std::string cmd = firmware.sensor_stream()
                                ? firmware::Dialect(firmware::Firmware::marlin).sensor_stream(sensor, on)
                                : dialect.sensor_stream(sensor, on);
    if (cmd.empty() || !firmware.sensor_stream())
      throw MachineError(
          fmt::format("the firmware ({}) does not stream {} data over this link (it reports no "
                      "Cap:TUNEKIT_SENSOR_STREAM); use Klipper's API socket (--port unix:PATH) or tunekit-sim",
                      firmware.name.empty() ? "unidentified" : firmware.name, sensor),
          t_->describe());
    link_.send(cmd);
  }
  bool can_record(const std::string& sensor) const override {
    return firmware.sensor_stream() || rrf_file_accelerometer(sensor) || marlin_auto_report(sensor);
  }
  void check_recording(const std::string& sensor) override {
    // A wrong or missing password fails here, before heating or homing, not after the test.
    if (!firmware.sensor_stream() && rrf_file_accelerometer(sensor)) {
      const machine::RrfLogin login(machine::parse_http_address(http_), http_password_, kHttpTimeout);
    }
  }
  void finish() override {}
  void safe_state(const std::vector<std::string>& commands) override {
    auto lines = commands;
    if (auto_report_on_) lines.push_back("M155 S0");  // the reports stop with the run
    link_.send_best_effort(lines, std::chrono::milliseconds(300));
    auto_report_on_ = false;
    rec_.stop_reports();
  }
  nlohmann::json stats() const override {
    const auto& s = link_.stats();
    nlohmann::json j{{"lines_sent", s.lines_sent},
                     {"resends", s.resends},
                     {"retries", s.retries},
                     {"busy", s.busy},
                     {"data_lines", s.data_lines}};
    if (!m956_files_.empty()) j["rrf_accelerometer_files"] = m956_files_;
    return j;
  }

 private:
  /// Marlin built with AUTO_REPORT_TEMPERATURES (M115 "Cap:AUTOREPORT_TEMP:1") reports the hot
  /// end's reading, target and soft-PWM power by itself (M155 S<seconds>): the heater's record.
  bool marlin_auto_report(const std::string& sensor) const {
    const auto cap = firmware.capabilities.find("AUTOREPORT_TEMP");
    return firmware.firmware == firmware::Firmware::marlin && sensor == "heater" &&
           cap != firmware.capabilities.end() && cap->second;
  }
  void start_auto_report() {
    const std::string cmd = fmt::format("M155 S{}", kReportInterval_s);
    for (const auto& l : link_.send(cmd))
      if (l.find("Unknown command") != std::string::npos)
        throw MachineError(fmt::format("the firmware answered '{}' with '{}': it offers Cap:AUTOREPORT_TEMP but "
                                       "has no temperature auto-report; the heater was not turned on",
                                       cmd, l),
                           t_->describe());
    auto_report_on_ = true;
    // Each report at the host's time of arrival on a real printer; on the simulated printer (its
    // M115 names tunekit-sim), whose clock runs as fast as it is read, at its place in the schedule.
    if (firmware.name.find("tunekit-sim") == std::string::npos) {
      const auto t0 = std::chrono::steady_clock::now();
      rec_.start_reports([t0] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); });
    } else {
      rec_.start_reports([n = 0]() mutable { return static_cast<double>(++n * kReportInterval_s); });
    }
  }
  void stop_auto_report() {
    link_.send("M155 S0");
    auto_report_on_ = false;
    rec_.stop_reports();
  }
  /// RepRapFirmware records its accelerometer into a file (M956); tunekit fetches it over the
  /// board's web server (rrf_http.hpp), the only way RepRapFirmware offers to read a file.
  bool rrf_file_accelerometer(const std::string& sensor) const {
    return firmware.firmware == firmware::Firmware::reprapfirmware && sensor == "accelerometer" && !http_.empty();
  }
  void start_m956(double window_s) {
    // Accelerometers.cpp: M955 P0 reports "... samples at <rate>Hz ..."; M956 takes a count.
    const auto rate = machine::parse_m955_rate_hz(link_.send("M955 P0"));
    if (!rate)
      throw MachineError("RepRapFirmware reports no accelerometer (M955 P0): configure it with M955 first",
                         t_->describe());
    m956_rate_hz_ = *rate;
    // The window as planned plus a second: RepRapFirmware cannot stop a run early.
    const long samples = std::lround(std::ceil(*rate * (std::max(0.0, window_s) + 1.0)));
    m956_name_ = fmt::format("tunekit_{}.csv", m956_files_.size() + 1);
    m956_window_s_ = window_s + 1.0;
    link_.send(fmt::format("M956 P0 S{} A0 F\"{}\"", samples, m956_name_));
  }
  void fetch_m956() {
    link_.send("M400");
    const auto addr = machine::parse_http_address(http_);
    const machine::RrfLogin login(addr, http_password_, kHttpTimeout);
    const std::string name = "0:/sys/accelerometer/" + m956_name_;
    std::string bytes;
    // The run ends after its sample count, in the board's time: poll, waiting G4 P250 between
    // reads (on a real board 250 ms; the simulator's clock runs with the dwell).
    const int polls = static_cast<int>(std::ceil(m956_window_s_ / 0.25)) + 40;
    for (int i = 0;; ++i) {
      bytes = machine::rrf_download(login.session(), name, kHttpTimeout);
      if (machine::rrf_accelerometer_file_complete(bytes)) break;
      if (i >= polls)
        throw MachineError(fmt::format("the accelerometer file {} did not finish within {:.1f} s", name, polls * 0.25),
                           addr.text());
      link_.send("G4 P250");
    }
    const std::string local = "rrf_" + m956_name_;
    core::write_file_atomic(j_.path(local), bytes);
    m956_files_.push_back(local);
    // The file as RepRapFirmware wrote it, read by the RRF reader (g -> mm/s^2, time from the rate).
    ident::AccelInputOptions opts;
    const auto rec = ident::load_rrf_accelerometer_csv(j_.path(local), bytes, opts);
    const double dt = rec.sampling.sample_rate_hz > 0 ? 1.0 / rec.sampling.sample_rate_hz : 1.0 / m956_rate_hz_;
    const std::size_t n = rec.channels.empty() ? 0 : rec.channels.front().size();
    auto ch = [&](std::size_t c, std::size_t i) { return c < rec.channels.size() ? rec.channels[c][i] : 0.0; };
    for (std::size_t i = 0; i < n; ++i) rec_.accel(static_cast<double>(i) * dt, ch(0, i), ch(1, i), ch(2, i));
  }
  std::unique_ptr<machine::Transport> t_;
  machine::GcodeLink link_;
  machine::Journal& j_;
  Recorder& rec_;
  std::string http_;
  std::optional<std::string> http_password_;  // never journaled or shown
  std::string m956_name_;
  double m956_rate_hz_ = 0, m956_window_s_ = 0;
  std::vector<std::string> m956_files_;
  bool auto_report_on_ = false;
};

class KlipperSession : public Session {
 public:
  KlipperSession(std::unique_ptr<machine::Transport> t, machine::Journal& j, Recorder& rec,
                 const machine::LinkOptions& lo, const machine::Sensors& sensors, SendGuard& guard)
      : client_(std::move(t), &j), j_(j), rec_(rec), timeout_(lo.timeout), sensors_(sensors), guard_(guard) {
    client_.on_message = [this](const nlohmann::json& m) { on_message(m); };
    client_.on_batch = [&j] { j.flush(); };
  }
  firmware::FirmwareInfo identify() override {
    // webhooks.py _handle_info_request: state "ready" once the configuration is loaded and the
    // micro-controllers are connected; "startup", "shutdown" or "error" otherwise.
    const auto info = client_.call("info", {{"client_info", {{"name", "tunekit"}}}}, timeout_);
    nlohmann::json query = nlohmann::json::object();
    if (info.value("state", "") == "ready")
      query = client_.call("objects/query", machine::klipper_settings_query(), timeout_);
    settings_ = machine::parse_klipper_settings(info, query);
    if (settings_.state != "ready")
      throw MachineError(
          fmt::format("Klipper is not ready (state '{}'{}{}); nothing but info was sent", settings_.state,
                      settings_.state_message.empty() ? "" : ": ", settings_.state_message),
          client_.transport().describe());
    firmware::FirmwareInfo f;
    f.firmware = firmware::Firmware::klipper;
    f.name = "Klipper";
    f.version = settings_.software_version;
    return f;
  }
  machine::MachineProfile with_firmware_limits(const machine::MachineProfile& p,
                                               std::vector<std::string>& notes) const override {
    return machine::with_klipper_settings(p, settings_, notes);
  }
  void send(const std::string& line) override {
    if (const auto why = guard_.refuse(line))
      throw MachineError(fmt::format("refused to send '{}': {} (nothing of it was sent)", line, *why),
                         client_.transport().describe());
    pending_.push_back(line);
    if (pending_.size() >= 50) flush_script();
  }
  void record(const std::string& sensor, bool on, double /*window_s*/) override {
    flush_script();
    if (sensor == "accelerometer") {
      if (on && !accel_subscribed_) {
        // The samples, and the toolhead's commanded motion on the same print-time clock (what
        // Klipper's motan data logger records): the modes are then fitted against the motion.
        const auto ep =
            machine::klipper_accelerometer_endpoint(sensors_.accelerometer_chip, sensors_.accelerometer_name);
        client_.call(ep.method, ep.params({{"tunekit", "accel"}}), timeout_);
        const auto tq = machine::klipper_trapq_endpoint("toolhead");
        client_.call(tq.method, tq.params({{"tunekit", "trapq_toolhead"}}), timeout_);
        accel_subscribed_ = true;
      }
      if (!on) {
        client_.pump(kBatchWait);  // the last batch of samples
        write_toolhead_motion();
      }
      accel_on_ = on;
      return;
    }
    if (sensor == "load_cell") {
      if (on && !load_subscribed_) {
        // The force stream, and the extruder's commanded motion on the same print-time clock:
        // the feed column is the trapq's extruder velocity at each force sample's time.
        const auto lc = machine::klipper_load_cell_endpoint(sensors_.load_cell_name);
        client_.call(lc.method, lc.params({{"tunekit", "load_cell"}}), timeout_);
        const auto tq = machine::klipper_trapq_endpoint("extruder");
        client_.call(tq.method, tq.params({{"tunekit", "trapq_extruder"}}), timeout_);
        load_subscribed_ = true;
      }
      if (!on) {
        client_.pump(kBatchWait);
        write_load_cell();
      }
      load_on_ = on;
      return;
    }
    throw MachineError(fmt::format("Klipper's API server streams no {} data", sensor), client_.transport().describe());
  }
  void finish() override {
    flush_script();
    if (accel_on_) write_toolhead_motion();
    if (load_on_) {
      client_.pump(kBatchWait);
      write_load_cell();
    }
  }
  bool can_record(const std::string& sensor) const override {
    return sensor == "accelerometer" || sensor == "load_cell";
  }
  void safe_state(const std::vector<std::string>& commands) override {
    try {
      std::string script;
      for (const auto& c : commands) script += (script.empty() ? "" : "\n") + c;
      client_.call("gcode/script", {{"script", script}}, std::chrono::milliseconds(500));
    } catch (const std::exception&) {
    }
  }
  nlohmann::json stats() const override {
    return {{"api", "klipper"}, {"trapq_moves", extruder_.size()}, {"load_cell_raw_samples", load_raw_}};
  }

 private:
  // Klipper sends sensor batches every 0.5 s (bulk_sensor.py, BATCH_INTERVAL): wait a little longer.
  static constexpr std::chrono::milliseconds kBatchWait{600};

  void on_message(const nlohmann::json& m) {
    if (!m.contains("params")) return;
    const std::string tag = m.value("tunekit", "");
    const auto& p = m["params"];
    if (tag == "accel" && accel_on_) {
      for (const auto& s : machine::parse_accel_rows(p)) rec_.accel(s.time_s, s.x, s.y, s.z);
    } else if (tag == "load_cell" && load_on_) {
      // Kept as received (nothing is lost if the run fails before the feed is known).
      auto& raw = j_.csv("load_cell_raw.csv", "time (s),force (N)");
      for (const auto& s : machine::parse_load_cell_rows(p, sensors_.load_cell_name)) {
        raw.row(fmt::format("{:.6f},{:.5f}", s.time_s, s.force_N));
        load_.push_back(s);
        ++load_raw_;
      }
    } else if (tag == "trapq_extruder") {
      extruder_.add(p);
    } else if (tag == "trapq_toolhead" && accel_on_) {
      toolhead_.add(p);
    }
  }
  // Each toolhead move of the recording as a piece of commanded motion: Klipper's trapq entries
  // hold their acceleration constant along their direction.
  void write_toolhead_motion() {
    for (const auto& m : toolhead_.moves()) {
      const double v[6] = {
          m.print_time_s, m.duration_s, m.acceleration * m.direction[0], m.acceleration * m.direction[1], 0.0, 0.0};
      rec_.motion(v);
    }
    toolhead_ = {};
  }
  // Each force sample's feed is the mean commanded feed over the sample's share of the time axis
  // (from halfway to the previous sample to halfway to the next), as the filament moved it: a
  // model driven by samples held over their interval then feeds the right length of filament,
  // where the velocity at the sample's instant catches a junction's brief slow-down whole.
  void write_load_cell() {
    for (std::size_t i = 0; i < load_.size(); ++i) {
      const double t = load_[i].time_s;
      const double prev = i > 0 ? load_[i - 1].time_s : (i + 1 < load_.size() ? 2 * t - load_[i + 1].time_s : t);
      const double next = i + 1 < load_.size() ? load_[i + 1].time_s : 2 * t - prev;
      rec_.load_cell(t, extruder_.mean_velocity_x(0.5 * (prev + t), 0.5 * (t + next)), load_[i].force_N);
    }
    load_.clear();
  }
  void flush_script() {
    if (pending_.empty()) return;
    std::string script;
    for (const auto& c : pending_) script += (script.empty() ? "" : "\n") + c;
    pending_.clear();
    client_.call("gcode/script", {{"script", script}}, timeout_);
  }
  machine::KlipperApiClient client_;
  machine::KlipperSettings settings_;
  machine::Journal& j_;
  Recorder& rec_;
  std::chrono::milliseconds timeout_;
  machine::Sensors sensors_;
  SendGuard& guard_;
  std::vector<std::string> pending_;
  std::vector<machine::KlipperLoadCellSample> load_;
  machine::TrapqTimeline extruder_, toolhead_;
  long load_raw_ = 0;
  bool accel_subscribed_ = false, accel_on_ = false, load_subscribed_ = false, load_on_ = false;
};

}  // namespace

std::unique_ptr<Session> make_gcode_session(std::unique_ptr<machine::Transport> t, machine::Journal& j, Recorder& rec,
                                            const machine::LinkOptions& lo, const std::atomic<bool>* abort,
                                            SendGuard& guard, std::string http,
                                            std::optional<std::string> http_password) {
  return std::make_unique<GcodeSession>(std::move(t), j, rec, lo, abort, guard, std::move(http),
                                        std::move(http_password));
}
std::unique_ptr<Session> make_klipper_session(std::unique_ptr<machine::Transport> t, machine::Journal& j, Recorder& rec,
                                              const machine::LinkOptions& lo, const machine::Sensors& sensors,
                                              SendGuard& guard) {
  return std::make_unique<KlipperSession>(std::move(t), j, rec, lo, sensors, guard);
}

}  // namespace tunekit::protocols::detail
