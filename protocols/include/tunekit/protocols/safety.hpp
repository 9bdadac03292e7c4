#pragma once
// The one gate between a protocol and a machine. check_protocol() interprets the protocol's
// G-code before anything is sent: every number finite, travel limits, per-axis speed and
// acceleration, extruder feed speed, volumetric flow and acceleration, temperatures, the
// sensors the protocol needs, and the protocol's size (lines, bytes) and machine time against
// configurable caps. Every violation is listed, not just the first. SendGuard is the last check
// in the link, line by line, whatever produced the line.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tunekit/machine/gcode.hpp"
#include "tunekit/machine/gcode_link.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::protocols {

/// Caps on what one protocol may ask of a machine, checked before the first byte is sent
/// (build_experiment refuses a protocol whose plan exceeds them before generating it, and the
/// gate checks the generated G-code again). Configurable with `tunekit run --max-duration`
/// and `--max-lines`.
struct ProtocolLimits {
  /// Machine time of the whole protocol, s. Two hours: the longest experiment tunekit defines
  /// takes minutes; a run of hours is a typing error, not an experiment.
  double max_duration_s = 7200;
  /// G-code lines. One million lines is ~25 MB of G-code and ~1 h over a 250 kbit/s link.
  std::size_t max_lines = 1'000'000;
  /// Bytes of G-code held in memory and written to protocol.gcode.
  std::size_t max_bytes = std::size_t{64} << 20;
};

struct Violation {
  std::size_t line = 0;  ///< 1-based line in the protocol's G-code (0: not tied to a line)
  std::string gcode;     ///< the offending line
  std::string what;      ///< e.g. "x speed 400 mm/s exceeds max_velocity_mm_s 300"
};

/// The first G-code word of `line` whose value is not a finite number ("Yinf", "F-nan",
/// "S1e999", "ACCEL=inf"), or nullopt. Comments, N<line> and *<checksum> are ignored, and
/// so are the free-text commands (M117, M118, RESPOND).
std::optional<std::string> non_finite_word(std::string_view line);

/// Machine time of `gcode`, s: every move as a jerk-limited profile plus every dwell.
double estimate_gcode_duration_s(const std::vector<std::string>& gcode);

/// Interprets `gcode` from the machine's home position (axis minimums) and returns all
/// violations of `profile`'s limits and of `limits`; `sensors` lists sensors the protocol
/// needs ("accelerometer", "load_cell", "filament_encoder", "camera").
std::vector<Violation> check_protocol(const std::vector<std::string>& gcode, const machine::MachineProfile& profile,
                                      const std::vector<std::string>& sensors, const ProtocolLimits& limits = {});

/// Throws InputError (exit code 2) naming every violation when there is any.
void require_within_limits(const std::vector<std::string>& gcode, const machine::MachineProfile& profile,
                           const std::vector<std::string>& sensors, const ProtocolLimits& limits = {});

/// The final check of each line a link writes to a machine: refuses a line holding a
/// non-finite number, a move to a position outside the profile's travel, a non-positive feed
/// rate, or a temperature above the profile's maximum. It follows the position the accepted
/// lines set up (G28 homes to the axis minimums); a refused line changes nothing.
class SendGuard : public machine::LineGuard {
 public:
  explicit SendGuard(const machine::MachineProfile& profile);
  /// Why `line` must not be sent, or nullopt when it may be (its effect is then recorded).
  std::optional<std::string> refuse(std::string_view line) override;

 private:
  machine::MachineProfile profile_;
  machine::GcodeInterpreter state_;
};

}  // namespace tunekit::protocols
