#pragma once
// The simulated machine's answers to single lines, as the runner reads them: shared by the
// machine tests that talk to the simulator line by line (M115, M493 and the FT_MOTION tests).
#include <string>
#include <string_view>
#include <vector>

#include "tunekit/firmware/marlin_m493.hpp"
#include "tunekit/sim/simulator.hpp"

namespace tunekit::test {

/// `text` split at its newlines (a last line without one is dropped, as a partial answer).
inline std::vector<std::string> text_lines(const std::string& text) {
  std::vector<std::string> out;
  std::size_t b = 0;
  for (std::size_t e; (e = text.find('\n', b)) != std::string::npos; b = e + 1) out.push_back(text.substr(b, e - b));
  return out;
}

/// The lines the simulator answers to one G-code line.
inline std::vector<std::string> sim_answer_lines(sim::Simulator& sim, const std::string& line) {
  std::string out;
  sim.handle_line(line, [&](std::string_view s) { out += s; });
  return text_lines(out);
}

/// What the runner asks a Marlin: M493, and M493 V after a list-form report.
inline firmware::FtMotionReport ask_sim_m493(sim::Simulator& sim) {
  auto lines = sim_answer_lines(sim, "M493");
  if (firmware::parse_m493_report(lines).form == firmware::M493Form::axis_list) {
    const auto v = sim_answer_lines(sim, "M493 V");
    lines.insert(lines.end(), v.begin(), v.end());
  }
  return firmware::parse_m493_report(lines);
}

}  // namespace tunekit::test
