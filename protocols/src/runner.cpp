#include "tunekit/protocols/runner.hpp"
#include "tunekit/machine/rrf_http.hpp"
#include "tunekit/ident/rrf_accelerometer.hpp"

#include <algorithm>
#include <ctime>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/journal.hpp"
#include "tunekit/machine/klipper_api.hpp"
#include "tunekit/machine/klipper_sensors.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/protocols/stop_signals.hpp"
#include "tunekit/sim/sim_camera.hpp"
#include "tunekit/machine/serial_transport.hpp"
#include "tunekit/sim/simulator.hpp"

namespace tunekit::protocols {
namespace {

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d_%H%M%S", &tm);
  return buf;
}

/// Parses whitespace-separated numbers after a prefix; returns how many were read.
int parse_numbers(std::string_view s, double* out, int max) {
  std::string tmp(s);
  const char* p = tmp.c_str();
  int n = 0;
  while (n < max) {
    char* end = nullptr;
    const double v = std::strtod(p, &end);
    if (end == p) break;
    out[n++] = v;
    p = end;
  }
  return n;
}

/// Sensor samples -> CSV files of the run directory.
class Recorder {
 public:
  Recorder(machine::Journal& j, std::string load_cell_file, std::string accel_file, std::string commanded_file)
      : j_(j),
        load_file_(std::move(load_cell_file)),
        accel_file_(std::move(accel_file)),
        cmd_file_(std::move(commanded_file)) {}

  void load_cell(double t, double feed, double force) {
    auto& c = j_.csv(load_file_, "time (s),feed (mm/s),force (N)");
    c.row(fmt::format("{:.6f},{:.5f},{:.5f}", t, feed, force));
    ++load_;
  }
  void accel(double t, double ax, double ay, double az) {
    auto& c = j_.csv(accel_file_, "#time,accel_x,accel_y,accel_z");
    c.row(fmt::format("{:.6f},{:.2f},{:.2f},{:.2f}", t, ax, ay, az));
    ++accel_;
  }
  void commanded(double t, double cx, double cy) {
    auto& c = j_.csv(cmd_file_, "time (s),accel_x (mm/s^2),accel_y (mm/s^2)");
    c.row(fmt::format("{:.6f},{:.2f},{:.2f}", t, cx, cy));
  }
  /// Handles a tunekit-sim data line; true if it was one.
  bool line(std::string_view l) {
    double v[6];
    if (l.rfind("echo:TKA ", 0) == 0) {
      const int n = parse_numbers(l.substr(9), v, 6);
      if (n >= 4) accel(v[0], v[1], v[2], v[3]);
      if (n == 6) commanded(v[0], v[4], v[5]);
      return true;
    }
    if (l.rfind("echo:TKL ", 0) == 0) {
      if (parse_numbers(l.substr(9), v, 3) == 3) load_cell(v[0], v[1], v[2]);
      return true;
    }
    return false;
  }
  long load_samples() const { return load_; }
  long accel_samples() const { return accel_; }
  const std::string& load_file() const { return load_file_; }
  const std::string& accel_file() const { return accel_file_; }
  const std::string& commanded_file() const { return cmd_file_; }

