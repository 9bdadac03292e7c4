#include "tunekit/protocols/run_files.hpp"

namespace tunekit::protocols {

std::string_view to_string(RunFile file) {
  switch (file) {
    case RunFile::accel: return "accel";
    case RunFile::commanded_accel: return "commanded_accel";
    case RunFile::commanded_motion: return "commanded_motion";
    case RunFile::feed_track: return "feed_track";
    case RunFile::gcode: return "gcode";
    case RunFile::journal: return "journal";
    case RunFile::load_cell: return "load_cell";
    case RunFile::sim_received: return "sim_received";
    case RunFile::summary: return "summary";
    case RunFile::thermal: return "thermal";
    case RunFile::truth: return "truth";
  }
  return "unknown";
}

nlohmann::json to_json(const RunFiles& files) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [file, path] : files) j[std::string(to_string(file))] = path;
  return j;
}

}  // namespace tunekit::protocols
