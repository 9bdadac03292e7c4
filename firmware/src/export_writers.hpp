#pragma once
// Internal: the per-firmware writers behind firmware_export.hpp. Each fills `r.updated`,
// `r.diff`, `r.changes`, `r.warnings` and `r.gcode` from `r.original`.

#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::firmware::detail {

inline constexpr int kDecimalsK = 4;
inline constexpr int kDecimalsSmooth = 4;
inline constexpr int kDecimalsFreq = 2;
inline constexpr int kDecimalsZeta = 3;

void write_klipper(ExportResult& r, const CompensatorSettings& s);
/// Kalico's bounds (firmware_limits.hpp) on a nonlinear advance setting; appends violations.
void validate_kalico(const KalicoAdvanceSetting& k, std::vector<std::string>& bad);
inline constexpr int kDecimalsKalico = 6;  // Kalico reports these with %.6f (extruder.py get_msg)
void write_marlin(ExportResult& r, const CompensatorSettings& s);
void write_rrf(ExportResult& r, const CompensatorSettings& s);

/// The shaper RepRapFirmware gets (it has one for all axes): the axis with the lower
/// frequency when X and Y differ (with a warning). Returns nullptr when none is set.
const ShaperSetting* rrf_single_shaper(const CompensatorSettings& s, std::vector<std::string>& warnings,
                                       std::string* axis = nullptr);

}  // namespace tunekit::firmware::detail
