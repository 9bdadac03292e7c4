#pragma once
// A fake Klipper API server for the tests: a Unix socket speaking JSON objects terminated by
// 0x03, backed by tunekit's simulated printer. Its message shapes are taken from Klipper's own
// source and documentation (Klipper v0.13, klippy/webhooks.py, klippy/extras/bulk_sensor.py,
// adxl345.py, lis2dw.py, lis3dh.py, mpu9250.py, icm20948.py, bmi160.py, load_cell.py,
// motion_report.py and docs/API_Server.md), not from tunekit's client:
//
// - Requests {"id", "method", "params"}; answers {"id", "result"} or {"id", "error": {"error":
//   "WebRequestError", "message"}} (webhooks.py). A mux endpoint selects its object by one
//   params key; an unknown value answers "The value '%s' is not valid for %s" (_handle_mux).
// - Accelerometer sections register "<module>/dump_<module>" with mux key "sensor" and the
//   section's last word as value (adxl345.py:228-231, lis2dw.py:91-94, mpu9250.py:82-85,
//   icm20948.py:83-86, bmi160.py:83); [lis3dh ...] is served by lis2dw.py's class
//   (lis3dh.py: lis2dw.LIS2DW(config, LIS3DH_TYPE)), so its endpoint is lis2dw/dump_lis2dw.
//   The subscription answers {"header": ["time", "x_acceleration", "y_acceleration",
//   "z_acceleration"]}; batches are the response_template with "params": {"data": [[time, x,
//   y, z], ...], "errors", "overflows"} (adxl345.py _process_batch, BatchWebhooksClient), time
//   and values rounded to 6 decimals (_convert_samples).
// - load_cell/dump_force registers mux key "load_cell" (load_cell.py:394; the API document's
//   example shows "sensor", but webhooks dispatches on the registered key) and answers {"header":
//   ["time", "force (g)", "counts", "tare_counts"]}; rows [time, grams, counts, tare_counts]
//   with grams = (counts - tare_counts) / counts_per_gram (counts_to_grams), or null while
//   not calibrated; params {"data", "errors", "overflows"} (load_cell.py:422).
// - motion_report/dump_trapq, mux key "name" ("toolhead", "extruder"), answers {"header":
//   ["time", "duration", "start_velocity", "acceleration", "start_position", "direction"]};
//   batches carry params {"data": [[print_time, move_t, start_v, accel, [x, y, z], [dx, dy,
//   dz]], ...]} (motion_report.py DumpTrapQ._process_batch). An extruder's entries carry the
//   filament position in x, direction (1, pressure-advance flag, 0) and a signed velocity
//   (kinematics/extruder.py process_move).
// - Times are print time: the fake adds a print-time origin to the simulator's clock.
// - `info` answers as webhooks.py _handle_info_request (v0.13.0-730): state, state_message,
//   hostname, klipper_path, python_path, process_id, user_id, group_id and the start arguments
//   log_file, config_file, software_version, cpu_info.
// - `objects/query` {"objects": {name: [fields] or null}} answers {"eventtime", "status": {name:
//   {...}}} (webhooks.py QueryStatusHelper; an object without status answers {}): configfile's
//   "settings" (every option a module read, defaults included, lower-case section names),
//   toolhead (toolhead.py get_status: max_velocity, max_accel, minimum_cruise_ratio,
//   square_corner_velocity, live) and extruder (extruder.py: pressure_advance, smooth_time).
// - `gcode/script` runs each line; a command no module registered is not run: Klipper answers
//   it with the G-code response 'Unknown command:"M201"' (gcode.py cmd_default, respond_info) and
//   the script goes on, so the request still succeeds. The commands known are those the
//   modules of a printer with this fake's sections register (gcode.py, toolhead.py,
//   gcode_move.py, homing.py, kinematics/extruder.py, heaters.py, heater_bed.py, fan.py,
//   stepper_enable.py, idle_timeout.py, input_shaper.py, resonance_tester.py, adxl345.py,
//   load_cell.py).
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "tunekit/sim/simulator.hpp"
#include "tunekit/machine/transport.hpp"

