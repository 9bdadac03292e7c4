// A machine profile (TOML, arbitrary text) through the safety gate, as a property: a profile is
// either refused at load (tunekit::Error), or every limit it sets is finite, and each protocol
// built for it is refused (InputError) or gives G-code in which no line holds a line break or
// NUL (text from the profile, such as its name, never becomes a line of its own) and that the
// link's last check (SendGuard) accepts line by line.
#include <cmath>
#include <cstdlib>

#include "fuzz_common.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/safety.hpp"

using namespace tunekit::protocols;
using tunekit::machine::MachineProfile;

namespace {

bool limits_finite(const MachineProfile& p) {
  for (const auto& [name, a] : p.axes)
    if (!std::isfinite(a.min_mm) || !std::isfinite(a.max_mm) || !std::isfinite(a.max_velocity_mm_s) ||
        !std::isfinite(a.max_accel_mm_s2))
      return false;
  return std::isfinite(p.temperature.hotend_max_c) && std::isfinite(p.temperature.bed_max_c) &&
         std::isfinite(p.extruder.max_flow_mm3_s) && std::isfinite(p.extruder.max_velocity_mm_s);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1 || size > 64 * 1024) return -1;
  const std::string text(tunekit::fuzz::as_text(data + 1, size - 1));
  MachineProfile profile;
  try {
    profile = tunekit::machine::parse_machine_profile(text, "fuzz.toml");
  } catch (const tunekit::Error&) {
    return 0;
  }
  if (!limits_finite(profile)) std::abort();  // a non-finite limit passed the load
  const auto& specs = protocol_specs();
  const auto& spec = specs[data[0] % specs.size()];
  const tunekit::firmware::Firmware fw =
      data[0] & 0x80 ? tunekit::firmware::Firmware::klipper : tunekit::firmware::Firmware::marlin;
  ProtocolLimits limits;  // small: one execution stays a few hundred lines (fuzz_protocol_params.cpp)
  limits.max_lines = 300;
  limits.max_bytes = 128 * 1024;
  Experiment e;
  try {
    e = build_experiment(spec.name, {}, "x", profile, tunekit::firmware::Dialect(fw), limits);
    require_within_limits(e.gcode, profile, e.sensors, limits);
  } catch (const tunekit::Error&) {
    return 0;
  }
  for (const auto& l : e.gcode)
    for (char c : l)
      if (c == '\n' || c == '\r' || c == '\0') std::abort();  // a hidden line reached the G-code
  SendGuard guard(profile);
  for (const auto& l : e.gcode) {
    if (l.empty() || l[0] == ';') continue;
    if (guard.refuse(l.substr(0, l.find(';')))) std::abort();  // the gate and the link disagree
  }
  return 0;
}