 private:
  machine::Journal& j_;
  std::string load_file_, accel_file_, cmd_file_;
  long load_ = 0, accel_ = 0;
};

class Session {
 public:
  virtual ~Session() = default;
  virtual firmware::FirmwareInfo identify() = 0;
  virtual void send(const std::string& line) = 0;
  /// `window_s`: how long the recording is expected to last (RepRapFirmware's M956 takes a
  /// sample count, not a stop command).
  virtual void record(const std::string& sensor, bool on, double window_s) = 0;
  /// Whether this link can record `sensor` (checked before anything is sent: no heating or
  /// homing for a protocol whose data cannot be recorded).
  virtual bool can_record(const std::string& sensor) const = 0;
  virtual void finish() = 0;
  virtual void safe_state(const std::vector<std::string>& commands) = 0;
  virtual nlohmann::json stats() const = 0;
  firmware::Dialect dialect;
  firmware::FirmwareInfo firmware;
};

class GcodeSession : public Session {
 public:
  GcodeSession(std::unique_ptr<machine::Transport> t, machine::Journal& j, Recorder& rec,
               const machine::LinkOptions& lo, const std::atomic<bool>* abort, SendGuard& guard, std::string http)
      : t_(std::move(t)), link_(*t_, &j, lo), j_(j), rec_(rec), http_(std::move(http)) {
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
    if (f.firmware == firmware::Firmware::marlin) {
      const auto ft = firmware::parse_m493_report(link_.send("M493"));
      f.ft_motion = ft.present;
      f.ft_motion_active = ft.active;
    }
    return f;
  }
  void send(const std::string& line) override { link_.send(line); }
  void record(const std::string& sensor, bool on, double window_s) override {
    if (!firmware.sensor_stream() && rrf_file_accelerometer(sensor)) {
      if (on) start_m956(window_s);
      else fetch_m956();
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
    return firmware.sensor_stream() || rrf_file_accelerometer(sensor);
  }
  void finish() override {}
  void safe_state(const std::vector<std::string>& commands) override {
    link_.send_best_effort(commands, std::chrono::milliseconds(300));
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
    const std::string name = "0:/sys/accelerometer/" + m956_name_;
    std::string bytes;
    // The run ends after its sample count, in the board's time: poll, waiting G4 P250 between
    // reads (on a real board 250 ms; the simulator's clock runs with the dwell).
    const int polls = static_cast<int>(std::ceil(m956_window_s_ / 0.25)) + 40;
    for (int i = 0;; ++i) {
      bytes = machine::rrf_download(addr, name, std::chrono::milliseconds(5000));
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
  std::string m956_name_;
  double m956_rate_hz_ = 0, m956_window_s_ = 0;
  std::vector<std::string> m956_files_;
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
    const auto r = client_.call("info", {{"client_info", {{"name", "tunekit"}}}}, timeout_);
    firmware::FirmwareInfo f;
    f.firmware = firmware::Firmware::klipper;
    f.name = "Klipper";
    f.version = r.value("software_version", "");
    return f;
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
        const auto ep =
            machine::klipper_accelerometer_endpoint(sensors_.accelerometer_chip, sensors_.accelerometer_name);
        client_.call(ep.method, ep.params({{"tunekit", "accel"}}), timeout_);
        accel_subscribed_ = true;
      }
      if (!on) client_.pump(kBatchWait);  // the last batch of samples
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
    }
  }
  void write_load_cell() {
    for (const auto& s : load_) rec_.load_cell(s.time_s, extruder_.velocity_x_at(s.time_s), s.force_N);
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
  machine::Journal& j_;
  Recorder& rec_;
  std::chrono::milliseconds timeout_;
  machine::Sensors sensors_;
  SendGuard& guard_;
  std::vector<std::string> pending_;
  std::vector<machine::KlipperLoadCellSample> load_;
  machine::TrapqTimeline extruder_;
  long load_raw_ = 0;
  bool accel_subscribed_ = false, accel_on_ = false, load_subscribed_ = false, load_on_ = false;
};

std::string unique_dir(const std::string& base) {
  std::string d = base;
  for (int i = 2; std::filesystem::exists(d); ++i) d = fmt::format("{}-{}", base, i);
  return d;
}

/// The protocol's lines after ";@epilogue": what restores the machine's own settings.
std::vector<std::string> epilogue_lines(const std::vector<std::string>& gcode) {
  std::vector<std::string> out;
  bool in = false;
  for (const auto& l : gcode) {
    if (l == ";@epilogue") in = true;
    else if (in && !l.empty() && l[0] != ';') out.push_back(l.substr(0, l.find(';')));
  }
  return out;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

}  // namespace

RunResult run_experiment(const RunOptions& o) {
  const bool sim = o.machine == "sim";
  const machine::MachineProfile profile = sim ? builtin_sim_profile() : machine::load_machine_profile(o.machine);
  const sim::SimConfig sim_cfg = sim::SimConfig::from_options(o.sim_options);  // bad options fail before anything else
  if (!sim && o.port.empty()) throw InputError("--port is needed with a machine profile (or use --machine sim)");
  // The simulator follows the firmware named by its "firmware=" option (Marlin by default).
  const std::string fw_name = sim ? sim_cfg.firmware : profile.firmware;
  const firmware::Dialect dialect(fw_name.empty() ? firmware::Firmware::marlin : firmware::firmware_from_name(fw_name));

  RunResult res;
  res.experiment = build_experiment(o.protocol, o.params, o.axis, profile, dialect, o.limits);
  res.gcode = res.experiment.gcode;
  // The gate: nothing is opened or sent when the protocol exceeds the profile or the caps.
  require_within_limits(res.gcode, profile, res.experiment.sensors, o.limits);
  if (o.dry_run) {
    res.status = "dry-run";
    return res;
  }

  // SIGINT, SIGTERM and SIGHUP stop the run safely from here on (stop_signals.hpp).
  const StopSignals stop_signals;
  const std::atomic<bool>* abort_flag = o.abort_flag ? o.abort_flag : &StopSignals::flag();
  const std::string stamp = utc_stamp();
  res.run_dir = o.run_dir.empty() ? unique_dir(fmt::format("{}/{}-{}", o.runs_root, o.protocol, stamp)) : o.run_dir;
  machine::Journal journal(res.run_dir);
  const std::string axis_tag = res.experiment.axis.empty() ? "xy" : res.experiment.axis;
  const std::string tag = o.file_tag.empty() ? stamp : o.file_tag;
  Recorder rec(
      journal, o.protocol == "liquefier-step" || o.protocol == "liquefier-flow-sweep" ? "step.csv" : "feed_force.csv",
      fmt::format("raw_data_{}_{}.csv", axis_tag, tag), fmt::format("commanded_accel_{}_{}.csv", axis_tag, tag));
  core::write_file_atomic(journal.path("protocol.gcode"), join_lines(res.gcode));
  res.files["journal"] = journal.path("journal.jsonl");
  res.files["gcode"] = journal.path("protocol.gcode");
  res.files["summary"] = journal.path("run.json");

  nlohmann::json summary{{"protocol", o.protocol},
                         {"experiment", res.experiment.to_json()},
                         {"machine", sim ? "sim" : o.machine},
                         {"profile", profile.name},
                         {"started_utc", stamp}};
  std::unique_ptr<sim::SimPtyServer> server;
  std::string port = o.port;
  if (sim) {
    core::write_file_atomic(journal.path("truth.json"), sim_cfg.truth().dump(2) + "\n");
    res.files["truth"] = journal.path("truth.json");
    if (port.empty()) {
      std::function<void(sim::Simulator&)> setup;
      if (o.sim_bed)
        setup = [bed = o.sim_bed](sim::Simulator& s) {
          s.deposit_sink = [bed](double t, const std::array<double, 4>& pos, double v, double q) {
            bed->deposit(t, pos, v, q);
          };
        };
      server = std::make_unique<sim::SimPtyServer>(sim_cfg, setup);
      port = server->path();
    }
  }
  summary["port"] = port;
  journal.event("start", {{"protocol", o.protocol}, {"port", port}, {"params", res.experiment.params}});
  auto progress = [&](const std::string& m) {
    if (o.progress) o.progress(m);
  };

  auto finish_sim = [&] {
    if (!server) return;
    server->stop();
    server->wait();
    const auto received = server->sim().received();
    core::write_file_atomic(journal.path("sim_received.gcode"), join_lines(received));
    core::write_file_atomic(journal.path("sim_stats.json"),
                            nlohmann::json{{"lines_received", received.size()},
                                           {"accel_samples_sent", server->sim().accel_samples_sent()},
                                           {"load_cell_samples_sent", server->sim().load_cell_samples_sent()},
                                           {"disconnected", server->disconnected()},
                                           {"halted", server->sim().halted()},
                                           {"machine_time_s", server->sim().time_s()}}
                                    .dump(2) +
                                "\n");
    res.files["sim_received"] = journal.path("sim_received.gcode");
  };
  auto list_files = [&] {
    if (journal.has_csv(rec.load_file())) res.files["load_cell"] = journal.path(rec.load_file());
    if (journal.has_csv(rec.accel_file())) res.files["accel"] = journal.path(rec.accel_file());
    if (journal.has_csv(rec.commanded_file())) res.files["commanded_accel"] = journal.path(rec.commanded_file());
  };

  SendGuard guard(profile);  // the last check of every line, in the link
  std::unique_ptr<Session> session;
  try {
    progress(fmt::format("connecting to {}", port));
    const bool api = port.rfind("unix:", 0) == 0;
    auto transport = machine::open_transport(port, o.baud);
    if (api)
      session = std::make_unique<KlipperSession>(std::move(transport), journal, rec, o.link, profile.sensors, guard);
    else
      session = std::make_unique<GcodeSession>(std::move(transport), journal, rec, o.link, abort_flag, guard,
                                               server ? server->http_url() : profile.http_address);
    session->firmware = session->identify();
    session->dialect = firmware::Dialect(
        session->firmware.firmware == firmware::Firmware::unknown ? dialect.firmware() : session->firmware.firmware);
    journal.event("firmware", {{"name", session->firmware.name},
                               {"version", session->firmware.version},
                               {"dialect", to_string(session->dialect.firmware())},
                               {"ft_motion", session->firmware.ft_motion},
                               {"ft_motion_active", session->firmware.ft_motion_active}});
    summary["firmware"] = {{"name", session->firmware.name}, {"version", session->firmware.version}};
    if (session->firmware.ft_motion) {
      res.ft_motion = session->firmware.ft_motion_active ? "active" : "built, inactive";
      summary["firmware"]["ft_motion"] = res.ft_motion;
    }
    // Fail before heating and homing when the link cannot record what the protocol needs.
    for (const auto& sensor : res.experiment.sensors)
      if (!session->can_record(sensor)) {
        const bool rrf = session->firmware.firmware == firmware::Firmware::reprapfirmware && sensor == "accelerometer";
        throw MachineError(
            fmt::format(
                "the firmware ({}) cannot record {} data over this link ({}); nothing but M115 was sent",
                session->firmware.name.empty() ? "unidentified" : session->firmware.name, sensor,
                rrf ? "RepRapFirmware records its accelerometer with M956 into 0:/sys/accelerometer/ and offers "
                      "no way to read a file over USB serial (M28/M29 write, M20 lists, M36/M38 describe a "
                      "file); give the profile its web server, [network] http = \"http://HOST\", to fetch it "
                      "with rr_download"
                    : "no tunekit sensor stream"),
            port);
      }
    progress(fmt::format("firmware: {} {}; running {} ({} lines, ~{:.0f} s of machine time)", session->firmware.name,
                         session->firmware.version, o.protocol, res.gcode.size(), res.experiment.estimated_duration_s));
    for (const auto& line : res.gcode) {
      if (abort_flag->load()) throw MachineError("interrupted", port);
      if (line.rfind(";@record ", 0) == 0) {
        const auto rest = line.substr(9);
        const auto sp = rest.find(' ');
        const std::string sensor = rest.substr(0, sp);
        const bool on = rest.substr(sp + 1) == "on";
        double window_s = 0;
        if (on) {
          // The planned machine time up to this sensor's "off" directive.
          const auto here = res.gcode.begin() + (&line - res.gcode.data());
          const auto off = std::find(here, res.gcode.end(), ";@record " + sensor + " off");
          window_s = estimate_gcode_duration_s(std::vector<std::string>(here, off));
        }
        session->record(sensor, on, window_s);
        continue;
      }
      if (line.empty() || line[0] == ';') continue;
      std::string cmd = line.substr(0, line.find(';'));
      while (!cmd.empty() && cmd.back() == ' ') cmd.pop_back();
      session->send(cmd);
    }
    session->finish();
  } catch (const MachineError& e) {
    const bool interrupted = abort_flag->load();
    const std::string signal = StopSignals::received();
    const MachineError why =
        interrupted && !signal.empty() ? MachineError("interrupted by " + signal, e.location()) : e;
    journal.error(why.formatted());
    const auto safe = (session ? session->dialect : dialect).safe_state(profile.temperature.heaters_off_on_abort);
    if (session) {
      journal.event("safe state", {{"commands", safe}});
      session->safe_state(safe);
      // Restore what the protocol changed for its test (after the stop). After an emergency
      // stop (M112) the firmware must be restarted, which reloads its configuration anyway.
      const auto restore = epilogue_lines(res.gcode);
      if (!restore.empty() && std::find(safe.begin(), safe.end(), "M112") == safe.end()) {
        journal.event("restore", {{"commands", restore}});
        session->safe_state(restore);
      }
    }
    journal.sync();
    summary["status"] = interrupted ? "interrupted" : "failed";
    summary["error"] = why.formatted();
    summary["samples"] = {{"load_cell", rec.load_samples()}, {"accel", rec.accel_samples()}};
    if (session) summary["link"] = session->stats();
    session.reset();
    finish_sim();
    list_files();
    summary["files"] = res.files;
    core::write_file_atomic(journal.path("run.json"), summary.dump(2) + "\n");
    throw MachineError(fmt::format("{} (the partial run is kept in {})", why.message(), res.run_dir), why.location());
  }
  journal.event("end", {{"load_cell_samples", rec.load_samples()}, {"accel_samples", rec.accel_samples()}});
  journal.sync();
  summary["status"] = "complete";
  summary["samples"] = {{"load_cell", rec.load_samples()}, {"accel", rec.accel_samples()}};
  summary["link"] = session->stats();
  session.reset();
  finish_sim();
  list_files();
  summary["files"] = res.files;
  core::write_file_atomic(journal.path("run.json"), summary.dump(2) + "\n");
  res.status = "complete";
  res.summary = summary;
  return res;
}

}  // namespace tunekit::protocols
