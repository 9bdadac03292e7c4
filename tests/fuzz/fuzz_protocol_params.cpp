// Protocol parameter validation as a property: any protocol, any parameters (raw double bit
// patterns, so every NaN, infinity, denormal and extreme is reachable) either are refused with
// an InputError, or give G-code that the gate accepts and whose every word is a finite number.
#include <cstdlib>
#include <cstring>
#include <map>

#include "fuzz_common.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/sim/builtin_profile.hpp"

using namespace tunekit::protocols;
using namespace tunekit::firmware;
using tunekit::machine::MachineProfile;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return -1;
  static const MachineProfile profile = tunekit::sim::builtin_sim_profile();
  const auto& specs = protocol_specs();
  const auto& spec = specs[data[0] % specs.size()];
  const Firmware fw = data[1] % 3 == 0   ? Firmware::marlin
                      : data[1] % 3 == 1 ? Firmware::klipper
                                         : Firmware::reprapfirmware;
  const std::string axis = data[1] & 0x80 ? "y" : "x";
  std::map<std::string, double> params;
  for (std::size_t i = 2; i + 9 <= size; i += 9) {
    double v;
    std::memcpy(&v, data + i + 1, sizeof v);
    params[spec.params[data[i] % spec.params.size()].name] = v;
  }
  // Small limits keep one execution to a few hundred lines (the default limits let a protocol
  // generate up to a million lines: about 23 inputs a second under the sanitizers). The gate
  // and the refusal before generation are the same code at any limit. The defaults of
  // liquefier-step, liquefier-flow-sweep, line-steps and axis-rectangle fit; the longer
  // protocols are refused before generation unless the fuzzer shortens them through their
  // parameters, as the seeds short-* do.
  ProtocolLimits limits;
  limits.max_lines = 300;
  limits.max_bytes = 128 * 1024;
  Experiment e;
  try {
    e = build_experiment(spec.name, params, axis, profile, Dialect(fw), limits);
    require_within_limits(e.gcode, profile, e.sensors, limits);
  } catch (const tunekit::InputError&) {
    return 0;
  }
  for (const auto& l : e.gcode)
    if (non_finite_word(l)) std::abort();  // the gate passed a non-finite number
  SendGuard guard(profile);
  for (const auto& l : e.gcode)
    if (l.rfind(";@", 0) != 0 && guard.refuse(l)) std::abort();  // the gate and the link disagree
  return 0;
}
