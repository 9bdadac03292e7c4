#pragma once
// The printed line test of the camera path: straight lines printed at constant speed along +X
// whose extrusion steps low -> high -> low part-way (a step of the commanded flow in space, and
// so in time, t = s / v). Photographed from above, the width along each line is the
// liquefier's step response (Holtrup, Tuning liquefier dynamics, MSc thesis, University of
// Twente, 2019, ch. 4.3: line width as the liquefier's output). Parameters and defaults are
// listed by `tunekit run --help` (protocol line-steps).
//
// The path segments are vision's (the width-to-time mapping reads them): code that includes
// this header links tunekit_vision as well (protocols links it privately).

#include <map>
#include <string>
#include <vector>

#include "tunekit/vision/width_to_dynamics.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::protocols {

/// One printed line of the test: it starts at (x0_mm, y_mm) and runs along +X through `path`.
struct PrintedLine {
  double x0_mm = 0, y_mm = 0;
  std::vector<vision::PathSegment> path;  ///< in print order (speed, length, filament)
  double length_mm() const;
};

/// The lines the protocol prints (in print order), from its parameters (every key filled in,
/// see build_experiment) and the profile.
std::vector<PrintedLine> line_steps_layout(const std::map<std::string, double>& params,
                                           const machine::MachineProfile& profile);

/// Appends the protocol's G-code (after the header comment).
void append_line_steps_gcode(std::vector<std::string>& gcode, const std::map<std::string, double>& params,
                             const machine::MachineProfile& profile, const firmware::Dialect& dialect);

}  // namespace tunekit::protocols
