// Delta calibration export: see delta_export.hpp.
#include "tunekit/firmware/delta_export.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::firmware {
namespace {

void delta_check_finite(const ident::DeltaGeometry& g) {
  bool ok = std::isfinite(g.radius_mm) && g.radius_mm > 0 && std::isfinite(g.homed_height_mm) &&
            std::isfinite(g.tilt_x) && std::isfinite(g.tilt_y);
  for (std::size_t i = 0; i < 3; ++i)
    ok = ok && std::isfinite(g.rod_mm[i]) && g.rod_mm[i] > g.radius_mm && std::isfinite(g.angle_deg[i]) &&
         std::isfinite(g.endstop_mm[i]);
  if (!ok) throw InputError("delta geometry is not finite or has a rod no longer than the radius; nothing exported");
}

void delta_check_no_tilt(const ident::DeltaGeometry& g, const char* firmware) {
  if (g.tilt_x != 0 || g.tilt_y != 0)
    throw InputError(fmt::format("{} has no delta bed tilt parameter: fit 3, 4, 6 or 7 factors for it", firmware));
}

}  // namespace

std::string delta_klipper_save_config(const ident::DeltaGeometry& g) {
  delta_check_finite(g);
  delta_check_no_tilt(g, "Klipper");
  // Klipper's configfile writes the sections with Python's configparser and prefixes every
  // line with "#*# " (stripped), below its SAVE_CONFIG header.
  std::string s =
      "#*# <---------------------- SAVE_CONFIG ---------------------->\n"
      "#*# DO NOT EDIT THIS BLOCK OR BELOW. The contents are auto-generated.\n"
      "#*#\n";
  s += fmt::format("#*# [printer]\n#*# delta_radius = {:.6f}\n", g.radius_mm);
  for (std::size_t i = 0; i < 3; ++i) {
    s += fmt::format("#*#\n#*# [stepper_{}]\n", static_cast<char>('a' + i));
    s += fmt::format("#*# angle = {:.6f}\n", g.angle_deg[i]);
    s += fmt::format("#*# arm_length = {:.6f}\n", g.rod_mm[i]);
    s += fmt::format("#*# position_endstop = {:.6f}\n", g.homed_height_mm + g.endstop_mm[i]);
  }
  return s;
}

std::string delta_marlin_gcode(const ident::DeltaGeometry& g, double probe_z_offset_mm) {
  delta_check_finite(g);
  delta_check_no_tilt(g, "Marlin");
  if (!std::isfinite(probe_z_offset_mm)) throw InputError("Marlin probe z offset is not finite");
  if (g.rod_mm[0] != g.rod_mm[1] || g.rod_mm[1] != g.rod_mm[2])
    throw InputError("Marlin's M665 L holds one diagonal rod length; the three rods differ");
  // Marlin moves a carriage down by -adj after it homes and then takes it to be at the top:
  // a larger adjustment raises that carriage, the opposite of an endstop adjustment e here.
  // adj_i = min(e) - e_i (all <= 0, as M666 requires) with delta height H + min(e); with a bed
  // probe Marlin homes the nozzle at delta_height - probe z offset (M851 Z), so that is added.
  const double emin = std::min({g.endstop_mm[0], g.endstop_mm[1], g.endstop_mm[2]});
  std::string s = "; delta calibration (tunekit delta)\n";
  s += fmt::format("M665 H{:.3f} L{:.3f} R{:.3f} X{:.3f} Y{:.3f} Z{:.3f}\n",
                   g.homed_height_mm + emin + probe_z_offset_mm, g.rod_mm[0], g.radius_mm,
                   g.angle_deg[0] - ident::kDeltaNominalAngles[0], g.angle_deg[1] - ident::kDeltaNominalAngles[1],
                   g.angle_deg[2] - ident::kDeltaNominalAngles[2]);
  s += fmt::format("M666 X{:.3f} Y{:.3f} Z{:.3f}\n", emin - g.endstop_mm[0], emin - g.endstop_mm[1],
                   emin - g.endstop_mm[2]);
  s += "M500\n";
  return s;
}

std::string delta_rrf_gcode(const ident::DeltaGeometry& g, double print_radius_mm) {
  delta_check_finite(g);
  if (!(std::isfinite(print_radius_mm) && print_radius_mm > 0))
    throw InputError("RepRapFirmware's M665 B needs the print radius (mm, > 0)");
  const double emean = (g.endstop_mm[0] + g.endstop_mm[1] + g.endstop_mm[2]) / 3.0;
  // The lines RepRapFirmware's LinearDeltaKinematics::WriteCalibrationParameters writes.
  std::string s = "; Delta parameters\n";
  s += fmt::format("M665 L{:.3f}:{:.3f}:{:.3f} R{:.3f} H{:.3f} B{:.1f} X{:.3f} Y{:.3f} Z{:.3f}\n", g.rod_mm[0],
                   g.rod_mm[1], g.rod_mm[2], g.radius_mm, g.homed_height_mm + emean, print_radius_mm,
                   g.angle_deg[0] - ident::kDeltaNominalAngles[0], g.angle_deg[1] - ident::kDeltaNominalAngles[1],
                   g.angle_deg[2] - ident::kDeltaNominalAngles[2]);
  s += fmt::format("M666 X{:.3f} Y{:.3f} Z{:.3f} A{:.2f} B{:.2f}\n", g.endstop_mm[0] - emean, g.endstop_mm[1] - emean,
                   g.endstop_mm[2] - emean, g.tilt_x * 100.0, g.tilt_y * 100.0);
  return s;
}

}  // namespace tunekit::firmware
