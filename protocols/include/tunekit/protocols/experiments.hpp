#pragma once
// Experiment protocols as G-code: what `tunekit run` sends. Each protocol has named parameters
// with units and defaults (listed by `tunekit run --help`), produces G-code for a dialect, and
// names the sensors it records. Lines of the form ";@record <sensor> on|off" mark where sensor
// recording starts and stops; the runner turns them into the firmware's commands (or API calls).
// A line ";@epilogue" starts the lines that restore what the protocol changed for its test
// (acceleration limits, cruise ratio, input shaping); the runner sends them also after an abort.
//
// Protocols (parameter defaults in experiments.cpp, documented in docs/machine.md):
//   liquefier-step      extrusion-rate steps low -> high -> low ..., load cell recorded
//   liquefier-sine      sine-dwell list of the feed (log-spaced frequencies), load cell recorded
//   liquefier-chirp     linear chirp of the feed, load cell recorded
//   ring-print          Holtrup's (2019) ring: a circle printed with the feed modulated by A sin(N theta)
//   line-steps          camera path: straight lines whose flow steps low -> high -> low (camera_prints.hpp)
//   axis-sweep          resonance sweep: acceleration accel_per_hz * f, f rising at hz_per_sec
//   axis-rectangle      Hemminger's (UCLA, 2022) overshoot rectangle: XY rectangle with pauses, repeated
//   test-pattern        pads, line steps and rings ordered by the coverage planner (coverage_planner.hpp)

#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/protocols/dialect.hpp"
#include "tunekit/protocols/machine_profile.hpp"

namespace tunekit::protocols {

struct ProtocolParam {
  std::string name;  ///< with its unit: "feed_low_mm_s"
  double default_value = 0;
  std::string unit;  ///< "mm/s"
  std::string help;
};

struct ProtocolSpec {
  std::string name;
  std::string description;
  std::vector<ProtocolParam> params;
  std::vector<std::string> sensors;  ///< needed sensors
  bool uses_axis = false;            ///< takes --axis x|y
};

const std::vector<ProtocolSpec>& protocol_specs();
const ProtocolSpec& protocol_spec(const std::string& name);  ///< InputError if unknown

struct Experiment {
  std::string protocol;
  std::string axis;                       ///< for axis protocols
  std::map<std::string, double> params;   ///< every parameter, defaults filled in
  std::vector<std::string> gcode;         ///< with ";@record" directives and comments
  std::vector<std::string> sensors;
  double estimated_duration_s = 0;        ///< machine time of the motion
  /// How the firmware's planner runs the excitation (per dialect): the acceleration in force,
  /// whether extrude-only moves stop, the test settings changed and restored, ...
  nlohmann::json excitation = nlohmann::json::object();
  nlohmann::json to_json() const;
};

/// Builds a protocol. `overrides` are "name" -> value; unknown names are an InputError.
/// Parameters that depend on the machine (e.g. the sweep's centre) default from the profile.
Experiment build_experiment(const std::string& protocol, const std::map<std::string, double>& overrides,
                            const std::string& axis, const MachineProfile& profile, const Dialect& dialect);

}  // namespace tunekit::protocols
