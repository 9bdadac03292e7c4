#pragma once
// Per-feature pressure advance in a sliced G-code file, for firmware that takes one advance
// number (Klipper SET_PRESSURE_ADVANCE ADVANCE=, Marlin M900 K, RepRapFirmware M572 D S).
//
// Features are the blocks the slicers mark with a `;TYPE:` comment (PrusaSlicer and OrcaSlicer
// ";TYPE:External perimeter", Cura ";TYPE:WALL-OUTER"). A block's flow is the extrusion-weighted
// mean over its printing moves (G0/G1 with E > 0 and an XY length) of
//     Q = (dE / dXY) * A_f * F / 60          (mm^3/s; E and XY in mm, F in mm/min)
// with E relative after M83 and absolute after M82 (G92 E resets it); G90/G91 set X/Y only, as in
// Klipper's gcode_move.py (Marlin's G90 also makes E absolute; slicers write M82/M83 after it).
// The advance for the block is the design's K(Q) (linear interpolation, held outside the
// table); it is written right after the block's `;TYPE:` line only when it differs from the
// active value by more than the hysteresis (relative), because every change costs a short
// stutter on Klipper (SET_PRESSURE_ADVANCE waits for the motion queue). Advance commands already
// in the file set the active value. Every original line is kept byte for byte; only whole lines
// are inserted, with the file's line ending.

#include <string>
#include <utility>
#include <vector>

#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::firmware {

struct GcodeAdvanceOptions {
  ExportFirmware firmware = ExportFirmware::klipper;  ///< kalico writes Klipper's command
  std::vector<std::pair<double, double>> k_of_flow;   ///< (flow mm^3/s, K s), >= 1 point
  double filament_area_mm2 = 0;                       ///< 0: from the file's "; filament_diameter = D" line
  double hysteresis = 0.10;                           ///< relative change of K needed to write a new value
  std::string klipper_extruder = "extruder";
  int rrf_drive = 0;
};

struct GcodeAdvanceChange {
  std::size_t line = 0;  ///< 1-based line of the original file the command follows
  std::string feature;
  double flow_mm3_s = 0;
  double k_s = 0;
};

struct GcodeAdvanceResult {
  std::string text;
  std::vector<GcodeAdvanceChange> changes;
  std::size_t features = 0;  ///< `;TYPE:` blocks with printing moves
  std::vector<std::string> warnings;
};

/// Whether `line` (without its ending) sets the advance for `fw`; `k_s` receives the value.
bool parse_advance_command(const std::string& line, ExportFirmware fw, double& k_s);

/// Inserts the per-feature advance. Throws InputError (path in the message) when the filament
/// diameter is unknown, the table holds a value outside the firmware's bounds, or no `;TYPE:`
/// feature is found.
GcodeAdvanceResult apply_gcode_advance(const std::string& text, const GcodeAdvanceOptions& o, const std::string& path);

}  // namespace tunekit::firmware
