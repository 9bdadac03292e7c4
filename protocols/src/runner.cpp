#include "tunekit/protocols/runner.hpp"

#include <ctime>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "tunekit/fitting/error.hpp"
#include "tunekit/protocols/atomic_file.hpp"
#include "tunekit/protocols/dialect.hpp"
#include "tunekit/protocols/journal.hpp"
#include "tunekit/protocols/klipper_api.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/protocols/serial_transport.hpp"
#include "tunekit/protocols/simulator.hpp"

namespace tunekit::protocols {
namespace {

// Same content as datasets/machines/sim.toml (tests check that they agree).
constexpr const char* kSimProfile = R"(# Machine profile of tunekit's built-in simulated printer (tunekit-sim).
[machine]
name = "tunekit simulated printer"
kinematics = "cartesian"
firmware = "marlin"

[axes.x]
min_mm = 0
max_mm = 220
max_velocity_mm_s = 300
max_accel_mm_s2 = 10000

[axes.y]
min_mm = 0
max_mm = 220
max_velocity_mm_s = 300
max_accel_mm_s2 = 10000

[axes.z]
min_mm = 0
max_mm = 250
max_velocity_mm_s = 15
max_accel_mm_s2 = 200

[extruder]
filament_diameter_mm = 1.75
nozzle_diameter_mm = 0.4
max_flow_mm3_s = 15
max_velocity_mm_s = 60
max_accel_mm_s2 = 5000

[print]
max_accel_mm_s2 = 3000
line_width_mm = 0.45
layer_height_mm = 0.2
speed_mm_s = 60

[temperature]
hotend_max_c = 280
bed_max_c = 110
heaters_off_on_abort = true

[sensors]
accelerometer = true
accelerometer_rate_hz = 3200
load_cell = true
filament_encoder = false
camera = false
)";

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
  Recorder(Journal& j, std::string load_cell_file, std::string accel_file, std::string commanded_file)
      : j_(j), load_file_(std::move(load_cell_file)), accel_file_(std::move(accel_file)), cmd_file_(std::move(commanded_file)) {}

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
  Journal& j_;
  std::string load_file_, accel_file_, cmd_file_;
  long load_ = 0, accel_ = 0;
};

class Session {
 public:
  virtual ~Session() = default;
  virtual FirmwareInfo identify() = 0;
  virtual void send(const std::string& line) = 0;
  virtual void record(const std::string& sensor, bool on) = 0;
  virtual void finish() = 0;
  virtual void safe_state(const std::vector<std::string>& commands) = 0;
  virtual nlohmann::json stats() const = 0;
  Dialect dialect;
  FirmwareInfo firmware;
};

class GcodeSession : public Session {
 public:
  GcodeSession(std::unique_ptr<Transport> t, Journal& j, Recorder& rec, const LinkOptions& lo, const std::atomic<bool>* abort,
               SendGuard& guard)
      : t_(std::move(t)), link_(*t_, &j, lo) {
    link_.guard = &guard;
    link_.on_line = [&rec](std::string_view l) { return rec.line(l); };
    link_.on_batch = [&j] { j.flush(); };
    link_.abort_flag = abort;
  }
  FirmwareInfo identify() override {
    link_.reset_line_numbers();
    return parse_m115(link_.send("M115"));
  }
  void send(const std::string& line) override { link_.send(line); }
  void record(const std::string& sensor, bool on) override {
    const std::string cmd = dialect.sensor_stream(sensor, on);
    if (cmd.empty() || !firmware.sensor_stream())
      throw MachineError(fmt::format("the firmware ({}) does not stream {} data over this link (it reports no "
                                     "Cap:TUNEKIT_SENSOR_STREAM); use Klipper's API socket (--port unix:PATH) or tunekit-sim",
                                     firmware.name.empty() ? "unidentified" : firmware.name, sensor),
                         t_->describe());
    link_.send(cmd);
  }
  void finish() override {}
  void safe_state(const std::vector<std::string>& commands) override {
    link_.send_best_effort(commands, std::chrono::milliseconds(300));
  }
  nlohmann::json stats() const override {
    const auto& s = link_.stats();
    return {{"lines_sent", s.lines_sent}, {"resends", s.resends}, {"retries", s.retries}, {"busy", s.busy}, {"data_lines", s.data_lines}};
  }

