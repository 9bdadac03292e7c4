// The klipper configuration parser and editor behind `tunekit export` on arbitrary text.
#include "fuzz_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return tunekit::fuzz::fuzz_config(tunekit::firmware::ExportFirmware::klipper, data, size);
}
