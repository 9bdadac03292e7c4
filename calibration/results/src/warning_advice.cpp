#include "tunekit/calibration/results/warning_advice.hpp"

#include <array>
#include <string_view>
#include <utility>

namespace tunekit::calibration {

std::string advice_for_warning(const std::string& w) {
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 14> table{{
      {"do NOT agree",
       "repeat both experiments; if they still disagree, the liquefier is not first-order at this feed: compare the "
       "step and Bode plots and check the load cell's mounting"},
      {"differs from 1",
       "calibrate the extrusion multiplier (flow rate) in the slicer or firmware; the advance K is not affected"},
      {"smoothing time not designed",
       "add [print] max_accel_mm_s2 and [extruder] max_accel_mm_s2 to the machine profile and run again"},
      {"some sections are not in this file",
       "make sure the included files do not set these options again after this file, or pass the file that holds "
       "them with --config"},
      {"outside the identified range",
       "step-test at feed rates that cover the design flow, or give a design flow inside the identified range"},
      {"were left out", "check the step results: every operating point needs a feed rate and a time constant"},
      {"rheology prediction ignored",
       "give a measured time constant (the results of 'tunekit step' or 'tunekit freq') with the rheology prediction"},
      {"no --profile", "pass the machine profile with --profile so the limits and line geometry are the machine's"},
      {"tf fit:",
       "look at the Bode plot and its coherence; excite longer, with a larger amplitude, or around the corner"},
      {"whole-record model not fitted",
       "the per-step and per-frequency results stand; for the model, record the commanded flow or feed (never below "
       "zero) as the input column"},
      {"output-error fit:", "look at the residuals of the record; excite longer or with a larger amplitude"},
      {"Z shaper is not exported",
       "set the Z shaper by hand in the firmware, if it has one: tunekit writes a Z shaper into Klipper's printer.cfg "
       "only"},
      {"shaper is not exported", "name the record's axis with --axis, or set that axis's shaper by hand"},
      {"coherence", "excite longer or with a larger amplitude so that more frequencies pass the coherence threshold"},
  }};
  for (const auto& [key, advice] : table)
    if (w.find(key) != std::string::npos) return std::string(advice);
  return "check the file or setting the warning names, then run the command again (its --help lists the options)";
}

}  // namespace tunekit::calibration
