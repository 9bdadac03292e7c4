// Machine profiles (TOML) on arbitrary text.
#include "fuzz_common.hpp"
#include "tunekit/machine/machine_profile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 65536) return -1;
  const std::string text(tunekit::fuzz::as_text(data, size));
  tunekit::fuzz::expect_result_or_error([&] { tunekit::machine::parse_machine_profile(text, "fuzz.toml"); });
  return 0;
}