namespace tunekit::test {

struct FakeKlipperConfig {
  /// Config sections of accelerometers, as in printer.cfg ("adxl345", "lis2dw toolhead").
  std::vector<std::string> accelerometers{"adxl345"};
  /// The load cell's section ("load_cell", "load_cell probe"); empty: none.
  std::string load_cell;
  double counts_per_gram = 412.7;  ///< [load_cell] counts_per_gram
  long tare_counts = 183452;       ///< what LOAD_CELL_TARE stored
  bool load_cell_calibrated = true;
  double print_time_origin_s = 3292.4;  ///< print time when the simulator's clock reads 0
  // The configuration in force ([printer], [extruder], [input_shaper]); the extrude-only limits
  // and minimum_cruise_ratio are the simulator's (SimConfig), so both agree.
  double max_velocity = 300;                    ///< [printer] max_velocity, mm/s
  double max_accel = 3000;                      ///< [printer] max_accel, mm/s^2
  double square_corner_velocity = 5;            ///< [printer] square_corner_velocity, mm/s
  double max_extrude_only_velocity = 50;        ///< [extruder] max_extrude_only_velocity, mm/s
  double pressure_advance = 0.04;               ///< [extruder] pressure_advance, s
  double smooth_time = 0.04;                    ///< [extruder] pressure_advance_smooth_time, s
  double shaper_freq_x = 0, shaper_freq_y = 0;  ///< [input_shaper]; 0: no section
  std::string shaper_type = "mzv";
  /// [input_shaper] shaper_type_x/_y as written in printer.cfg, e.g. a parameterized
  /// "mzv(n=4,t=0.9)" (klippy/extras/shaper_defs.py, Klipper 2026); empty: not set.
  std::string shaper_type_x, shaper_type_y;
  std::string state = "ready";  ///< what info reports
};

class FakeKlipper {
 public:
  FakeKlipper(const std::string& path, tunekit::sim::SimConfig config, FakeKlipperConfig fake = {})
      : path_(path), sim_(klipper_rules(std::move(config))), fake_(std::move(fake)) {
    // Endpoints as Klipper registers them at start-up, from the config sections.
    for (const auto& section : fake_.accelerometers) {
      std::string module = section.substr(0, section.find(' '));
      if (module == "lis3dh") module = "lis2dw";
      endpoints_[module + "/dump_" + module].first = "sensor";
      endpoints_[module + "/dump_" + module].second.insert(last_word(section));
    }
    if (!fake_.load_cell.empty()) {
      endpoints_["load_cell/dump_force"].first = "load_cell";
      endpoints_["load_cell/dump_force"].second.insert(last_word(fake_.load_cell));
    }
    endpoints_["motion_report/dump_trapq"] = {"name", {"toolhead", "extruder"}};

    ::unlink(path.c_str());
    listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
    REQUIRE(::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
    REQUIRE(::listen(listen_fd_, 1) == 0);
    thread_ = std::thread([this] { serve(); });
  }
  ~FakeKlipper() {
    stop_ = true;
    ::shutdown(listen_fd_, SHUT_RDWR);
    ::close(listen_fd_);
    thread_.join();
    ::unlink(path_.c_str());
  }
  FakeKlipper(const FakeKlipper&) = delete;
  FakeKlipper& operator=(const FakeKlipper&) = delete;

  std::vector<std::string> scripts() {
    std::lock_guard<std::mutex> l(mu_);
    return scripts_;
  }
  /// Every request's method and params, in order.
  std::vector<nlohmann::json> requests() {
    std::lock_guard<std::mutex> l(mu_);
    return requests_;
  }
  long samples_sent() const { return sent_; }
  /// Commands Klipper would have answered 'Unknown command:"..."' (not run), in order.
  std::vector<std::string> unknown_commands() {
    std::lock_guard<std::mutex> l(mu_);
    return unknown_;
  }
  /// The parameters of the last SET_INPUT_SHAPER, split as Klipper splits an extended command
  /// (shell words, each at its first '='; names upper-cased), e.g. {"SHAPER_TYPE_X": "mzv(n=4,t=0.9)"}.
  std::map<std::string, std::string> last_input_shaper() {
    std::lock_guard<std::mutex> l(mu_);
    return input_shaper_;
  }
  /// The simulator's clock (s) when the last script finished.
  double machine_time_s() const { return machine_time_; }
  long load_cell_samples_sent() const { return load_sent_; }

 private:
  static std::string last_word(const std::string& s) {
    const auto sp = s.find_last_of(' ');
    return sp == std::string::npos ? s : s.substr(sp + 1);
  }
  static double round6(double v) { return std::round(v * 1e6) / 1e6; }
  /// Shell words of `args`: whitespace separates, double quotes group ('\\' escapes '"' and
  /// '\\' inside them), single quotes group literally.
  static std::vector<std::string> shell_words(const std::string& args) {
    std::vector<std::string> words;
    std::string w;
    bool in_word = false;
    char quote = 0;
    for (std::size_t i = 0; i < args.size(); ++i) {
      const char c = args[i];
      if (quote == '"' && c == '\\' && i + 1 < args.size() && (args[i + 1] == '"' || args[i + 1] == '\\')) {
        w += args[++i];
      } else if (quote && c == quote) {
        quote = 0;
      } else if (quote) {
        w += c;
      } else if (c == '"' || c == '\'') {
        quote = c;
        in_word = true;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        if (in_word) words.push_back(w);
        w.clear();
        in_word = false;
      } else {
        w += c;
        in_word = true;
      }
    }
    if (in_word) words.push_back(w);
    return words;
  }
  void remember_input_shaper(const std::string& line) {
    const auto sp = line.find_first_of(" \t");
    std::map<std::string, std::string> params;
    for (const auto& word : shell_words(sp == std::string::npos ? std::string() : line.substr(sp + 1))) {
      const auto eq = word.find('=');
      std::string key = word.substr(0, eq);
      for (auto& c : key) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      params[key] = eq == std::string::npos ? std::string() : word.substr(eq + 1);
    }
    std::lock_guard<std::mutex> l(mu_);
    input_shaper_ = params;
  }
  // A Klipper peer plans moves as Klipper does: the simulator follows Klipper's planner rules.
  static tunekit::sim::SimConfig klipper_rules(tunekit::sim::SimConfig c) {
    c.firmware = "klipper";
    return c;
  }

  // Commands registered by the modules of the fake's printer (see the header comment).
  bool known_command(const std::string& cmd) const {
    static const std::set<std::string> base{"M110",
                                            "M112",
                                            "M115",
                                            "RESTART",
                                            "FIRMWARE_RESTART",
                                            "ECHO",
                                            "STATUS",
                                            "HELP",  // gcode.py
                                            "G4",
                                            "M400",
                                            "SET_VELOCITY_LIMIT",
                                            "M204",  // toolhead.py
                                            "G0",
                                            "G1",
                                            "G20",
                                            "G21",
                                            "M82",
                                            "M83",
                                            "G90",
                                            "G91",
                                            "G92",
                                            "M220",
                                            "M221",
                                            "M114",
                                            "GET_POSITION",
                                            "SET_GCODE_OFFSET",
                                            "SAVE_GCODE_STATE",
                                            "RESTORE_GCODE_STATE",  // gcode_move.py
                                            "G28",                  // homing.py
                                            "M104",
                                            "M109",
                                            "SET_PRESSURE_ADVANCE",
                                            "SET_EXTRUDER_ROTATION_DISTANCE",
                                            "SYNC_EXTRUDER_MOTION",
                                            "ACTIVATE_EXTRUDER",  // kinematics/extruder.py
                                            "SET_HEATER_TEMPERATURE",
                                            "TURN_OFF_HEATERS",
                                            "M105",
                                            "TEMPERATURE_WAIT",  // heaters.py
                                            "M140",
                                            "M190",
                                            "M106",
                                            "M107",
                                            "M18",
                                            "M84",
                                            "SET_STEPPER_ENABLE",
                                            "SET_IDLE_TIMEOUT",
                                            "SET_INPUT_SHAPER",
                                            "MEASURE_AXES_NOISE",
                                            "TEST_RESONANCES",
                                            "SHAPER_CALIBRATE",
                                            "ACCELEROMETER_MEASURE",
                                            "ACCELEROMETER_QUERY"};
    if (base.count(cmd) != 0) return true;
    return !fake_.load_cell.empty() && (cmd == "LOAD_CELL_TARE" || cmd == "LOAD_CELL_CALIBRATE" ||
                                        cmd == "LOAD_CELL_READ" || cmd == "LOAD_CELL_DIAGNOSTIC");
  }
  // The command word as gcode.py reads it: the first word, upper case (an extended command's
  // name ends at the first space or '=').
  static std::string command_word(const std::string& line) {
    std::string l = line.substr(0, line.find(';'));
    const auto b = l.find_first_not_of(" \t");
    if (b == std::string::npos) return "";
    l = l.substr(b);
    std::string w = l.substr(0, l.find_first_of(" \t"));
    for (auto& c : w) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return w;
  }
  nlohmann::json status_of(const std::string& name) const {
    const auto& sc = sim_.config();
    if (name == "configfile") {
      nlohmann::json settings{{"printer",
                               {{"kinematics", "cartesian"},
                                {"max_velocity", fake_.max_velocity},
                                {"max_accel", fake_.max_accel},
                                {"minimum_cruise_ratio", sc.minimum_cruise_ratio},
                                {"square_corner_velocity", fake_.square_corner_velocity}}},
                              {"extruder",
                               {{"max_extrude_only_velocity", fake_.max_extrude_only_velocity},
                                {"max_extrude_only_accel", sc.max_extrude_only_accel_mm_s2},
                                {"max_extrude_only_distance", sc.max_extrude_only_distance_mm},
                                {"pressure_advance", fake_.pressure_advance},
                                {"pressure_advance_smooth_time", fake_.smooth_time}}}};
      if (fake_.shaper_freq_x > 0 || fake_.shaper_freq_y > 0)
        settings["input_shaper"] = {{"shaper_type", fake_.shaper_type},
                                    {"shaper_freq_x", fake_.shaper_freq_x},
                                    {"shaper_freq_y", fake_.shaper_freq_y},
                                    {"damping_ratio_x", 0.1},
                                    {"damping_ratio_y", 0.1}};
      if (!fake_.shaper_type_x.empty()) settings["input_shaper"]["shaper_type_x"] = fake_.shaper_type_x;
      if (!fake_.shaper_type_y.empty()) settings["input_shaper"]["shaper_type_y"] = fake_.shaper_type_y;
      return {{"settings", settings}};
    }
    if (name == "toolhead")
      return {{"max_velocity", fake_.max_velocity},
              {"max_accel", fake_.max_accel},
              {"minimum_cruise_ratio", sc.minimum_cruise_ratio},
              {"square_corner_velocity", fake_.square_corner_velocity}};
    if (name == "extruder") return {{"pressure_advance", fake_.pressure_advance}, {"smooth_time", fake_.smooth_time}};
    return nlohmann::json::object();
  }

  // One executed move -> trapq entries: the profile cut into 1 ms pieces of constant
  // acceleration, pieces of equal acceleration merged (cruise and constant-acceleration phases
  // become one entry each, as Klipper's accel/cruise/decel entries).
  void add_trapq(double t0, double duration, const tunekit::machine::Profile& prof, const std::array<double, 4>& start,
                 const std::array<double, 4>& u) {
    const double piece = 1e-3;
    const bool xy = u[0] != 0 || u[1] != 0;
    const double e_ratio = u[3];
    double xyz_norm = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    nlohmann::json* last_e = nullptr;
    nlohmann::json* last_t = nullptr;
    for (double a = 0; a < duration - 1e-12; a += piece) {
      const double b = std::min(duration, a + piece);
      const auto sa = prof.at(a), sb = prof.at(b);
      const double acc = (sb.vel_mm_s - sa.vel_mm_s) / (b - a);
      const double pt = fake_.print_time_origin_s + t0 + a;
      auto extend = [&](nlohmann::json* last, double v_scale) {
        if (last == nullptr) return false;
        const double last_acc = (*last)[3].get<double>();
        if (std::abs(last_acc - acc * v_scale) > 1e-6 * (1 + std::abs(acc * v_scale))) return false;
        (*last)[1] = (*last)[1].get<double>() + (b - a);
        return true;
      };
      if (e_ratio != 0 && !extend(last_e, e_ratio)) {
        trapq_["extruder"].push_back({pt,
                                      b - a,
                                      sa.vel_mm_s * e_ratio,
                                      acc * e_ratio,
                                      {start[3] + e_ratio * sa.pos_mm, 0.0, 0.0},
                                      {1.0, xy ? 1.0 : 0.0, 0.0}});
        last_e = &trapq_["extruder"].back();
      }
      if (xyz_norm > 0 && !extend(last_t, xyz_norm)) {
        trapq_["toolhead"].push_back(
            {pt,
             b - a,
             sa.vel_mm_s * xyz_norm,
             acc * xyz_norm,
             {start[0] + u[0] * sa.pos_mm, start[1] + u[1] * sa.pos_mm, start[2] + u[2] * sa.pos_mm},
             {u[0] / xyz_norm, u[1] / xyz_norm, u[2] / xyz_norm}});
        last_t = &trapq_["toolhead"].back();
      }
    }
  }

  void serve() {
    const int fd = ::accept(listen_fd_, nullptr, nullptr);
    if (fd < 0) return;
    tunekit::machine::FdTransport t(fd, "fake klipper");
    tunekit::machine::LineReader reader(t, '\x03');
    nlohmann::json accel_rows = nlohmann::json::array(), load_rows = nlohmann::json::array();
    std::vector<nlohmann::json> accel_templates, load_templates;
    std::map<std::string, std::vector<nlohmann::json>> trapq_templates;
    const double t0 = fake_.print_time_origin_s;
    sim_.accel_sink = [&](double tt, double x, double y, double z) {
      accel_rows.push_back({round6(t0 + tt), round6(x), round6(y), round6(z)});
    };
    sim_.load_cell_sink = [&](double tt, double force_N) {
      const long counts = fake_.tare_counts + std::lround(force_N / 9.80665e-3 * fake_.counts_per_gram);
      nlohmann::json grams = nullptr;
      if (fake_.load_cell_calibrated) grams = static_cast<double>(counts - fake_.tare_counts) / fake_.counts_per_gram;
      load_rows.push_back({t0 + tt, grams, counts, fake_.tare_counts});
    };
    sim_.move_sink = [&](double ts, double d, const tunekit::machine::Profile& p, const std::array<double, 4>& s,
                         const std::array<double, 4>& u) { add_trapq(ts, d, p, s, u); };
    auto send = [&](const nlohmann::json& m) { t.write(m.dump() + "\x03"); };
    // BatchWebhooksClient.handle_batch: a copy of the template with "params" set to the batch.
    auto flush_rows = [&](nlohmann::json& rows, const std::vector<nlohmann::json>& templates, bool sensor) {
      long sent = 0;
      for (std::size_t i = 0; i < rows.size(); i += 200) {
        nlohmann::json chunk = nlohmann::json::array();
        for (std::size_t k = i; k < std::min(rows.size(), i + 200); ++k) chunk.push_back(rows[k]);
        for (const auto& templ : templates) {
          nlohmann::json msg = templ;
          msg["params"] = sensor ? nlohmann::json{{"data", chunk}, {"errors", 0}, {"overflows", 0}}
                                 : nlohmann::json{{"data", chunk}};
          send(msg);
        }
        if (!templates.empty()) sent += static_cast<long>(chunk.size());
      }
      rows = nlohmann::json::array();
      return sent;
    };
    try {
      while (!stop_) {
        auto frame = reader.next(std::chrono::milliseconds(50));
        if (!frame) continue;
        const auto req = nlohmann::json::parse(*frame);
        const auto id = req["id"];
        const std::string method = req["method"];
        const nlohmann::json params = req.value("params", nlohmann::json::object());
        {
          std::lock_guard<std::mutex> l(mu_);
          requests_.push_back({{"method", method}, {"params", params}});
        }
        auto error = [&](const std::string& message) {
          send({{"id", id}, {"error", {{"error", "WebRequestError"}, {"message", message}}}});
        };
        if (method == "info") {
          send({{"id", id},
                {"result",
                 {{"state", fake_.state},
                  {"state_message", fake_.state == "ready" ? "Printer is ready" : "Printer is not ready"},
                  {"hostname", "fake-klipper"},
                  {"klipper_path", "/home/pi/klipper"},
                  {"python_path", "/home/pi/klippy-env/bin/python"},
                  {"process_id", 4242},
                  {"user_id", 1000},
                  {"group_id", 1000},
                  {"log_file", "/tmp/klippy.log"},
                  {"config_file", "/home/pi/printer_data/config/printer.cfg"},
                  {"software_version", "v0.13.0-730-fake"},
                  {"cpu_info", "4 core ARMv7 Processor rev 4 (v7l)"}}}});
          continue;
        }
        if (method == "objects/query") {
          const auto objects = params.value("objects", nlohmann::json::object());
          if (!objects.is_object()) {
            error("Invalid argument");
            continue;
          }
          nlohmann::json status = nlohmann::json::object();
          for (const auto& [name, fields] : objects.items()) {
            const nlohmann::json all = status_of(name);
            if (fields.is_null()) {
              status[name] = all;
              continue;
            }
            status[name] = nlohmann::json::object();
            for (const auto& f : fields)
              if (f.is_string() && all.contains(f.get<std::string>()))
                status[name][f.get<std::string>()] = all[f.get<std::string>()];
          }
          send({{"id", id}, {"result", {{"eventtime", 1234.5}, {"status", status}}}});
          continue;
        }
        if (method == "gcode/script") {
          const std::string script = params.value("script", "");
          {
            std::lock_guard<std::mutex> l(mu_);
            scripts_.push_back(script);
          }
          std::stringstream ss(script);
          std::string line;
          const tunekit::sim::Simulator::Emit ignore = [](std::string_view) {};
          while (std::getline(ss, line)) {
            const std::string cmd = command_word(line);
            if (!cmd.empty() && !known_command(cmd)) {
              std::lock_guard<std::mutex> l(mu_);
              unknown_.push_back(cmd);  // gcode.py: respond_info('Unknown command:"%s"'); not run
              continue;
            }
            if (cmd == "SET_INPUT_SHAPER") remember_input_shaper(line);
            sim_.handle_line(line, ignore);
          }
          // No flush at the end of a script: Klipper keeps the last moves in its lookahead queue
          // until more moves come or a dwell/M400 flushes it (klippy/toolhead.py LookAheadQueue),
          // so moves sent in several scripts join at speed as moves of one script do.
          machine_time_ = sim_.time_s();
          sent_ += flush_rows(accel_rows, accel_templates, true);
          load_sent_ += flush_rows(load_rows, load_templates, true);
          for (auto& [name, rows] : trapq_) flush_rows(rows, trapq_templates[name], false);
          send({{"id", id}, {"result", nlohmann::json::object()}});
          continue;
        }
        const auto ep = endpoints_.find(method);
        if (ep == endpoints_.end()) {
          error("No registered endpoint '" + method + "'");
          continue;
        }
        const auto& [key, values] = ep->second;
        const std::string value =
            params.contains(key) && params[key].is_string() ? params[key].get<std::string>() : "None";
        if (values.count(value) == 0) {
          error("The value '" + value + "' is not valid for " + key);
          continue;
        }
        const nlohmann::json templ = params.value("response_template", nlohmann::json::object());
        if (method == "load_cell/dump_force") {
          load_templates.push_back(templ);
          sim_.set_streaming("load_cell", true);
          send({{"id", id}, {"result", {{"header", {"time", "force (g)", "counts", "tare_counts"}}}}});
        } else if (method == "motion_report/dump_trapq") {
          trapq_templates[value].push_back(templ);
          send({{"id", id},
                {"result",
                 {{"header", {"time", "duration", "start_velocity", "acceleration", "start_position", "direction"}}}}});
        } else {
          accel_templates.push_back(templ);
          sim_.set_streaming("accelerometer", true);
          send({{"id", id}, {"result", {{"header", {"time", "x_acceleration", "y_acceleration", "z_acceleration"}}}}});
        }
      }
    } catch (const std::exception&) {
    }
  }

  std::string path_;
  tunekit::sim::Simulator sim_;
  FakeKlipperConfig fake_;
  std::map<std::string, std::pair<std::string, std::set<std::string>>> endpoints_;  // method -> (key, values)
  std::map<std::string, nlohmann::json> trapq_{{"toolhead", nlohmann::json::array()},
                                               {"extruder", nlohmann::json::array()}};
  int listen_fd_ = -1;
  std::atomic<bool> stop_{false};
  std::atomic<long> sent_{0}, load_sent_{0};
  std::mutex mu_;
  std::vector<std::string> scripts_;
  std::map<std::string, std::string> input_shaper_;
  std::vector<std::string> unknown_;
  std::atomic<double> machine_time_{0};
  std::vector<nlohmann::json> requests_;
  std::thread thread_;
};

}  // namespace tunekit::test
