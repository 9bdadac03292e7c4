// Machine profiles (TOML) on arbitrary text.
#include "fuzz_common.hpp"
#include "tunekit/machine/machine_profile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Long inputs reach the deep nesting that only long texts have (a dotted table header of
  // 40,000 levels is 80 KB): scripts/fuzz runs this harness with -max_len=262144.
  if (size > 1024 * 1024) return -1;
  const std::string text(tunekit::fuzz::as_text(data, size));
  tunekit::fuzz::expect_result_or_error([&] { tunekit::machine::parse_machine_profile(text, "fuzz.toml"); });
  return 0;
}
