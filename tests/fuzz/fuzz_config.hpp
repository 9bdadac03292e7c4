#pragma once
// One harness per firmware: the configuration text is parsed and edited by export with a
// fixed set of settings.
#include <cstdlib>

#include "fuzz_common.hpp"
#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::fuzz {

inline int fuzz_config(firmware::ExportFirmware fw, const std::uint8_t* data, std::size_t size) {
  if (size > 65536) return -1;
  const std::string text(as_text(data, size));
  firmware::CompensatorSettings s;
  s.pa_k_s = 0.045;
  if (fw != firmware::ExportFirmware::rrf) s.pa_smooth_s = 0.04;
  s.shapers["x"] = {fw == firmware::ExportFirmware::marlin ? "zv" : "mzv", 45.2, 0.1};
  s.shapers["y"] = {fw == firmware::ExportFirmware::marlin ? "zv" : "mzv", 38.5, 0.1};
  expect_result_or_error([&] { firmware::export_config_text(fw, text, "fuzz.cfg", s); });
  return 0;
}

}  // namespace tunekit::fuzz
