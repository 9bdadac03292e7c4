// The simulator's fault injection: what each SimFault kind does to the line it is planned for
// (drop it, corrupt it, answer late, hang up, or halt as a thermal runaway does).
#include <string>

#include <fmt/format.h>

#include "sim_constants.hpp"
#include "tunekit/sim/simulator.hpp"

namespace tunekit::sim {

std::string SimFault::describe() const {
  switch (kind) {
    case Kind::drop: return fmt::format("drop@{}", at_line);
    case Kind::garble: return fmt::format("garble@{}", at_line);
    case Kind::late_ok: return fmt::format("late-ok@{}:{:g}", at_line, delay_ms);
    case Kind::disconnect: return fmt::format("disconnect@{}", at_line);
    case Kind::error: return fmt::format("error@{}", at_line);
  }
  return "?";
}

std::optional<bool> Simulator::inject_faults(std::string& line, double& late_ms, const Emit& emit) {
  for (const auto& f : cfg_.faults) {
    if (f.at_line != received_count_) continue;
    switch (f.kind) {
      case SimFault::Kind::drop: return true;  // as if the line never arrived
      case SimFault::Kind::disconnect: out_flush(emit); return false;
      case SimFault::Kind::garble: {
        // Corrupt a character of the command (not the checksum): the checksum no longer matches.
        const auto star = line.rfind('*');
        const std::size_t at = star != std::string::npos && star > 1 ? star - 1 : line.size() - 1;
        line[at] = static_cast<char>(line[at] ^ sim::kGarbleBit);
        break;
      }
      case SimFault::Kind::late_ok: late_ms = f.delay_ms; break;
      case SimFault::Kind::error:
        out_flush(emit);
        emit("Error:Thermal Runaway, system stopped! Heater_ID: 0\nError:Printer halted. kill() called!\n");
        sync_heater();
        heater_.off();  // kill() turns the heaters off
        halted_ = true;
        return true;
    }
  }
  return std::nullopt;
}

}  // namespace tunekit::sim
