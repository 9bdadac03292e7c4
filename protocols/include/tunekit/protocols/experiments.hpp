#pragma once
// Experiment protocols as G-code: what `tunekit run` sends. Each protocol has named parameters
// with units and defaults (listed by `tunekit run --help`), produces G-code for a dialect, and
// names the sensors it records. Lines of the form ";@record <sensor> on|off" mark where sensor
// recording starts and stops; the runner turns them into the firmware's commands (or API calls).
// A line ";@epilogue" starts the lines that restore what the protocol changed for its test
// (acceleration limits, cruise ratio, input shaping); the runner sends them also after an abort.
//
// Protocols (parameter defaults in protocol_specs.cpp, documented in docs/machine.md):
//   liquefier-step      extrusion-rate steps low -> high -> low ..., load cell recorded
//   liquefier-flow-sweep feed steps up and down through flow levels up to the hot end's limit, each level
//                       reached from below and above (flow_sweep_plan.hpp), load cell recorded
//   liquefier-sine      sine-dwell list of the feed (log-spaced frequencies), load cell recorded
//   liquefier-chirp     linear chirp of the feed, load cell recorded
//   ring-print          Holtrup's (2019) ring: a circle printed with the feed modulated by A sin(N theta)
//   line-steps          camera path: straight lines whose flow steps low -> high -> low (camera_prints.hpp)
//   axis-sweep          resonance sweep: acceleration accel_per_hz * f, f rising at hz_per_sec; on Klipper
//                       with the slow +-sweeping_accel motion of period sweeping_period Klipper adds
//   axis-rectangle      Hemminger's (UCLA, 2022) overshoot rectangle: XY rectangle with pauses, repeated
//   test-pattern        pads, line steps and rings ordered by the coverage planner (coverage_planner.hpp)
//   heater-identify     the hot end's thermal experiment: heat-up, target steps, fan and extrusion steps, a
//                       held-out fan and extrusion step; the heater recorded (thermal_plan.hpp)

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/safety.hpp"

namespace tunekit::protocols {

/// What values a parameter accepts (checked before any G-code is generated). Every value must
/// also be finite; `max_value` is a plausibility cap that keeps the arithmetic of the protocol
/// (and its conversions to whole numbers) far from overflow. The machine's own limits are
/// checked afterwards on the G-code by the safety gate (safety.hpp).
enum class ParamDomain {
  positive,      ///< > 0
  non_negative,  ///< >= 0
  any,           ///< any finite value (positions; the gate checks them against the travel)
  count,         ///< a whole number >= 1
};

struct ProtocolParam {
  std::string name;  ///< with its unit: "feed_low_mm_s"
  double default_value = 0;
  std::string unit;  ///< "mm/s"
  std::string help;
  ParamDomain domain = ParamDomain::positive;
  double max_value = 1e6;  ///< |value| must not exceed this
};

/// The experiment protocols (protocol_specs() describes each).
enum class Protocol {
  liquefier_step,
  liquefier_flow_sweep,
  liquefier_sine,
  liquefier_chirp,
  ring_print,
  line_steps,
  axis_sweep,
  axis_rectangle,
  test_pattern,
  heater_identify,
};

struct ProtocolSpec {
  Protocol id;
  std::string name;  ///< what the command line and run.json call it: "liquefier-step"
  std::string description;
  std::vector<ProtocolParam> params;
  std::vector<std::string> sensors;  ///< needed sensors
  bool uses_axis = false;            ///< takes --axis x|y
};

const std::vector<ProtocolSpec>& protocol_specs();
const ProtocolSpec& protocol_spec(const std::string& name);  ///< InputError if unknown
const ProtocolSpec& protocol_spec(Protocol id);
/// The protocol's name: "liquefier-step", ...
const std::string& to_string(Protocol id);

struct Experiment {
  std::string protocol;
  std::string axis;                      ///< for axis protocols
  std::map<std::string, double> params;  ///< every parameter, defaults filled in
  std::vector<std::string> gcode;        ///< with ";@record" directives and comments
  std::vector<std::string> sensors;
  double estimated_duration_s = 0;  ///< machine time of the motion
  /// How the firmware's planner runs the excitation (per dialect): the acceleration in force,
  /// whether extrude-only moves stop, the test settings changed and restored, ...
  nlohmann::json excitation = nlohmann::json::object();
  nlohmann::json to_json() const;
};

/// Builds a protocol. `overrides` are "name" -> value; unknown names are an InputError.
/// Parameters that depend on the machine (e.g. the sweep's centre) default from the profile.
/// Every parameter is checked against its domain first (InputError naming it), then the
/// protocol's line count and machine time are computed from the parameters and compared with
/// `limits` before any G-code is generated, so no parameter can make it hang or exhaust memory.
Experiment build_experiment(const std::string& protocol, const std::map<std::string, double>& overrides,
                            const std::string& axis, const machine::MachineProfile& profile,
                            const firmware::Dialect& dialect, const ProtocolLimits& limits = {});

}  // namespace tunekit::protocols
