#include "tunekit/firmware/firmware_limits.hpp"

#include <iterator>

namespace tunekit::firmware::limits {

std::vector<FirmwareShaper> shapers_of(ExportFirmware fw, bool ft_motion) {
  switch (fw) {
    case ExportFirmware::klipper:
    case ExportFirmware::kalico: return {std::begin(kKlipperShapers), std::end(kKlipperShapers)};
    case ExportFirmware::marlin:
      if (ft_motion) return {std::begin(kMarlinFtMotionShapers), std::end(kMarlinFtMotionShapers)};
      return {std::begin(kMarlinClassicShapers), std::end(kMarlinClassicShapers)};
    case ExportFirmware::rrf: return {std::begin(kRrfShapers), std::end(kRrfShapers)};
  }
  return {};
}

std::optional<FirmwareShaper> find_shaper(ExportFirmware fw, const std::string& type, bool ft_motion) {
  for (const auto& s : shapers_of(fw, ft_motion))
    if (type == s.tunekit_name && !type.empty()) return s;
  return std::nullopt;
}

std::string shaper_list(ExportFirmware fw, bool ft_motion) {
  std::string out;
  for (const auto& s : shapers_of(fw, ft_motion)) out += (out.empty() ? "" : ", ") + std::string(s.firmware_name);
  return out;
}

std::string firmware_title(ExportFirmware fw) {
  switch (fw) {
    case ExportFirmware::klipper: return "Klipper";
    case ExportFirmware::kalico: return "Kalico";
    case ExportFirmware::marlin: return "Marlin";
    case ExportFirmware::rrf: return "RepRapFirmware";
  }
  return "?";
}

}  // namespace tunekit::firmware::limits
