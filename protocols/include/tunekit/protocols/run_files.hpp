#pragma once
// The files of a run directory by what they hold: RunResult::files (runner.hpp), run.json's
// "files" and the results of `tunekit run`.

#include <map>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace tunekit::protocols {

/// What a file of a run holds. In the order of the names to_string() gives, so that RunFiles
/// lists them as run.json does.
enum class RunFile {
  accel,             ///< the accelerometer's samples: raw_data_<axis>_<tag>.csv
  commanded_accel,   ///< the commanded acceleration at those samples: commanded_accel_<axis>_<tag>.csv
  commanded_motion,  ///< the commanded motion, piece by piece: commanded_motion_<axis>_<tag>.csv
  feed_track,        ///< the commanded feed as the firmware plans it: feed_track.csv
  gcode,             ///< the protocol's G-code with its recording directives: protocol.gcode
  journal,           ///< every line sent and received, and every event: journal.jsonl
  load_cell,         ///< the load cell's samples: step.csv or feed_force.csv
  sim_received,      ///< what the simulated printer received: sim_received.gcode
  summary,           ///< the run's summary: run.json
  thermal,           ///< the hot end's samples (temperature, duties, feed, target): thermal.csv
  truth,             ///< the simulated printer's truth: truth.json
};

/// The file's key in run.json's "files": "load_cell", "commanded_accel", ...
std::string_view to_string(RunFile file);

/// A run's files: what each holds -> its path.
using RunFiles = std::map<RunFile, std::string>;

/// As run.json's "files": {"load_cell": PATH, ...}.
nlohmann::json to_json(const RunFiles& files);

}  // namespace tunekit::protocols
