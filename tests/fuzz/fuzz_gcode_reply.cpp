// What a firmware answers, parsed by the G-code link: the bytes arrive as the firmware's reply
// to one numbered line (then the connection closes), and each reply line also goes through
// M115 identification, line splitting (N/checksum) and the G-code word parser and send guard.
#include <chrono>
#include <sstream>
#include <vector>

#include "fuzz_common.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/machine/gcode_link.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/machine/transport.hpp"
#include "tunekit/sim/builtin_profile.hpp"

using namespace tunekit::protocols;
using namespace tunekit::machine;
using namespace tunekit::firmware;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 16384) return -1;
  const std::string text(tunekit::fuzz::as_text(data, size));
  std::vector<std::string> lines;
  {
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
  }
  tunekit::fuzz::expect_result_or_error([&] { parse_m115(lines); });
  static const MachineProfile profile = tunekit::sim::builtin_sim_profile();
  SendGuard guard(profile);
  for (const auto& l : lines) {
    split_numbered(l);
    if (const auto w = parse_gcode(l)) {
      GcodeInterpreter in;
      in.apply(*w);
    }
    non_finite_word(l);
    guard.refuse(l);
  }
  tunekit::fuzz::expect_result_or_error([&] { check_protocol(lines, profile, {}); });
  // The link: the firmware's side writes the bytes and hangs up.
  auto pair = make_transport_pair();
  tunekit::fuzz::expect_result_or_error([&] {
    pair.second->write(text);
    pair.second->close();
  });
  GcodeLink link(*pair.first, nullptr, {std::chrono::milliseconds(20), 0, true});
  link.on_line = [](std::string_view l) { return l.rfind("echo:TK", 0) == 0; };
  tunekit::fuzz::expect_result_or_error([&] {
    for (int i = 0; i < 4; ++i) link.send("G1 X10 F600");
  });
  return 0;
}
