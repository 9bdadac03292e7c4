#pragma once
// Heater logs a firmware writes on its own, read into a table of one heater's samples:
//
// * Klipper's klippy.log "Stats" lines (Kevin O'Connor et al., Klipper, klippy/extras/
//   statistics.py and heaters.py), one a second:
//     Stats 2016.5: gcodein=0  mcu: ... heater_bed: target=60 temp=59.8 pwm=0.127 ... extruder: target=210 temp=209.8
//     pwm=0.512
//   the time is the host's monotonic clock in seconds; each heater prints
//   "<name>: target=%.0f temp=%.1f pwm=%.3f" (Heater.stats) -- and only while it is active
//   (a target set, or its last reading above 50 degC): a cold, idle heater is absent from the
//   line. The part-cooling fan's speed is not in Stats (Klipper's fans have no stats()), nor is
//   the extruder's feed: a record read from klippy.log has neither.
// * Marlin's temperature auto-report (M155 S<seconds>) and M105 replies,
//     T:210.0 /210.0 B:60.1 /60.0 @:64 B@:127
//   without a time stamp: consecutive lines are `interval_s` apart. `@:` is the hot end's
//   software-PWM amount, 0 to 127 (Marlin/src/module/temperature.cpp: soft_pwm_amount =
//   get_pid_output_hotend(e) >> 1, the 0-255 PID output halved); duty = @ / 127.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::formats {

/// One heater's samples as a log states them, in file order.
struct HeaterLog {
  std::string heater;            ///< "extruder", "T0", ...
  std::vector<double> t_s;       ///< sample time, s (klippy.log: the host's clock)
  std::vector<double> target_c;  ///< the target temperature, degC
  std::vector<double> temp_c;    ///< the measured temperature, degC
  std::vector<double> duty;      ///< heater PWM duty in [0, 1]
  /// Index of the first sample of each continuous run: a new run starts where the log's time goes
  /// back or jumps by more than `max_gap_s` (a restart of the host, the heater idle and absent).
  std::vector<std::size_t> run_starts;
  std::size_t lines_read = 0;     ///< Stats lines (or report lines) seen
  std::size_t lines_skipped = 0;  ///< of those, lines cut short or without this heater
};

/// The samples of one continuous run [begin, end).
struct HeaterRun {
  std::size_t begin = 0, end = 0;
};
std::vector<HeaterRun> heater_runs(const HeaterLog& log);

/// Reads `heater`'s samples from klippy.log text. A Stats line cut short (a truncated file, a
/// line without its heater's three values) is skipped and counted. InputError (exit 2) when the
/// text has no Stats line, or no line with this heater (naming the heaters that are there).
/// `max_gap_s`: a longer gap between samples starts a new run.
HeaterLog read_klippy_heater_log(std::string_view text, const std::string& heater = "extruder", double max_gap_s = 5.0);

/// Reads hot end `tool`'s samples ("T" for a single hot end, "T0", "T1" ...) from Marlin's
/// temperature reports, one report each `interval_s` seconds. InputError when no report line has
/// that hot end with its `@` power (M155 reports without it are of no use for a thermal fit).
HeaterLog read_marlin_temperature_reports(std::string_view text, double interval_s, const std::string& tool = "T");

}  // namespace tunekit::formats