 private:
  std::unique_ptr<Transport> t_;
  GcodeLink link_;
};

class KlipperSession : public Session {
 public:
  KlipperSession(std::unique_ptr<Transport> t, Journal& j, Recorder& rec, const LinkOptions& lo, SendGuard& guard)
      : client_(std::move(t), &j), rec_(rec), timeout_(lo.timeout), guard_(guard) {
    client_.on_message = [this](const nlohmann::json& m) {
      if (!accel_on_ || m.value("tunekit", "") != "accel" || !m.contains("params")) return;
      const auto& p = m["params"];
      if (!p.contains("data")) return;
      for (const auto& row : p["data"])
        if (row.is_array() && row.size() >= 4)
          rec_.accel(row[0].get<double>(), row[1].get<double>(), row[2].get<double>(), row[3].get<double>());
    };
    client_.on_batch = [&j] { j.flush(); };
  }
  FirmwareInfo identify() override {
    const auto r = client_.call("info", {{"client_info", {{"name", "tunekit"}}}}, timeout_);
    FirmwareInfo f;
    f.firmware = Firmware::klipper;
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
  void record(const std::string& sensor, bool on) override {
    flush_script();
    if (sensor != "accelerometer")
      throw MachineError(fmt::format("Klipper's API server streams no {} data", sensor), client_.transport().describe());
    if (on && !subscribed_) {
      client_.call("adxl345/dump_adxl345", {{"sensor", "adxl345"}, {"response_template", {{"tunekit", "accel"}}}}, timeout_);
      subscribed_ = true;
    }
    if (!on) client_.pump(std::chrono::milliseconds(100));  // trailing samples
    accel_on_ = on;
  }
  void finish() override { flush_script(); }
  void safe_state(const std::vector<std::string>& commands) override {
    try {
      std::string script;
      for (const auto& c : commands) script += (script.empty() ? "" : "\n") + c;
      client_.call("gcode/script", {{"script", script}}, std::chrono::milliseconds(500));
    } catch (const std::exception&) {
    }
  }
  nlohmann::json stats() const override { return {{"api", "klipper"}}; }

 private:
  void flush_script() {
    if (pending_.empty()) return;
    std::string script;
    for (const auto& c : pending_) script += (script.empty() ? "" : "\n") + c;
    pending_.clear();
    client_.call("gcode/script", {{"script", script}}, timeout_);
  }
  KlipperApiClient client_;
  Recorder& rec_;
  std::chrono::milliseconds timeout_;
  SendGuard& guard_;
  std::vector<std::string> pending_;
  bool subscribed_ = false, accel_on_ = false;
};

std::string unique_dir(const std::string& base) {
  std::string d = base;
  for (int i = 2; std::filesystem::exists(d); ++i) d = fmt::format("{}-{}", base, i);
  return d;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

}  // namespace

MachineProfile builtin_sim_profile() { return parse_machine_profile(kSimProfile, "<built-in simulated printer profile>"); }

RunResult run_experiment(const RunOptions& o) {
  const bool sim = o.machine == "sim";
  const MachineProfile profile = sim ? builtin_sim_profile() : load_machine_profile(o.machine);
  const SimConfig sim_cfg = SimConfig::from_options(o.sim_options);  // bad options fail before anything else
  if (!sim && o.port.empty()) throw InputError("--port is needed with a machine profile (or use --machine sim)");
  const Dialect dialect(profile.firmware.empty() ? Firmware::marlin : firmware_from_name(profile.firmware));

  RunResult res;
  res.experiment = build_experiment(o.protocol, o.params, o.axis, profile, dialect, o.limits);
  res.gcode = res.experiment.gcode;
  // The gate: nothing is opened or sent when the protocol exceeds the profile or the caps.
  require_within_limits(res.gcode, profile, res.experiment.sensors, o.limits);
  if (o.dry_run) {
    res.status = "dry-run";
    return res;
  }

  const std::string stamp = utc_stamp();
  res.run_dir = o.run_dir.empty() ? unique_dir(fmt::format("{}/{}-{}", o.runs_root, o.protocol, stamp)) : o.run_dir;
  Journal journal(res.run_dir);
  const std::string axis_tag = res.experiment.axis.empty() ? "xy" : res.experiment.axis;
  const std::string tag = o.file_tag.empty() ? stamp : o.file_tag;
  Recorder rec(journal, o.protocol == "liquefier-step" ? "step.csv" : "feed_force.csv",
               fmt::format("raw_data_{}_{}.csv", axis_tag, tag), fmt::format("commanded_accel_{}_{}.csv", axis_tag, tag));
  write_file_atomic(journal.path("protocol.gcode"), join_lines(res.gcode));
  res.files["journal"] = journal.path("journal.jsonl");
  res.files["gcode"] = journal.path("protocol.gcode");
  res.files["summary"] = journal.path("run.json");

  nlohmann::json summary{{"protocol", o.protocol},
                         {"experiment", res.experiment.to_json()},
                         {"machine", sim ? "sim" : o.machine},
                         {"profile", profile.name},
                         {"started_utc", stamp}};
  std::unique_ptr<SimPtyServer> server;
  std::string port = o.port;
  if (sim) {
    write_file_atomic(journal.path("truth.json"), sim_cfg.truth().dump(2) + "\n");
    res.files["truth"] = journal.path("truth.json");
    if (port.empty()) {
      server = std::make_unique<SimPtyServer>(sim_cfg);
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
    write_file_atomic(journal.path("sim_received.gcode"), join_lines(received));
    write_file_atomic(journal.path("sim_stats.json"),
                      nlohmann::json{{"lines_received", received.size()},
                                     {"accel_samples_sent", server->sim().accel_samples_sent()},
                                     {"load_cell_samples_sent", server->sim().load_cell_samples_sent()},
                                     {"disconnected", server->disconnected()},
                                     {"halted", server->sim().halted()},
                                     {"machine_time_s", server->sim().time_s()}}
                              .dump(2) + "\n");
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
    auto transport = open_transport(port, o.baud);
    if (api) session = std::make_unique<KlipperSession>(std::move(transport), journal, rec, o.link, guard);
    else session = std::make_unique<GcodeSession>(std::move(transport), journal, rec, o.link, o.abort_flag, guard);
    session->firmware = session->identify();
    session->dialect = Dialect(session->firmware.firmware == Firmware::unknown ? dialect.firmware() : session->firmware.firmware);
    journal.event("firmware", {{"name", session->firmware.name},
                               {"version", session->firmware.version},
                               {"dialect", to_string(session->dialect.firmware())}});
    summary["firmware"] = {{"name", session->firmware.name}, {"version", session->firmware.version}};
    progress(fmt::format("firmware: {} {}; running {} ({} lines, ~{:.0f} s of machine time)", session->firmware.name,
                         session->firmware.version, o.protocol, res.gcode.size(), res.experiment.estimated_duration_s));
    for (const auto& line : res.gcode) {
      if (o.abort_flag && o.abort_flag->load()) throw MachineError("interrupted", port);
      if (line.rfind(";@record ", 0) == 0) {
        const auto rest = line.substr(9);
        const auto sp = rest.find(' ');
        session->record(rest.substr(0, sp), rest.substr(sp + 1) == "on");
        continue;
      }
      if (line.empty() || line[0] == ';') continue;
      std::string cmd = line.substr(0, line.find(';'));
      while (!cmd.empty() && cmd.back() == ' ') cmd.pop_back();
      session->send(cmd);
    }
    session->finish();
  } catch (const MachineError& e) {
    journal.error(e.formatted());
    const auto safe = (session ? session->dialect : dialect).safe_state(profile.temperature.heaters_off_on_abort);
    if (session) {
      journal.event("safe state", {{"commands", safe}});
      session->safe_state(safe);
    }
    journal.sync();
    summary["status"] = "failed";
    summary["error"] = e.formatted();
    summary["samples"] = {{"load_cell", rec.load_samples()}, {"accel", rec.accel_samples()}};
    if (session) summary["link"] = session->stats();
    session.reset();
    finish_sim();
    list_files();
    summary["files"] = res.files;
    write_file_atomic(journal.path("run.json"), summary.dump(2) + "\n");
    throw MachineError(fmt::format("{} (the partial run is kept in {})", e.message(), res.run_dir), e.location());
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
  write_file_atomic(journal.path("run.json"), summary.dump(2) + "\n");
  res.status = "complete";
  res.summary = summary;
  return res;
}

}  // namespace tunekit::protocols
