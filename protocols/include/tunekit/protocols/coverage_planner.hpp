#pragma once
// Grid-based coverage path planning for tunekit's test prints, after Li and Yao, "Coverage Path
// Planning Application on FDM 3D Printer", USC, 2018 (Path Cost Evaluation): the layer is divided
// into square cells one line width wide; the cells to print are those of the test patterns (pads
// for photos, line steps, rings). Every cell's cost is the number of its eight neighbours that
// are covered or not to be printed; from the start cell the nozzle moves to the uncovered
// neighbour of highest cost (4-neighbours first on ties), and only when no neighbour is left
// (a "singularity") does it travel, with a retraction, to the nearest uncovered cell. The
// baseline is the plain zigzag (raster) of the same cells: every row left to right, travelling
// with a retraction over every gap.
//
// Lengths in mm, speeds in mm/s, accelerations in mm/s^2, times in s.

#include <string>
#include <vector>

#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::protocols {

struct TestPatternSet {
  int pads = 4;  ///< filled squares for photos
  double pad_mm = 20;
  int line_steps = 5;  ///< single-width lines of rising length (line_mm * (k+1) / line_steps)
  double line_mm = 30;
  int rings = 2;  ///< two-cell-wide rings
  double ring_radius_mm = 12;
  double spacing_mm = 5;  ///< gap between patterns
};

struct PlannedMove {
  double x0, y0, x1, y1;  ///< mm
  bool extrude = false;   ///< false: travel (preceded by a retraction)
};

struct CoverageStats {
  double print_mm = 0, travel_mm = 0;
  int retractions = 0;
  double time_s = 0;  ///< each move from rest to rest (trapezoid), plus the retractions
};

struct CoveragePlan {
  std::string planner;  ///< "pce" or "zigzag"
  double cell_mm = 0;
  std::vector<PlannedMove> moves;
  CoverageStats stats;
};

struct CoverageMotion {
  double print_speed_mm_s = 40, travel_speed_mm_s = 150, accel_mm_s2 = 1500;
  double retract_mm = 0.8, retract_speed_mm_s = 40;
};

/// Cells of the standard pattern set laid out in rows centred on the bed of `profile`
/// (InputError if they do not fit within the x/y travel less a 5 mm margin).
/// Returns the plan with `planner` = "pce" or "zigzag".
CoveragePlan plan_test_patterns(const TestPatternSet& set, const machine::MachineProfile& profile,
                                const std::string& planner, const CoverageMotion& motion);

}  // namespace tunekit::protocols
