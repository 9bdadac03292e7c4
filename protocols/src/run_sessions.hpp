#pragma once
// The runner's machine sessions (internal to the protocols library): what records the sensor
// samples into the run directory (Recorder), and one session per kind of link, G-code over a
// serial line or pseudo-terminal (Marlin, Prusa, RepRapFirmware, tunekit-sim) or Klipper's API
// server, each identifying the firmware before anything else is sent.
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/gcode_link.hpp"
#include "tunekit/machine/journal.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/machine/transport.hpp"

namespace tunekit::protocols {
class SendGuard;
}  // namespace tunekit::protocols

namespace tunekit::protocols::detail {

/// Parses whitespace-separated numbers; returns how many were read.
int parse_numbers(std::string_view s, double* out, int max);

/// Sensor samples -> CSV files of the run directory.
class Recorder {
 public:
  Recorder(machine::Journal& j, std::string load_cell_file, std::string accel_file, std::string commanded_file,
           std::string motion_file)
      : j_(j),
        load_file_(std::move(load_cell_file)),
        accel_file_(std::move(accel_file)),
        cmd_file_(std::move(commanded_file)),
        motion_file_(std::move(motion_file)) {}

  void load_cell(double t, double feed, double force) {
    auto& c = j_.csv(load_file_, "time (s),feed (mm/s),force (N)");
    c.row(csv_row({{t, 6}, {feed, 5}, {force, 5}}));
    ++load_;
  }
  void accel(double t, double ax, double ay, double az) {
    auto& c = j_.csv(accel_file_, "#time,accel_x,accel_y,accel_z");
    c.row(csv_row({{t, 7}, {ax, 2}, {ay, 2}, {az, 2}}));
    ++accel_;
  }
  void commanded(double t, double cx, double cy) {
    auto& c = j_.csv(cmd_file_, "time (s),accel_x (mm/s^2),accel_y (mm/s^2)");
    c.row(csv_row({{t, 7}, {cx, 2}, {cy, 2}}));
  }
  /// One piece of commanded motion: from t0 for `duration`, the acceleration accel + jerk * (t - t0).
  void motion(const double* v) {
    auto& c =
        j_.csv(motion_file_, "time (s),duration (s),accel_x (mm/s^2),accel_y (mm/s^2),jerk_x (mm/s^3),jerk_y (mm/s^3)");
    c.row(csv_row({{v[0], 9}, {v[1], 9}, {v[2], 4}, {v[3], 4}, {v[4], 1}, {v[5], 1}}));
  }
  /// One sample of the hot end: time, temperature, target, heater duty, fan duty, feed.
  void thermal(const double* v) {
    auto& c =
        j_.csv(kThermalFile, "time (s),temperature (degC),target (degC),heater_duty (1),fan_duty (1),feed (mm/s)");
    c.row(csv_row({{v[0], 3}, {v[1], 2}, {v[2], 1}, {v[3], 4}, {v[4], 4}, {v[5], 4}}));
    ++thermal_;
  }
  /// What the protocol commands of the hot end that Marlin's temperature reports do not state:
  /// from `from_s` (s after the record starts) on, the fan's duty (0..1) and the feed (mm/s).
  struct ThermalInput {
    double from_s = 0, fan_duty = 0, feed_mm_s = 0;
  };
  void set_thermal_inputs(std::vector<ThermalInput> inputs) { thermal_inputs_ = std::move(inputs); }
  /// From now on Marlin's temperature reports (" T:210.00 /210.00 ... @:64 ...") are heater
  /// samples, each at `clock()` (s after the record started), with the fan and feed the protocol
  /// commands then; until stop_reports().
  void start_reports(std::function<double()> clock) { report_clock_ = std::move(clock); }
  void stop_reports() { report_clock_ = nullptr; }
  /// A Marlin temperature report while reports are read, as a heater sample; true if it was one.
  bool marlin_report(std::string_view l);
  /// Handles a tunekit-sim data line, or a Marlin report while they are read; true if it was one.
  bool line(std::string_view l) {
    if (report_clock_ && marlin_report(l)) return true;
    double v[6];
    if (l.rfind("echo:TKH ", 0) == 0) {
      if (parse_numbers(l.substr(9), v, 6) == 6) thermal(v);
      return true;
    }
    if (l.rfind("echo:TKM ", 0) == 0) {
      if (parse_numbers(l.substr(9), v, 6) == 6) motion(v);
      return true;
    }
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
  static constexpr const char* kThermalFile = "thermal.csv";
  long thermal_samples() const { return thermal_; }
  long load_samples() const { return load_; }
  long accel_samples() const { return accel_; }
  const std::string& load_file() const { return load_file_; }
  const std::string& accel_file() const { return accel_file_; }
  const std::string& commanded_file() const { return cmd_file_; }
  const std::string& motion_file() const { return motion_file_; }

 private:
  /// One CSV row, each value with its decimals; the buffer is reused from row to row.
  std::string_view csv_row(std::initializer_list<core::FixedField> fields) {
    row_.clear();
    core::append_fixed_fields(row_, ',', fields);
    return row_;
  }

  machine::Journal& j_;
  std::string row_;
  std::string load_file_, accel_file_, cmd_file_, motion_file_;
  long load_ = 0, accel_ = 0, thermal_ = 0;
  std::vector<ThermalInput> thermal_inputs_;
  std::function<double()> report_clock_;
};

class Session {
 public:
  virtual ~Session() = default;
  virtual firmware::FirmwareInfo identify() = 0;
  virtual void send(const std::string& line) = 0;
  /// Sends a run of protocol lines (no recording directive among them), in order. By default one
  /// by one, stopping before the next line once `abort` is set.
  virtual void send_lines(const std::vector<std::string>& lines, const std::atomic<bool>& abort) {
    for (const auto& l : lines) {
      if (abort.load()) throw MachineError("interrupted");
      send(l);
    }
  }
  /// `window_s`: how long the recording is expected to last (RepRapFirmware's M956 takes a
  /// sample count, not a stop command).
  virtual void record(const std::string& sensor, bool on, double window_s) = 0;
  /// Whether this link can record `sensor` (checked before anything is sent: no heating or
  /// homing for a protocol whose data cannot be recorded).
  virtual bool can_record(const std::string& sensor) const = 0;
  /// Checks, still before anything but the identification is sent, what recording `sensor`
  /// will need from the machine (RepRapFirmware: logging in to its web server).
  virtual void check_recording(const std::string& /*sensor*/) {}
  virtual void finish() = 0;
  virtual void safe_state(const std::vector<std::string>& commands) = 0;
  virtual nlohmann::json stats() const = 0;
  /// The profile with the stricter of its own and the firmware's reported limits, and the
  /// firmware's settings in force as what a test restores; each change is noted.
  virtual machine::MachineProfile with_firmware_limits(const machine::MachineProfile& p,
                                                       std::vector<std::string>& /*notes*/) const {
    return p;
  }
  firmware::Dialect dialect;
  firmware::FirmwareInfo firmware;
};

std::unique_ptr<Session> make_gcode_session(std::unique_ptr<machine::Transport> t, machine::Journal& j, Recorder& rec,
                                            const machine::LinkOptions& lo, const std::atomic<bool>* abort,
                                            SendGuard& guard, std::string http,
                                            std::optional<std::string> http_password);
std::unique_ptr<Session> make_klipper_session(std::unique_ptr<machine::Transport> t, machine::Journal& j, Recorder& rec,
                                              const machine::LinkOptions& lo, const machine::Sensors& sensors,
                                              SendGuard& guard);

}  // namespace tunekit::protocols::detail
