#pragma once
// Firmware dialects: which firmware a machine runs (from its M115 report) and the commands
// each one uses for what the protocols need (acceleration limit, relative extrusion, wait for
// moves, heaters off, stop motion, sensor streaming).
//
// M115 reports recognized (first line that names the firmware):
//   Marlin:          FIRMWARE_NAME:Marlin 2.1.2.1 (...) SOURCE_CODE_URL:... PROTOCOL_VERSION:1.0 ...
//   Prusa:           FIRMWARE_NAME:Prusa-Firmware 3.13.2 ... / FIRMWARE_NAME:Prusa-Firmware-Buddy 5.1.0 ...
//   Klipper:         FIRMWARE_NAME:Klipper FIRMWARE_VERSION:v0.12.0-...
//   RepRapFirmware:  FIRMWARE_NAME: RepRapFirmware for Duet 3 MB6HC FIRMWARE_VERSION: 3.5.1 ...
// Capability lines "Cap:NAME:0|1" (Marlin) are collected; tunekit-sim reports
// "Cap:TUNEKIT_SENSOR_STREAM:1" for its sensor streaming command M4100 (docs/machine.md).

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "tunekit/firmware/marlin_m493.hpp"

namespace tunekit::firmware {

enum class Firmware { unknown, marlin, prusa, klipper, reprapfirmware };

std::string to_string(Firmware f);
/// "marlin", "prusa", "klipper", "rrf"/"reprapfirmware" (case-insensitive); unknown otherwise.
Firmware firmware_from_name(const std::string& name);

struct FirmwareInfo {
  Firmware firmware = Firmware::unknown;
  std::string name;                          ///< FIRMWARE_NAME as reported
  std::string version;                       ///< best-effort version string
  std::map<std::string, bool> capabilities;  ///< Cap: lines
  bool sensor_stream() const;                ///< tunekit's M4100 streaming available
  /// Marlin built with FT_MOTION (it answered M493), and whether fixed-time motion is active
  /// (then the classic shaper and smooth linear advance are bypassed: stepper.cpp isr()).
  /// Marlin's M115 has no FT_MOTION capability line (Marlin/src/gcode/host/M115.cpp): both come
  /// from the M493 report (parse_m493_report).
  bool ft_motion = false;
  bool ft_motion_active = false;
  FtMotionReport m493;  ///< the M493 report itself (marlin_m493.hpp), when Marlin answered one
};

/// A value as a Klipper extended G-code parameter carries it (`NAME=<value>`). Klipper splits the
/// parameters like a POSIX shell (klippy/gcode.py _get_extended_params: shlex, whitespace_split,
/// '#' and ';' start a comment), then each at its first '='; so a value with whitespace, a quote,
/// a backslash, '#' or ';' is double-quoted ('"' and '\' escaped) and any other, such as
/// "mzv(n=4,t=0.9)", is written as it is. A value with a control character (a line break would
/// end the line and start another command) is refused: InputError.
std::string klipper_param_value(const std::string& value);

/// Parses the lines a machine printed in answer to M115 (any order, other lines ignored).
FirmwareInfo parse_m115(const std::vector<std::string>& lines);

class Dialect {
 public:
  explicit Dialect(Firmware f = Firmware::marlin) : fw_(f) {}
  Firmware firmware() const { return fw_; }
  std::string set_accel(double accel_mm_s2) const;  ///< print/travel acceleration
  std::string wait_for_moves() const { return "M400"; }
  std::string set_hotend(double temp_c, bool wait) const;
  /// Commands that bring the machine to a safe state after an abort: stop motion, then
  /// heaters off if `heaters_off`.
  std::vector<std::string> safe_state(bool heaters_off) const;
  /// Commands that turn the hot end and the bed off (the end of a run that heated them, and
  /// the second half of safe_state).
  std::vector<std::string> heaters_off() const;
  /// G-code that starts/stops a sensor stream (tunekit-sim's M4100); empty when the firmware
  /// streams through another channel (Klipper's API server).
  std::string sensor_stream(const std::string& sensor, bool on) const;
  /// Marlin's FT_MOTION as its M493 report said (marlin_m493.hpp): the M493 letters that turn
  /// its shapers off for a test and set them back depend on the form of that report.
  const FtMotionReport& ft_motion() const { return ft_; }
  void set_ft_motion(FtMotionReport r) { ft_ = std::move(r); }

 private:
  Firmware fw_;
  FtMotionReport ft_;
};

}  // namespace tunekit::firmware
